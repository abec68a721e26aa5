"""The placement alone of the import round trip's garments (docs/import.md, ``darts.meshimport.align``):
each written file read, repaired and placed on its category's shipped template (arms at rest, as
the round trip's garments are), then measured against the edited garment it was made from.

    python scripts/import_placement.py [--work ~/.cache/darts/import-round-trip] [ROW ...]

Needs the files ``scripts/import_round_trip.py`` wrote under ``--work`` (garments with an
accessory are left out: their template is built, not shipped). Per row: the mean unsigned distance
of the placed file's vertices to the original's welded surface (mm), and the placement's rotation
error against the rigid motion the file was written with (degrees, as yaw about Y, pitch about X,
roll about Z). No output file: the numbers quoted in ``align.py`` and docs/import.md.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def place_row(work: Path, row: int, body) -> tuple[str, float, np.ndarray] | None:
    """(category, mean distance mm, yaw/pitch/roll error deg) of round-trip garment ``row``."""
    from scipy.spatial.transform import Rotation

    from darts.crdl.deform import weld_garment
    from darts.crdl.fit import FitSurface
    from darts.dart.io import load_dart
    from darts.dart.model import welded
    from darts.geometry.distance import SurfaceDistance
    from darts.meshimport.align import align_to_template, apply_matrix
    from darts.meshimport.pose import lower_arms
    from darts.meshimport.read import read_garment_mesh
    from darts.meshimport.repair import repair_garment_mesh
    from darts.templates.categories import CATEGORIES
    from scenes import GARMENTS_DIR

    draw = json.loads((work / f"g{row:02d}.json").read_text())["recipe"]
    if draw["accessories"]:
        return None
    stem = work / f"g{row:02d}-{draw['category']}"
    mesh = stem.with_suffix(f".{draw['format']}")
    source = read_garment_mesh(mesh, None, None, None)
    vertices, faces, loops, _ = repair_garment_mesh(source.vertices, source.faces, mesh)
    shipped = load_dart(GARMENTS_DIR / f"{draw['category']}.npz")
    template = weld_garment(shipped)
    hull = None if shipped.hull_vertices is None else (shipped.hull_vertices, shipped.hull_faces)
    fit = FitSurface(lower_arms(shipped, body, 0.0).body_vertices, body.faces, hull)  # the body at rest, as the import
    placement = align_to_template(vertices, faces, loops, CATEGORIES[draw["category"]], template.vertices,
                                  template.faces, template.lines, fit)
    original = welded(load_dart(stem.with_suffix(".original.npz")))
    distance, _, _ = SurfaceDistance(np.asarray(original[0], np.float64), original[1]).query(
        apply_matrix(placement.matrix, vertices), winding=False)
    written = Rotation.from_euler("yx", [draw["yaw_deg"], draw["tilt_deg"]], degrees=True).as_matrix()
    error = Rotation.from_matrix(placement.matrix[:3, :3] @ written).as_euler("yxz", degrees=True)
    return draw["category"], 1e3 * float(np.abs(distance).mean()), error


def main() -> None:
    from darts.body.io import load_body

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, default=Path.home() / ".cache" / "darts" / "import-round-trip")
    parser.add_argument("rows", type=int, nargs="*", help="rows (default: every one under --work)")
    args = parser.parse_args()
    rows = args.rows or sorted(int(p.stem[1:]) for p in args.work.glob("g[0-9][0-9].json"))
    body, means = load_body(None), []
    for row in rows:
        placed = place_row(args.work, row, body)
        if placed is None:
            continue
        category, mean, error = placed
        means.append(mean)
        print(f"{row:2d} {category:20s} {mean:6.2f} mm   yaw {error[0]:+.2f}  pitch {error[1]:+.2f}  roll {error[2]:+.2f} deg",
              flush=True)
    print(f"mean over {len(means)}: {np.mean(means):.2f} mm")


if __name__ == "__main__":
    main()
