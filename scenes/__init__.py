"""Shipped inputs: AMASS-format motions (``scenes/motions``) and, later, garments and presets."""
from __future__ import annotations

from pathlib import Path

MOTIONS_DIR = Path(__file__).parent / "motions"


def shipped_motions() -> list[str]:
    """Names of the shipped motions (``walk``, ``run``, ...)."""
    return sorted(p.stem for p in MOTIONS_DIR.glob("*.npz"))


def resolve_motion(name_or_path: str) -> Path:
    """A motion path: the argument itself if it is a file, else the shipped motion of that name."""
    path = Path(name_or_path)
    if not path.exists() and (MOTIONS_DIR / f"{name_or_path}.npz").is_file():
        return MOTIONS_DIR / f"{name_or_path}.npz"
    return path
