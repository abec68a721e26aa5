"""The paper's Fig. 6 on the shipped garments: the same procedural targets reached by handle-based
Laplacian deformation, libigl's ARAP with hard handles, the CRDL's local-global solver without the
body (like for like with libigl), the CRDL with Adam and the CRDL local-global.

Prints the table of docs/crdl.md, keeps the numbers in docs/data/crdl_comparison.json and draws
docs/images/crdl_comparison.png. Needs the ``compare`` extra (libigl). One core (torch threads 1).
Every method is scored the same way: ARAP energy (Eq. 2, our cotangent weights, best rotations),
handle RMSE against the arc-length targets, fraction of vertices inside the body, wall time.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from darts.body.io import load_body
from darts.crdl.arap import arap_energy, arap_system
from darts.crdl.deform import fit_surface, handle_targets, weld_garment
from darts.crdl.layer import Crdl
from darts.crdl.targets import edit_targets, parse_edit
from darts.dart.io import load_dart
from darts.shipped import resolve_garment, shipped_garments
from darts.templates.defaults import DEFAULT_EASE

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "data" / "crdl_comparison.json"
PICTURE = ROOT / "docs" / "images" / "crdl_comparison.png"
METHODS = ("laplacian", "libigl-arap", "crdl-no-fit", "crdl-adam", "crdl-local-global")
#: One procedural target per category (lengthen, shorten, widen).
TARGETS = {
    "short-sleeve-top": ["hem=+0.05", "sleeve=-0.03", "neckline=+0.02"],
    "long-sleeve-top": ["hem=+0.05", "sleeve=-0.05", "neckline=+0.02"],
    "sleeveless-top": ["hem=+0.05", "neckline=+0.02"],
    "short-sleeve-dress": ["hem=+0.08", "neckline=+0.02"],
    "long-sleeve-dress": ["hem=+0.08", "sleeve=-0.05"],
    "sleeveless-dress": ["hem=+0.08", "hem_width=+0.04"],
    "long-pants": ["hem=-0.10", "waist=+0.02"],
    "short-pants": ["hem=+0.05", "waist=+0.02"],
    "long-skirt": ["hem=+0.10", "hem_width=+0.05"],
    "short-skirt": ["hem=+0.08", "hem_width=+0.04", "waist=+0.02"],
}
PICTURED = ("short-sleeve-top", "long-skirt")


def laplacian_deformation(system, handles: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """Handle-based Laplacian editing: L p = L r on the free vertices, handles at their targets."""
    from scipy.sparse.linalg import splu

    laplacian = system.laplacian().tocsr()
    rest = system.rest.numpy()
    free = np.setdiff1d(np.arange(len(rest)), handles)
    p = rest.copy()
    p[handles] = targets
    rhs = (laplacian @ rest)[free] - laplacian[free][:, handles] @ targets
    p[free] = splu(laplacian[free][:, free].tocsc()).solve(rhs)
    return p


def libigl_arap(vertices: np.ndarray, faces: np.ndarray, handles: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """libigl's ARAP with the handles as hard constraints (100 local-global iterations)."""
    import igl

    data = igl.ARAPData()
    data.max_iter = 100
    igl.arap_precomputation(vertices, faces.astype(np.int64), 3, handles.astype(np.int32), data)
    return igl.arap_solve(targets, data, vertices.copy())


def run_garment(name: str, body) -> tuple[dict, dict]:
    dart = load_dart(resolve_garment(name))
    garment = weld_garment(dart)
    surface = fit_surface(dart, body)
    edits = [parse_edit(text) for text in TARGETS[dart.category]]
    targets = {line: surface.push_out(points, DEFAULT_EASE)
               for line, points in edit_targets(dart.category, garment.vertices, garment.lines, edits).items()}
    handles, points = handle_targets(garment, targets)
    system = arap_system(garment.vertices, garment.faces)
    results, shapes = {}, {}
    for method in METHODS:
        start = time.perf_counter()
        if method == "laplacian":
            p = laplacian_deformation(system, handles, points)
        elif method == "libigl-arap":
            p = libigl_arap(garment.vertices, garment.faces, handles, points)
        elif method == "crdl-no-fit":  # the same solver without the body: the like-for-like ARAP comparison
            p = Crdl(garment.vertices, garment.faces, handles).solve_local_global(points).vertices
        else:
            layer = Crdl(garment.vertices, garment.faces, handles, surface)
            p = (layer.solve_adam(points, progress=True) if method == "crdl-adam" else layer.solve_local_global(points)).vertices
        wall = time.perf_counter() - start
        tensor = torch.as_tensor(p)
        results[method] = {
            "arap_energy": float(arap_energy(system, tensor)),
            "handle_rmse": float(np.sqrt(np.square(p[handles] - points).sum(1).mean())),
            "penetration": surface.inside_fraction(p),
            "wall_seconds": wall,
        }
        shapes[method] = p
        print(name, method, json.dumps(results[method]), flush=True)
    row = {"garment": name, "category": dart.category, "vertices": len(garment.vertices),
           "edits": TARGETS[dart.category], "methods": results}
    return row, {"faces": garment.faces, "shapes": shapes, "surface": surface}


def markdown(rows: list[dict]) -> str:
    lines = ["| garment (vertices) | edits | method | ARAP energy | handle RMSE (mm) | penetration | wall (s) |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        for index, (method, r) in enumerate(row["methods"].items()):
            head = f"{row['garment']} ({row['vertices']:,})" if index == 0 else ""
            edits = " ".join(row["edits"]) if index == 0 else ""
            lines.append(f"| {head} | {edits} | {method} | {r['arap_energy']:.4g} | {1e3 * r['handle_rmse']:.2f} | "
                         f"{100 * r['penetration']:.2f} % | {r['wall_seconds']:.2f} |")
    return "\n".join(lines)


def draw(pictures: dict, body_vertices: np.ndarray, body_faces: np.ndarray, path: Path) -> None:
    """One row per pictured garment, one column per method; vertices inside the body in red."""
    from matplotlib.figure import Figure

    from darts.render import FRONT, draw_mesh

    figure = Figure(figsize=(3.2 * len(METHODS), 3.6 * len(pictures)))
    for row, (name, picture) in enumerate(pictures.items()):
        for column, method in enumerate(METHODS):
            ax = figure.add_subplot(len(pictures), len(METHODS), row * len(METHODS) + column + 1)
            p = picture["shapes"][method]
            inside = picture["surface"].body.query(p)[0] < 0
            garment_colors = np.where(inside[picture["faces"]].any(1)[:, None], [0.85, 0.1, 0.1], [0.3, 0.55, 0.85])
            vertices = np.concatenate([body_vertices, p])
            faces = np.concatenate([body_faces, picture["faces"] + len(body_vertices)])
            colors = np.concatenate([np.full((len(body_faces), 3), 0.75), garment_colors])
            draw_mesh(ax, vertices, faces, colors, *FRONT, two_sided=True)
            ax.set_title(f"{name}\n{method}", fontsize=9)
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--garments", default=",".join(TARGETS), help="comma-separated shipped garment names")
    args = parser.parse_args()
    torch.set_num_threads(1)
    body = load_body()
    rows, pictures = [], {}
    for name in args.garments.split(","):
        if name not in shipped_garments():
            raise SystemExit(f"unknown shipped garment '{name}'")
        row, picture = run_garment(name, body)
        rows.append(row)
        if name in PICTURED:
            pictures[name] = picture
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(rows, indent=1))
    if pictures:
        shaped, _ = body.shaped()
        draw(pictures, shaped[0].double().numpy(), body.faces, PICTURE)
    print(markdown(rows))


if __name__ == "__main__":
    main()
