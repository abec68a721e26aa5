"""An outfit folder: several DARTs worn together, as ``darts reconstruct PHOTO -o OUT_DIR`` writes
them and ``darts-sim OUT_DIR MOTION`` runs them.

    OUT_DIR/outfit.json      {"garments": ["long-pants.npz", "short-sleeve-top.npz"], ...}: the
                             DARTs in layer order, inner first (paths relative to the folder), and
                             whatever the writer adds (the photograph, the categories, notes)
    OUT_DIR/<name>.npz       each DART (``darts.dart.io``)

Each file is written atomically and ``outfit.json`` last, so a folder without it is unfinished.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

from darts.errors import DartsInputError

INDEX = "outfit.json"


def outfit_garments(folder: str | os.PathLike) -> list[Path]:
    """The DART paths of the outfit ``folder``, inner layer first; a ``DartsInputError`` naming the
    folder when it has no readable index or the index names files that are not there."""
    folder = Path(folder)
    index = folder / INDEX
    if not index.is_file():
        raise DartsInputError(folder, f"is a folder without {INDEX}: not an outfit folder (darts reconstruct PHOTO -o "
                                      "OUT_DIR writes one)")
    try:
        names = json.loads(index.read_text())["garments"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise DartsInputError(index, f"unreadable outfit index ({exc.__class__.__name__}: {exc})") from None
    if not isinstance(names, list) or not names or not all(isinstance(n, str) and n for n in names):
        raise DartsInputError(index, "'garments' must be a non-empty list of file names")
    paths = [folder / name for name in names]
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise DartsInputError(index, f"names garment files that are not in the folder: {', '.join(missing)}")
    return paths


def write_outfit_folder(folder: str | os.PathLike, garments: list[tuple[str, object]], index: dict) -> list[Path]:
    """Write each (file name, ``Dart``) of ``garments`` (inner layer first) into ``folder`` and then
    ``outfit.json`` (``index`` with the garments' names added); the paths written."""
    from darts.dart.io import save_dart
    from darts.fileio import atomic_path

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, dart in garments:
        save_dart(dart, folder / name)
        written.append(folder / name)
    with atomic_path(folder / INDEX) as tmp:
        tmp.write_text(json.dumps({"garments": [name for name, _ in garments], **index}, indent=1) + "\n")
    return written + [folder / INDEX]
