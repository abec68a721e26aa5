"""Write the shipped DARTs to scenes/garments/ (one per category on the default body, plus a
short-sleeve top with a collar and a tie), and print the table of docs/templates.md."""
from __future__ import annotations

import argparse
from pathlib import Path

from darts.body.io import load_body
from darts.dart.build import make_dart
from darts.dart.io import save_dart
from darts.templates.categories import CATEGORIES

EXTRAS = {"tshirt-collar-tie": ("short-sleeve-top", ["collar", "tie"])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output-dir", default="scenes/garments")
    args = parser.parse_args()
    body = load_body()
    jobs = {cid: (cid, []) for cid in CATEGORIES} | EXTRAS
    print("| garment | category | vertices | faces | panels | seams | seam pairs | feature lines |")
    print("|---|---|---|---|---|---|---|---|")
    for name, (category, accessories) in jobs.items():
        dart = make_dart(category, body, accessories=accessories)
        save_dart(dart, Path(args.output_dir) / f"{name}.npz")
        print(f"| {name} | {category} | {len(dart.vertices)} | {len(dart.faces)} | {len(dart.panel_names)} | "
              f"{len(dart.seams)} | {len(dart.pairs)} | {', '.join(dart.lines)} |")


if __name__ == "__main__":
    main()
