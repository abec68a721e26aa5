"""Where a dataset's garments end along the limbs, per category and recipe: how far apart the
recipes keep short and long sleeves, shorts and long pants, short and long skirts.

    python scripts/recipe_ends.py DATASET [--out FILE.json]

For every garment of ``DATASET/garments`` (its DART before the drape: rest pose on its own body
shape, canonical frame): each end line — the cuffs, a lower garment's hems — as s along its limb
(``darts.photo.attributes``' convention: 0 at the shoulder or hip, 0.5 at the elbow or knee, 1 at
the wrist or ankle, linear along each bone, on the garment's body's rest landmarks,
``darts.photo.lengths.rest_landmarks``): the s where the limb's polyline crosses the plane of the
line (its centre and axis, ``darts.crdl.targets.loop_frame``); of two cuffs or legs the shorter.
That is the s a photograph's read end (``sleeve_end``, ``hem_end``) measures, without the picture.
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

#: the limbs whose ends decide a category: (the long categories' prefixes, the short ones')
LIMBS = {"sleeve": (("long-sleeve",), ("short-sleeve",)), "trouser leg": (("long-pants",), ("short-pants",)),
         "skirt": (("long-skirt",), ("short-skirt",))}


def crossing(polyline: np.ndarray, centre: np.ndarray, axis: np.ndarray, samples: int = 2001) -> float:
    """The s in [0, 1] where ``polyline`` (``darts.photo.attributes.point_at``) comes nearest to
    crossing the plane through ``centre`` normal to ``axis``."""
    from darts.photo.attributes import point_at

    s = np.linspace(0.0, 1.0, samples)
    level = np.array([np.dot(point_at(polyline, value) - centre, axis) for value in s])
    return float(s[np.argmin(np.abs(level))])


def garment_end(folder: Path, body) -> tuple[dict, float | None]:
    """(the garment's ``meta.json``, its end s: ``None`` for a garment without a limb's end)."""
    from darts.crdl.targets import loop_frame
    from darts.dart.io import load_dart
    from darts.geometry.loops import feature_lines
    from darts.photo.attributes import ARM, LEG, chain
    from darts.photo.lengths import rest_landmarks

    meta = json.loads((folder / "meta.json").read_text())
    category = meta["category"]
    if "sleeveless" in category:
        return meta, None
    dart = load_dart(folder / "garment.npz")
    lines = feature_lines(dart, dart.vertices)
    centre = np.asarray(dart.vertices, np.float64).mean(0)
    points = rest_landmarks(body, np.asarray(meta["betas"]))
    ends = []
    for side in ("left", "right"):
        if "sleeve" in category:
            name, polyline = f"{side}_cuff", chain(points, side, ARM)
        elif "pants" in category:
            name, polyline = f"{side}_hem", chain(points, side, LEG)
        elif "skirt" in category:
            name, polyline = "hem", 0.5 * (chain(points, "left", LEG) + chain(points, "right", LEG))
        else:
            return meta, None
        ends.append(crossing(polyline, *loop_frame(np.asarray(lines[name], np.float64), centre)))
    return meta, min(ends)


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    from darts.body.io import load_body

    body = load_body(None)
    rows = []
    for folder in sorted((args.data / "garments").glob("g*")):
        if not (folder / "garment.npz").is_file():
            continue
        meta, end = garment_end(folder, body)
        if end is not None:
            rows.append({"id": meta["id"], "category": meta["category"], "edits": meta["edits"], "end": round(end, 4)})
    summary = {"data": str(args.data), **summarise(rows)}
    text = json.dumps(summary, indent=1)
    if args.out:
        args.out.write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
