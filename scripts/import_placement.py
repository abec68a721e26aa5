"""The placement alone of the import round trip's garments (docs/import.md, ``darts.meshimport.align``):
each written file read, repaired and placed on its category's shipped template (arms at rest, as
the round trip's garments are), and that placement refined on its openings' fitted edit
(``darts.meshimport.register.placed_on_edit``, which the import registers as one more candidate),
each measured against the edited garment it was made from.

    python scripts/import_placement.py [--work ~/.cache/darts/import-round-trip] [ROW ...]

Needs the files ``scripts/import_round_trip.py`` wrote under ``--work`` (garments with an
accessory are left out: their template is built, not shipped). Per row and placement: the mean
unsigned distance of the placed file's vertices to the original's welded surface (mm), their mean
distance from where the rigid motion the file was written with says they belong (mm: a garment slid
along itself, which the surface distance hardly sees, counts here), and the rotation error against
that motion (degrees, as yaw about Y, pitch about X, roll about Z). No output file: the numbers
quoted in ``align.py``, ``register.py`` and docs/import.md.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def place_row(work: Path, row: int, body) -> tuple[str, list[tuple[float, float, np.ndarray]]] | None:
    """(category, [(surface distance mm, vertex offset mm, yaw/pitch/roll error deg)] of the placement
    and of it refined on the edit) of round-trip garment ``row``."""
    from scipy.spatial.transform import Rotation

    from darts.crdl.deform import weld_garment
    from darts.crdl.fit import FitSurface
    from darts.dart.io import load_dart
    from darts.dart.model import welded
    from darts.geometry.distance import SurfaceDistance
    from darts.meshimport.align import align_to_template, apply_matrix
    from darts.meshimport.pose import lower_arms
    from darts.meshimport.read import read_garment_mesh
    from darts.meshimport.register import placed_on_edit
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
    refined = placed_on_edit(placement, vertices, shipped, fit, placement.line_targets)
    original = welded(load_dart(stem.with_suffix(".original.npz")))
    surface = SurfaceDistance(np.asarray(original[0], np.float64), original[1])
    written = Rotation.from_euler("yx", [draw["yaw_deg"], draw["tilt_deg"]], degrees=True).as_matrix()
    belong = (vertices - draw["move_m"]) @ written  # x = R y + move, so y = R^T (x - move)
    measured = []
    for alignment in (placement, refined):
        placed = apply_matrix(alignment.matrix, vertices)
        distance, _, _ = surface.query(placed, winding=False)
        error = Rotation.from_matrix(alignment.matrix[:3, :3] @ written).as_euler("yxz", degrees=True)
        measured.append((1e3 * float(np.abs(distance).mean()), 1e3 * float(np.linalg.norm(placed - belong, axis=1).mean()),
                         error))
    return draw["category"], measured


def main() -> None:
    from darts.body.io import load_body

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, default=Path.home() / ".cache" / "darts" / "import-round-trip")
    parser.add_argument("rows", type=int, nargs="*", help="rows (default: every one under --work)")
    args = parser.parse_args()
    rows = args.rows or sorted(int(p.stem[1:]) for p in args.work.glob("g[0-9][0-9].json"))
    body, totals = load_body(None), []
    for row in rows:
        placed = place_row(args.work, row, body)
        if placed is None:
            continue
        category, measured = placed
        totals.append([(distance, offset) for distance, offset, _ in measured])
        print(f"{row:2d} {category:18s}" + " | ".join(
            f"{name} {distance:5.2f} mm, off {offset:5.2f} mm, yaw {error[0]:+.2f} pitch {error[1]:+.2f} roll {error[2]:+.2f} deg"
            for name, (distance, offset, error) in zip(("placed", "on its edit"), measured)), flush=True)
    means = np.mean(totals, axis=0)
    print(f"mean over {len(totals)}: placed {means[0, 0]:.2f} mm (off {means[0, 1]:.2f} mm); "
          f"on its edit {means[1, 0]:.2f} mm (off {means[1, 1]:.2f} mm)")


if __name__ == "__main__":
    main()
