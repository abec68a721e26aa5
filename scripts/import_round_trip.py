"""The import round trip of issue 47 (docs/import.md): shipped DARTs edited with the CRDL, remeshed,
written as another tool would write them, imported back with ``darts import``, and compared with
the garment they came from.

    python scripts/import_round_trip.py [--count 20] [--collars 2] [--seed 0] [--work DIR]
                                        [--out docs/data/import_round_trip.json] [--rows FIRST LAST]
                                        [--own-mesh-again TAG]

Garment k (``--seed`` and k fix every draw; resumable: a garment whose result is under ``--work``,
default ~/.cache/darts/import-round-trip, is not made again; ``--own-mesh-again TAG`` imports only
its ``--own-mesh`` column again, from the same file, after a change that touches nothing else; TAG
names the change, and a garment done again under it is not done again):
1. **Category** ``CATEGORIES[k % 10]``; the last ``--collars`` garments are short- and long-sleeve
   tops built with the collar accessory (``darts.template(..., accessories=["collar"])``).
2. **Edits**: every edit of the category's dataset ranges (``sim.dataset.recipe.EDIT_RANGES``: hem,
   sleeve, neckline, widths), drawn uniformly, applied by the CRDL (``darts.deform``).
3. **Remeshed**: the welded surface (panels joined at their seams) remeshed isotropically
   (gpytoolbox's ``remesh_botsch``, Botsch & Kobbelt 2004; 10 rounds; creases sharper than 30 deg
   kept, ``tests.helpers.isotropic_remesh``) to a target edge of 0.7-1.5 times its own mean edge:
   a different triangulation and resolution, the openings kept.
4. **Written** in the k-th of six forms: OBJ in cm and mm (Y up), GLB in cm and mm (a node scale of
   0.01 or 0.001 over the points, as a DCC writes a scene in those units), USD in cm (Z up) and mm
   (Y up, ``metersPerUnit``), turned about the vertical by up to 25 deg, tilted up to 3 deg and moved
   up to 0.5 m.
5. **Imported** twice, nothing else given (the category guessed, the units and up axis read or
   guessed): ``darts import FILE -o garment.npz --report report.json`` (the registered template)
   and the same with ``--own-mesh`` (the file's own mesh, cut into the template's panels).

Measured against the edited garment (both in the canonical frame, metres; reported in mm):
- **surface distances** both ways: area-uniform samples (20,000) of one welded surface, unsigned
  point-to-surface distance to the other; mean, p95 and max;
- **seams**: each seam vertex of the import (a vertex of a seam pair) to the nearest seam edge of
  the original (a panel-boundary edge between two of its seam vertices): mean, max and the share
  within 5 mm;
- the category guessed, the scale fitted and the report's own distances to the file.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.helpers import isotropic_remesh, round_trip_distances, write_usd_mesh  # noqa: E402

BIN = Path(sys.executable).parent
RESULTS = ROOT / "docs" / "data" / "import_round_trip.json"
#: The six forms a garment is written in: (format, unit in metres, up axis).
FORMS = (("obj", 0.01, "y"), ("obj", 0.001, "y"), ("glb", 0.01, "y"), ("glb", 0.001, "y"), ("usda", 0.01, "z"),
         ("usda", 0.001, "y"))
COLLAR_CATEGORIES = ("short-sleeve-top", "long-sleeve-top")


def recipe(seed: int, k: int, count: int, collars: int) -> dict:
    """Garment ``k``'s draws: category, accessories, edits, remeshing factor, form and rigid motion."""
    from darts.templates.categories import CATEGORIES
    from sim.dataset.recipe import EDIT_RANGES

    rng = np.random.default_rng([seed, k])
    collar = k >= count
    category = COLLAR_CATEGORIES[(k - count) % len(COLLAR_CATEGORIES)] if collar else list(CATEGORIES)[k % len(CATEGORIES)]
    edits = {name: round(float(rng.uniform(*bounds)), 4) for name, bounds in EDIT_RANGES[category].items()}
    form = FORMS[k % len(FORMS)]
    return {"index": k, "category": category, "accessories": ["collar"] if collar else [], "edits": edits,
            "edge_factor": round(float(rng.uniform(0.7, 1.5)), 3), "format": form[0], "unit_m": form[1], "up": form[2],
            "yaw_deg": round(float(rng.uniform(-25, 25)), 2), "tilt_deg": round(float(rng.uniform(-3, 3)), 2),
            "move_m": np.round(rng.uniform(-0.5, 0.5, 3), 3).tolist()}


def shipped_garment(draw: dict):
    """The shipped DART of the draw's category (built with its accessories)."""
    import darts

    return darts.template(draw["category"], accessories=draw["accessories"]) if draw["accessories"] \
        else darts.load_garment(draw["category"])


def edited_garment(draw: dict):
    """``shipped_garment`` deformed by the draw's edits."""
    import darts

    deformed, _ = darts.deform(shipped_garment(draw), edits=[f"{name}={value}" for name, value in draw["edits"].items()])
    return deformed


def write_form(path: Path, vertices: np.ndarray, faces: np.ndarray, draw: dict) -> None:
    """``vertices`` [N,3] (canonical frame, metres) turned, moved and written as the draw's form."""
    import trimesh
    from scipy.spatial.transform import Rotation

    moved = Rotation.from_euler("yx", [draw["yaw_deg"], draw["tilt_deg"]], degrees=True).apply(vertices) + draw["move_m"]
    points = moved / draw["unit_m"]
    if draw["format"] == "obj":
        trimesh.Trimesh(points, faces, process=False).export(path)
    elif draw["format"] == "glb":
        scene = trimesh.Scene()
        scene.add_geometry(trimesh.Trimesh(points, faces, process=False), transform=np.diag([draw["unit_m"]] * 3 + [1.0]))
        scene.export(path)
    else:
        y_to_z = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
        write_usd_mesh(path, points @ y_to_z.T if draw["up"] == "z" else points, faces, draw["unit_m"], draw["up"])


def import_and_measure(mesh: Path, original, stem: Path, seed: int, own_mesh: bool) -> dict:
    """``darts import`` of ``mesh`` (``--own-mesh`` or not) measured against ``original``."""
    from darts.dart.io import load_dart

    garment, report_path = stem.with_suffix(".npz"), stem.with_suffix(".report.json")
    start = time.time()
    subprocess.run([BIN / "darts", "import", mesh, "-o", garment, "--report", report_path, "--quiet",
                    *(["--own-mesh"] if own_mesh else [])], check=True)
    seconds = time.time() - start
    report = json.loads(report_path.read_text())
    return {"guessed": report["category"], "scale": report["scale"], "import_wall_s": seconds,
            "report": {k: {m: report[k][m] for m in ("mean_mm", "p95_mm", "max_mm")}
                       for k in ("dart_to_mesh", "mesh_to_dart", "moved_out_of_body") if k in report},
            **round_trip_distances(load_dart(garment), original, seed)}


def run_one(draw: dict, work: Path, seed: int) -> dict:
    """Make, write, import (the registered template, and the file's own mesh) and measure one
    garment (module docstring)."""
    from darts.dart.io import save_dart

    stem = work / f"g{draw['index']:02d}-{draw['category']}"
    original = edited_garment(draw)
    save_dart(original, stem.with_suffix(".original.npz"))
    vertices, faces = isotropic_remesh(original, draw["edge_factor"])
    mesh = stem.with_suffix(f".{draw['format']}")
    write_form(mesh, vertices, faces, draw)
    return {**draw, "file_vertices": len(vertices), "original_vertices": len(original.vertices),
            **import_and_measure(mesh, original, stem, seed, own_mesh=False),
            "own_mesh": import_and_measure(mesh, original, stem.with_name(stem.name + "-own"), seed, own_mesh=True)}


def own_mesh_again(row: dict, work: Path, seed: int) -> dict:
    """``row`` with its ``--own-mesh`` import made and measured again from the file under ``work``."""
    from darts.dart.io import load_dart

    stem = work / f"g{row['index']:02d}-{row['category']}"
    original = load_dart(stem.with_suffix(".original.npz"))
    mesh = stem.with_suffix(f".{row['format']}")
    return {**row, "own_mesh": import_and_measure(mesh, original, stem.with_name(stem.name + "-own"), seed, own_mesh=True)}


def _means(r: dict) -> str:
    return f"{r['imported_to_original']['mean_mm']:.2f} / {r['original_to_imported']['mean_mm']:.2f} mm"


def _seams(r: dict) -> str:
    return f"{r['seams']['mean_mm']:.1f} / {r['seams']['max_mm']:.1f} mm, {100 * r['seams']['within_5mm']:.0f} %"


def table(rows: list[dict]) -> list[str]:
    """The Markdown table of docs/import.md (``scripts/docs_tables.py``)."""
    lines = ["| # | category | edits (cm) | file | guessed | template: import→original / back, mean | p95 "
             "| seams: mean / max, within 5 mm | own mesh: mean both ways | seams |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        edits = ", ".join(f"{k} {100 * v:+.1f}" for k, v in r["edits"].items())
        accessories = " + collar" if r["accessories"] else ""
        unit = {0.01: "cm", 0.001: "mm"}[r["unit_m"]]
        own = r["own_mesh"]
        lines.append(f"| {r['index']} | {r['category']}{accessories} | {edits} | {r['format'].upper().rstrip('A')}, "
                     f"{unit}, {r['file_vertices']} vertices | {'yes' if r['guessed'] == r['category'] else r['guessed']} | "
                     f"{_means(r)} | {r['imported_to_original']['p95_mm']:.1f} / {r['original_to_imported']['p95_mm']:.1f} mm | "
                     f"{_seams(r)} | {_means(own)} | {_seams(own)} |")
    return lines


def summary(rows: list[dict]) -> str:
    """One line: how many garments meet issue 47's bars (2 mm mean both ways; every seam vertex
    within 5 mm of the original's seams), the registered template's and the file's own mesh's."""

    def larger_mean(r: dict) -> float:
        return max(r["imported_to_original"]["mean_mm"], r["original_to_imported"]["mean_mm"])

    guessed = sum(r["guessed"] == r["category"] for r in rows)
    parts = []
    for name, results in (("the registered template", rows), ("the own mesh", [r["own_mesh"] for r in rows])):
        close = sum(larger_mean(r) <= 2.0 for r in results)
        seams = sum(r["seams"]["max_mm"] <= 5.0 for r in results)
        median = np.median([larger_mean(r) for r in results])
        parts.append(f"{name} within 2 mm both ways on average for {close} (median of the larger mean {median:.2f} mm), "
                     f"every seam vertex within 5 mm of the original's seams for {seams}")
    return f"{len(rows)} garments, the category guessed for {guessed}: " + "; ".join(parts) + "."


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--collars", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--work", type=Path, default=Path.home() / ".cache" / "darts" / "import-round-trip")
    parser.add_argument("--out", type=Path, default=RESULTS)
    parser.add_argument("--rows", type=int, nargs=2, metavar=("FIRST", "LAST"),
                        help="make and measure only garments FIRST..LAST (two runs at once share the work); the table "
                             "is written when every garment is under --work")
    parser.add_argument("--own-mesh-again", metavar="TAG",
                        help="import the garments already under --work again with --own-mesh only (after a change to "
                             "it alone, named TAG), from the same files; a garment already done again under TAG is kept")
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    rows = []
    for k in range(args.count + args.collars):
        draw = recipe(args.seed, k, args.count, args.collars)
        done = args.work / f"g{k:02d}.json"
        if args.rows and not args.rows[0] <= k <= args.rows[1]:
            continue
        if done.exists() and json.loads(done.read_text())["recipe"] == draw:
            record = json.loads(done.read_text())
            row = record["row"]
            if args.own_mesh_again and record.get("own_mesh_again") != args.own_mesh_again:
                row = own_mesh_again(row, args.work, args.seed)
                done.write_text(json.dumps({"recipe": draw, "row": row, "own_mesh_again": args.own_mesh_again}))
        else:
            row = run_one(draw, args.work, args.seed)
            done.write_text(json.dumps({"recipe": draw, "row": row}))
        rows.append(row)
        print("\n".join(table([row])[2:]), flush=True)
    if len(rows) == args.count + args.collars:
        args.out.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
