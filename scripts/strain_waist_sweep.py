"""The trousers' strain against the waistband's hold in the deep poses (issue 46): the shipped long
pants sitting and squatting, at the defaults and with the waistband's grip or the cloth's friction
on the body changed, or cut looser (the template's ease: the cloth's distance off the body at rest;
6 mm everywhere for the trousers shipped until the sitting allowance, ``darts.templates.defaults.SEAT_EASE``,
which the shipped long pants now carry below a 6 mm waistband), alone and under the long-sleeve top
(an outfit: the strain's 99th percentile of all its edges, and of each garment's); and where the
stretched edges lie.

    python scripts/strain_waist_sweep.py [--out docs/data/strain_waist_sweep.json] [--only NAME;NAME] [--drape]

Each configuration runs the whole motion (0.5 s settle, 30 fps, default body, every recorded frame
measured, ``sim.run.simulate``): the largest 99th percentile and the largest edge strain of a frame
(``sim.quality.edge_strain``: max(l / l0 - 1, 0)), the largest waist slide (``sim.quality.WaistSlide``),
the most crossing edges in a frame (and every frame's count), the largest share of particles inside the body by the closest
point's sign, and the fastest particle inside a substep against the recorded frames' fastest (m/s).
The cloth's friction is the DART's material value (``--material``'s cotton: 0.4) unless a row sets it.

At the frame of the default's sit with the largest 99th percentile, the edges stretched past
``HOT`` are counted by the body part nearest their midpoint (``darts.body.segmentation``), by their
rest depth below the garment's top (canonical frame, Y up) and by side (front: rest z above the
garment's middle), beside the stretch of the body's own skin there (its edges against the first
recorded frame, 99th percentile per part): linear blend skinning stretches the seat's skin, and
cloth held on it by the waistband's grip has to follow.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from darts.fileio import atomic_path

ROOT = Path(__file__).resolve().parents[1]
GARMENT = "long-pants"
MOTIONS = ("sit", "squat")
#: name -> (waist_friction, the cloth's friction on the body or None for the material's, the cut's
#: ease in m everywhere or None for the shipped DART (6 mm at the waistband, ``SEAT_EASE`` below it),
#: motions, a shipped garment worn over the pants as an outfit or None)
CONFIGURATIONS = {
    "6 mm cut (shipped before), waistband grip 3": (3.0, None, 0.006, MOTIONS, None),
    "6 mm cut, waistband grip 1.5": (1.5, None, 0.006, MOTIONS, None),
    "6 mm cut, waistband grip 0.75": (0.75, None, 0.006, MOTIONS, None),
    "6 mm cut, no waistband grip": (0.0, None, 0.006, MOTIONS, None),
    "6 mm cut, waistband grip 3, cloth friction 0.1": (3.0, 0.1, 0.006, MOTIONS, None),
    "6 mm cut, waistband grip 3, frictionless cloth": (3.0, 0.0, 0.006, MOTIONS, None),
    "cut with 15 mm ease": (3.0, None, 0.015, MOTIONS, None),
    "cut with 30 mm ease": (3.0, None, 0.03, (*MOTIONS, "kneel", "walk"), None),
    "6 mm cut, under the long-sleeve top": (3.0, None, 0.006, MOTIONS, "long-sleeve-top"),
    "cut with 30 mm ease, under the long-sleeve top": (3.0, None, 0.03, MOTIONS, "long-sleeve-top"),
    "shipped: 6 mm waistband, 30 mm below": (3.0, None, None, (*MOTIONS, "kneel", "walk"), None),
    "shipped, under the long-sleeve top": (3.0, None, None, (*MOTIONS, "kneel"), "long-sleeve-top"),
}
#: the configuration whose worst sitting frame is taken apart (``where``)
DEFAULT = "6 mm cut (shipped before), waistband grip 3"
#: an edge stretched past this is counted where it lies (the issue's p99 target)
HOT = 0.15
#: rest depth bands below the garment's top (m)
DEPTHS = (0.0, 0.03, 0.10, 0.20, 0.40, 2.0)


def garment(ease: float | None):
    """The long pants: the shipped DART, or the same category cut on the default body with ``ease`` (m)
    everywhere."""
    from darts.body.io import load_body
    from darts.dart.build import make_dart
    from darts.dart.io import load_dart
    from darts.shipped import resolve_garment

    if ease is None:
        return load_dart(resolve_garment(GARMENT))
    return make_dart(GARMENT, load_body(), seat_ease=ease, ease=ease)


def run(motion: str, waist: float, friction: float | None, ease: float | None, over: str | None,
        keep: bool = False) -> tuple[dict, dict | None]:
    """(the row's measures, with ``keep`` what ``where`` needs of the worst frame, else None) of one
    configuration; with ``over``, the pants and that shipped garment as an outfit (``sim.outfit``)."""
    from darts.body.io import load_body
    from darts.dart.io import load_dart
    from darts.motion.amass import load_motion
    from darts.shipped import resolve_garment, resolve_motion
    from sim.body_track import build_body_track
    from sim.engine.settings import SimSettings
    from sim.outfit import outfit_model
    from sim.run import simulate, summary

    body = load_body()
    dart = garment(ease)
    if friction is not None:
        dart.material["friction"] = friction
    garments = dart if over is None else outfit_model([dart, load_dart(resolve_garment(over))], [GARMENT, over],
                                                      body.shaped()[0][0].double().numpy(), body.faces)
    settings = SimSettings(waist_friction=waist)
    track = build_body_track(body, load_motion(resolve_motion(motion)), settings.fps, 0.5, gap=settings.body_gap)
    kept = []  # every recorded frame's garment and body, only for the run ``where`` takes apart
    result = simulate(garments, track, settings,
                      sink=(lambda garment, body: kept.append((garment.copy(), body.copy()))) if keep else None)
    stats = summary(result, len(dart.vertices) if over is None else len(garments.model.rest))
    p99 = [f["strain"]["p99"] for f in result.frames]
    worst = int(np.argmax(p99))
    row = {"motion": motion, "waist_friction": waist, "cloth_friction": friction, "ease": ease, "stable": result.stable,
           "strain_p99": stats["strain_p99"], "strain_max": stats["strain_max"],
           "max_waist_slide": stats["max_waist_slide"], "max_self_intersections": stats["max_self_intersections"],
           "max_penetration": stats["max_penetration"], "max_substep_speed": stats["max_substep_speed"],
           "max_frame_speed": stats["max_frame_speed"], "worst_frame": worst,
           "crossings_per_frame": [f["self_intersections"] for f in result.frames],
           "strain_p99_per_garment": None if over is None else {
               name: max(f["garments"][name]["strain"]["p99"] for f in result.frames) for name in garments.names}}
    if not keep:
        return row, None
    return row, {"dart": dart, "track": track, "garment": kept[worst][0], "body": kept[worst][1], "first_body": kept[0][1]}


def where(worst: dict) -> dict:
    """The edges stretched past ``HOT`` at the worst frame by body part, rest depth and side, and the
    skin's own stretch per part there (module docstring)."""
    from scipy.spatial import cKDTree

    from darts.body.segmentation import PART_NAMES
    from darts.geometry.mesh import unique_edges
    from sim.engine.model import cloth_model
    from sim.quality import edge_strain

    model, track = cloth_model(worst["dart"]), worst["track"]
    particles = np.zeros((len(model.rest), 3))
    particles[model.particle_of_vertex] = worst["garment"]
    strain = edge_strain(model, particles)
    hot = strain > HOT
    middle = 0.5 * (particles[model.edges[:, 0]] + particles[model.edges[:, 1]])
    part = track.parts[cKDTree(worst["body"]).query(middle)[1]]
    rest = 0.5 * (model.rest[model.edges[:, 0]] + model.rest[model.edges[:, 1]])
    depth = model.rest[:, 1].max() - rest[:, 1]
    front = rest[:, 2] > np.median(model.rest[:, 2])
    skin_edges = unique_edges(np.asarray(track.faces).reshape(-1, 3))

    def lengths(v):
        return np.linalg.norm(v[skin_edges[:, 0]] - v[skin_edges[:, 1]], axis=1)

    skin = lengths(worst["body"]) / lengths(worst["first_body"]) - 1.0
    skin_part = track.parts[skin_edges[:, 0]]
    parts = {}
    for index in np.unique(part[hot]):
        mine = part == index
        parts[PART_NAMES[index]] = {"hot": int((hot & mine).sum()), "edges": int(mine.sum()),
                                    "hot_mean_strain": float(strain[hot & mine].mean()),
                                    "skin_p99": float(np.percentile(skin[skin_part == index], 99))}
    bands = [{"from": a, "to": b, "edges": int(((depth >= a) & (depth < b)).sum()),
              "hot": int((hot & (depth >= a) & (depth < b)).sum()),
              "hot_back": int((hot & ~front & (depth >= a) & (depth < b)).sum()),
              "max": float(strain[(depth >= a) & (depth < b)].max(initial=0.0))}
             for a, b in zip(DEPTHS[:-1], DEPTHS[1:])]
    return {"edges": len(strain), "hot": int(hot.sum()), "parts": parts, "depths": bands}


#: the dataset drape's check of a cut: the first ``DRAPE_COUNT`` trousers (long or short) of this seed
DRAPE_SEED, DRAPE_COUNT = 0, 8
#: cut name -> (ease at the waistband, ease below it; None: the category's own, the shipped cut)
DRAPE_CUTS = {"6 mm everywhere": (0.006, 0.006), "shipped: 6 mm waistband, 30 mm below": (0.006, None),
              "30 mm everywhere": (0.03, 0.03)}


def drape_drops() -> dict[str, list[float]]:
    """How far (m) each cut's waistband settles down the hips in the reconstruction dataset's drape
    (``sim.dataset.drape``: 0.5 s under gravity on the still body, the implicit solver, its own
    settings): the waist line's mean height (canonical Y) before less after, for the first
    ``DRAPE_COUNT`` trousers of seed ``DRAPE_SEED``, each cut on the recipe's body and deformed to
    its edits as the dataset does (``sim.dataset.recipe.recipe_garment``)."""
    from darts.body.io import load_body
    from darts.dart.build import make_dart
    from darts.templates.categories import CATEGORIES
    from darts.templates.defaults import DATASET_EDGE_LENGTH
    from sim.dataset.drape import drape
    from sim.dataset.recipe import garment_recipe, recipe_garment

    body = load_body()
    recipes = [r for r in (garment_recipe(DRAPE_SEED, i) for i in range(20 * DRAPE_COUNT))
               if CATEGORIES[r.category].family == "pants"][:DRAPE_COUNT]
    drops = {}
    for name, (ease, seat_ease) in DRAPE_CUTS.items():
        drops[name] = []
        for recipe in recipes:
            template = make_dart(recipe.category, body, np.asarray(recipe.betas), DATASET_EDGE_LENGTH,
                                 seat_ease=seat_ease, ease=ease)
            dart, _, _ = recipe_garment(recipe, body, template)
            waist = np.asarray(dart.lines["waist"])
            settled = drape(dart, body, "pants").vertices
            drops[name].append(float(np.asarray(dart.vertices)[waist, 1].mean() - settled[waist, 1].mean()))
        print(name, np.round(100 * np.array(drops[name]), 1), "cm", flush=True)
    return drops


def table(document: dict) -> str:
    """The sweep's Markdown table."""
    lines = ["| configuration | motion | strain p99 / max (%) | waist slide (cm) | crossing edges | inside (sign, %) "
             "| fastest substep / frame particle (m/s) |", "|---|---|---|---|---|---|---|"]
    for name, rows in document["configurations"].items():
        for r in rows:
            each = r.get("strain_p99_per_garment")
            apart = "" if not each else " (" + ", ".join(f"{g} {100 * p:.1f}" for g, p in each.items()) + ")"
            lines.append(f"| {name} | {r['motion']} | {100 * r['strain_p99']:.1f}{apart} / {100 * r['strain_max']:.0f} | "
                         f"{100 * r['max_waist_slide']:.1f} | {r['max_self_intersections']} | "
                         f"{100 * r['max_penetration']:.2f} | {r['max_substep_speed']:.1f} / {r['max_frame_speed']:.2f} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "data" / "strain_waist_sweep.json")
    parser.add_argument("--only", help="run only these configurations (names joined by ';'); keep the others' rows "
                                       "already in --out")
    parser.add_argument("--drape", action="store_true", help="only the cuts' waistbands in the dataset's drape "
                                                             "(about 2 minutes), into --out's 'drape'")
    args = parser.parse_args()
    if args.drape:
        document = json.loads(args.out.read_text())
        document["drape"] = {"seed": DRAPE_SEED, "count": DRAPE_COUNT, "waist_drop": drape_drops()}
        with atomic_path(args.out) as temporary:
            temporary.write_text(json.dumps(document, indent=1))
        return
    only = list(CONFIGURATIONS) if args.only is None else args.only.split(";")
    unknown = sorted(set(only) - set(CONFIGURATIONS))
    if unknown:
        parser.error(f"unknown configurations: {'; '.join(unknown)}")
    document = {"command": "python scripts/strain_waist_sweep.py", "garment": GARMENT, "hot": HOT, "configurations": {}}
    if args.only is not None and args.out.exists():
        document = json.loads(args.out.read_text())
    kept = document["configurations"]
    document["configurations"] = {}
    for name, (waist, friction, ease, motions, over) in CONFIGURATIONS.items():
        if name not in only:
            if name in kept:
                document["configurations"][name] = kept[name]
            continue
        rows = []
        for motion in motions:
            taken_apart = name == DEFAULT and motion == "sit"
            row, worst = run(motion, waist, friction, ease, over, keep=taken_apart)
            if taken_apart:
                document["worst_sit"] = {"frame": row["worst_frame"], **where(worst)}
            rows.append(row)
            print(name, json.dumps(row), flush=True)
        document["configurations"][name] = rows
    with atomic_path(args.out) as temporary:
        temporary.write_text(json.dumps(document, indent=1))
    print(table(document))


if __name__ == "__main__":
    main()
