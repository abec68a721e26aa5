"""How left-right symmetric the CRDL's edits leave a garment (docs/crdl.md, "Targets").

    python scripts/edit_symmetry.py [--count 20] [--collars 2] [--seed 0] [--out docs/data/edit_symmetry.json]

The garments are the import round trip's (``scripts/import_round_trip.py``, the same draws: every
edit of the category's dataset ranges, applied by ``darts.deform``). Each garment, and the shipped
DART it was edited from, is reflected in its own mirror plane (``darts.geometry.symmetry``: the
plane that maps the welded surface onto itself), and every seam vertex of the reflection is
measured to the nearest seam edge of the unreflected garment (``tests.helpers.seam_offsets``): a
symmetric garment's seams land on their mirror twins. Reported per garment: the largest of those
distances and their mean (mm), the template's and the edited garment's, and the surface's own
mirror residual (mean distance of the reflected surface to itself, mm).
"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from import_round_trip import edited_garment, recipe, shipped_garment  # noqa: E402

from tests.helpers import seam_offsets  # noqa: E402

RESULTS = ROOT / "docs" / "data" / "edit_symmetry.json"


def lopsidedness(dart) -> dict:
    """The seams' distances to their mirror twins (max and mean, mm) and the surface's mirror
    residual (mm) of ``dart`` (module docstring)."""
    from darts.crdl.deform import weld_garment
    from darts.geometry.symmetry import mirror_plane

    welded = weld_garment(dart)
    plane = mirror_plane(np.asarray(welded.vertices, np.float64), welded.faces, np.array([1.0, 0.0, 0.0]))
    reflected = replace(dart, vertices=plane.reflect(np.asarray(dart.vertices, np.float64)).astype(np.float32))
    offsets = seam_offsets(reflected, dart)
    return {"seam_max_mm": 1e3 * float(offsets.max()), "seam_mean_mm": 1e3 * float(offsets.mean()),
            "surface_residual_mm": 1e3 * plane.residual}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--collars", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    templates, rows = {}, []
    for k in range(args.count + args.collars):
        draw = recipe(args.seed, k, args.count, args.collars)
        key = (draw["category"], tuple(draw["accessories"]))
        if key not in templates:
            templates[key] = lopsidedness(shipped_garment(draw))
        row = {"index": k, "category": draw["category"], "accessories": draw["accessories"], "edits": draw["edits"],
               "template": templates[key], "edited": lopsidedness(edited_garment(draw))}
        rows.append(row)
        print(f"{k:2d} {draw['category']:20s} template {row['template']['seam_max_mm']:4.1f} mm, "
              f"edited {row['edited']['seam_max_mm']:4.1f} mm", flush=True)
    args.out.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
