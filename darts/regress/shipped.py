"""The networks shipped in ``darts/regress/weights/``, each loaded once per process."""
from __future__ import annotations

from functools import cache
from pathlib import Path

from darts.errors import DartsInputError

WEIGHTS = Path(__file__).parent / "weights"


@cache
def shipped_model(kind: str, name: str):
    """A shipped network (``weights/<name>.pt``, a checkpoint of ``kind``: classifier or lines) and
    its record."""
    from darts.regress.train import load_checkpoint

    path = WEIGHTS / f"{name}.pt"
    if not path.is_file():
        raise DartsInputError(path, "the shipped weights are missing (train them: docs/reconstruction.md)")
    return load_checkpoint(path, kind)
