"""Where a dataset's garments end along the limbs, per category and recipe: how far apart the
recipes keep short and long sleeves, shorts and long pants, short and long skirts.

    python scripts/recipe_ends.py DATASET [--out FILE.json]

For every garment of ``DATASET/garments`` (its DART before the drape: rest pose on its own body
shape, canonical frame): where it ends along its limb (``sim.dataset.recipe.garment_end``: the
cuffs' or the legs' hems' s, ``darts.photo.attributes``' convention, 0 at the shoulder or hip, 0.5
at the elbow or knee, 1 at the wrist or ankle; the s a photograph's read end measures, without
the picture).
Per category and per recipe (``sim.dataset.recipe.RECIPES``), the s range of the garments that
recipe could draw (``within_recipe``), and per limb and recipe the gap between the longest short
and the shortest long garment (negative: they overlap, and pictures there carry both labels).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

#: the limbs whose ends decide a category: (the long categories' prefix, the short ones')
LIMBS = {"sleeve": ("long-sleeve", "short-sleeve"), "trouser leg": ("long-pants", "short-pants"),
         "skirt": ("long-skirt", "short-skirt")}


def garment_row(folder: Path, body) -> dict | None:
    """A garment folder's category, edits and end (``sim.dataset.recipe.garment_end``); ``None``
    for a garment without a limb's end."""
    from darts.dart.io import load_dart
    from sim.dataset.recipe import garment_end

    meta = json.loads((folder / "meta.json").read_text())
    end = garment_end(load_dart(folder / "garment.npz"), body, meta["betas"])
    return None if end is None else {"id": meta["id"], "category": meta["category"], "edits": meta["edits"],
                                     "end": round(end, 4)}


def summarise(rows: list[dict]) -> dict:
    """Per category and recipe the s range (min, p10, median, p90, max) of the garments the recipe
    could draw, and per limb and recipe the gap (shortest long - longest short)."""
    from sim.dataset.recipe import RECIPES, within_recipe

    ranges, gaps = {}, {}
    for recipe in RECIPES:
        drawn = [row for row in rows if within_recipe(row["category"], row["edits"], recipe)]
        for category in sorted({row["category"] for row in drawn}):
            ends = np.array([row["end"] for row in drawn if row["category"] == category])
            ranges.setdefault(category, {})[str(recipe)] = {
                "garments": len(ends), **dict(zip(("min", "p10", "median", "p90", "max"),
                                                  np.round(np.percentile(ends, [0, 10, 50, 90, 100]), 3).tolist()))}
        for limb, (long, short) in LIMBS.items():
            longs = [row["end"] for row in drawn if row["category"].startswith(long)]
            shorts = [row["end"] for row in drawn if row["category"].startswith(short)]
            if longs and shorts:
                gaps.setdefault(limb, {})[str(recipe)] = {"longest_short": round(max(shorts), 3),
                                                          "shortest_long": round(min(longs), 3),
                                                          "gap": round(min(longs) - max(shorts), 3)}
    return {"garments": len(rows), "ends": ranges, "gaps": gaps}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    from darts.body.io import load_body

    body = load_body(None)
    rows = [row for folder in sorted((args.data / "garments").glob("g*")) if (folder / "garment.npz").is_file()
            for row in [garment_row(folder, body)] if row is not None]
    summary = {"data": str(args.data), **summarise(rows)}
    text = json.dumps(summary, indent=1)
    if args.out:
        args.out.write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
