"""Write the shipped DARTs to scenes/garments/ (one per category on the default body, plus a
short-sleeve top with a collar and a tie); ``python scripts/docs_tables.py shipped-garments`` then
writes their table in docs/templates.md."""
from __future__ import annotations

import argparse
from pathlib import Path

from darts.body.io import load_body
from darts.dart.build import make_dart
from darts.dart.io import save_dart
from darts.templates.categories import CATEGORIES

EXTRAS = {"tshirt-collar-tie": ("short-sleeve-top", ["collar", "tie"])}


def _jobs() -> dict[str, tuple[str, list[str]]]:
    return {cid: (cid, []) for cid in CATEGORIES} | EXTRAS


def shipped_names() -> list[str]:
    """The shipped garments' names, in the order they are made."""
    return list(_jobs())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output-dir", default="scenes/garments")
    args = parser.parse_args()
    body = load_body()
    for name, (category, accessories) in _jobs().items():
        dart = make_dart(category, body, accessories=accessories)
        save_dart(dart, Path(args.output_dir) / f"{name}.npz")
        print(f"wrote {name}: {len(dart.vertices)} vertices")


if __name__ == "__main__":
    main()
