"""The numbers and picture of docs/import.md: garment meshes made outside the template builder,
imported with ``darts import`` (by default and with ``--own-mesh``) and simulated on the walk and
the squat with ``darts-sim`` (default settings).

    python scripts/evaluate_import.py [--work DIR] [--reuse]

Meshes (written under ``--work``, default ~/.cache/darts/import-eval): a skirt built as an elliptic
cone of quads (OBJ, metres); the shipped short-sleeve top subdivided, stretched, turned and moved,
in centimetres, as OBJ (Y up) and as USD (Z up, metersPerUnit 0.01, a translate on the prim); the
shipped short skirt exported by ``darts export`` (the round trip); Newton's example shirt
(``NEWTON_SHIRT``) where it has been fetched. Results: docs/data/import.json, the picture:
docs/images/import_shirt.png.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.helpers import cone_skirt_obj, remeshed_shirt, write_usd_mesh  # noqa: E402

#: The console scripts of the environment running this script.
BIN = Path(sys.executable).parent
RESULTS = ROOT / "docs" / "data" / "import.json"
#: A garment made by another project: Newton 1.8's example shirt (``pip download newton==1.8.0
#: --no-deps``, then unzip ``newton/examples/assets/unisex_shirt.usd`` here); its row is left out
#: when it is not.
NEWTON_SHIRT = Path.home() / ".cache" / "darts" / "assets" / "unisex_shirt.usd"
#: Each imported garment is simulated on these (darts-sim defaults).
MOTIONS = ("walk", "squat")
PICTURE = ROOT / "docs" / "images" / "import_shirt.png"


def _meshes(work: Path) -> dict[str, Path]:
    import trimesh

    from darts.dart.io import load_dart

    cone_skirt_obj(work / "cone_skirt.obj")
    vertices, faces = remeshed_shirt(load_dart(ROOT / "scenes" / "garments" / "short-sleeve-top.npz"))
    trimesh.Trimesh(vertices, faces, process=False).export(work / "shirt_cm_yup.obj")
    y_to_z = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
    write_usd_mesh(work / "shirt_cm_zup.usda", vertices @ y_to_z.T - [0, 0, 10.0], faces, 0.01, "z", (0, 0, 10.0))
    subprocess.run([BIN / "darts", "export", ROOT / "scenes" / "garments" / "short-skirt.npz", "-o", work / "short_skirt.obj"],
                   check=True)
    meshes = {"cone skirt (OBJ, quads, m)": work / "cone_skirt.obj", "shirt (OBJ, cm, Y up)": work / "shirt_cm_yup.obj",
              "shirt (USD, cm, Z up)": work / "shirt_cm_zup.usda", "short-skirt round trip (OBJ)": work / "short_skirt.obj"}
    if NEWTON_SHIRT.exists():
        meshes["Newton's unisex_shirt.usd (USD, cm, Y up)"] = NEWTON_SHIRT
    return meshes


def _import_and_simulate(mesh: Path, base: Path, png: list, own_mesh: bool, reuse: bool) -> dict:
    """Import ``mesh`` (as ``base``.npz, with ``--own-mesh`` or not), simulate it on ``MOTIONS``; the
    report and each motion's stats. With ``reuse``, outputs already under the work folder are read
    instead of made again."""
    garment, report_path = base.with_suffix(".npz"), base.with_suffix(".report.json")
    if not (reuse and report_path.exists()):
        subprocess.run([BIN / "darts", "import", mesh, "-o", garment, "--report", report_path, "--quiet", *png,
                        *(["--own-mesh"] if own_mesh else [])], check=True)
    motions = {}
    for motion in MOTIONS:
        stats_path = base.with_suffix(f".{motion}.stats.json")
        if not (reuse and stats_path.exists()):
            subprocess.run([BIN / "darts-sim", garment, motion, "-o", base.with_suffix(f".{motion}.usdc"), "--stats",
                            stats_path, "--quiet"], check=True)
        stats = json.loads(stats_path.read_text())
        motions[motion] = {k: stats[k] for k in ("stable", "simulated_frames", "max_penetration", "strain_p99", "sim_fps")}
    return {"report": json.loads(report_path.read_text()), **motions}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, default=Path.home() / ".cache" / "darts" / "import-eval")
    parser.add_argument("--reuse", action="store_true", help="read the imports and runs already under --work")
    args = parser.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    rows = {}
    meshes = _meshes(args.work)
    pictured = list(meshes)[-1]  # Newton's shirt where fetched, else the USD shirt
    for name, mesh in meshes.items():
        for own_mesh in (False, True):
            base = args.work / (mesh.stem + ("-own" if own_mesh else ""))
            png = ["--png", PICTURE] if name == pictured and not own_mesh else []
            result = _import_and_simulate(mesh, base, png, own_mesh, args.reuse)
            report = result.pop("report")
            row = {"category": report["category"], "category_guess_mm": report["category_guess"],
                   "scale": report["scale"], "dart_to_mesh": report["dart_to_mesh"], "mesh_to_dart": report["mesh_to_dart"],
                   "feature_line_max_mm": max(v["max_mm"] for v in report["feature_lines"].values()),
                   "inside_body": report["inside_body"], **result}
            if own_mesh:
                row["moved_out_of_body"] = report["moved_out_of_body"]
            if "round trip" in name and not own_mesh:
                from darts.dart.io import load_dart

                moved = np.linalg.norm(load_dart(base.with_suffix(".npz")).vertices
                                       - load_dart(ROOT / "scenes" / "garments" / "short-skirt.npz").vertices, axis=1)
                row["round_trip_mm"] = {"mean": 1e3 * float(moved.mean()), "max": 1e3 * float(moved.max())}
            rows[name + (", --own-mesh" if own_mesh else "")] = row
            print(name, "own mesh" if own_mesh else "", json.dumps(row))
    RESULTS.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
