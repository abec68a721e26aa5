"""Names of the shipped motions and garments (the data in the ``scenes`` package) and what a
command's MOTION or GARMENT argument resolves to: a file, else the shipped one of that name."""
from __future__ import annotations

from pathlib import Path

from darts.errors import DartsInputError
from scenes import GARMENTS_DIR, MOTIONS_DIR


def shipped_motions() -> list[str]:
    """Names of the shipped motions (``walk``, ``run``, ...)."""
    return sorted(p.stem for p in MOTIONS_DIR.glob("*.npz"))


def shipped_garments() -> list[str]:
    """Names of the shipped DARTs (``short-sleeve-top``, ...)."""
    return sorted(p.stem for p in GARMENTS_DIR.glob("*.npz"))


def garment_help() -> str:
    """What a GARMENT argument takes, for a command's --help."""
    return f"a garment.npz (a DART) or a shipped garment: {', '.join(shipped_garments())}"


def motion_help() -> str:
    """What a MOTION argument takes, for a command's --help."""
    return f"an AMASS-format .npz or a shipped motion: {', '.join(shipped_motions())}"


def _resolve(name_or_path: str | Path, folder: Path, kind: str) -> Path:
    path = Path(name_or_path)
    if path.exists() or path.is_symlink():  # a link that leads nowhere is the loader's to explain
        return path
    if (folder / f"{name_or_path}.npz").is_file():
        return folder / f"{name_or_path}.npz"
    names = sorted(p.stem for p in folder.glob("*.npz"))
    raise DartsInputError(path, f"neither a file nor a shipped {kind} (shipped: {', '.join(names)})")


def resolve_motion(name_or_path: str | Path) -> Path:
    """A motion path: the argument itself if it is a file, else the shipped motion of that name;
    a DartsInputError listing the shipped motions when it is neither."""
    return _resolve(name_or_path, MOTIONS_DIR, "motion")


def resolve_garment(name_or_path: str | Path) -> Path:
    """A garment path: the argument itself if it is a file, else the shipped DART of that name; a
    DartsInputError listing the shipped garments when it is neither."""
    return _resolve(name_or_path, GARMENTS_DIR, "garment")
