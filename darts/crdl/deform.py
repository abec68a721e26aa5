"""Deform a DART with the CRDL: weld its seams, match its feature lines to target loops, solve, and
give every DART vertex its welded vertex's new place (seams, springs and panels carried over).
Everything is in the body's canonical frame (Y up), metres.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from darts.body.model import BodyModel
from darts.crdl import SOLVERS
from darts.crdl.fit import FitSurface
from darts.crdl.layer import Crdl, CrdlResult, CrdlWeights
from darts.crdl.targets import correspond
from darts.dart.model import Dart, welded
from darts.errors import DartsInputError


@dataclass
class WeldedGarment:
    """The DART with its seams closed: vertices [W,3], faces [F,3], the welded index of each DART
    vertex [V], and each feature line as a loop of welded vertices."""

    vertices: np.ndarray
    faces: np.ndarray
    index: np.ndarray
    lines: dict[str, np.ndarray]


def weld_garment(dart: Dart) -> WeldedGarment:
    """Close every seam; a line crossing a seam visits both copies, which become one vertex."""
    vertices, faces, index = welded(dart)
    lines = {}
    for name, loop in dart.lines.items():
        mapped = index[np.asarray(loop)]
        keep = mapped != np.roll(mapped, 1)
        lines[name] = mapped[keep] if keep.any() else mapped[:1]
    return WeldedGarment(vertices, faces, index, lines)


def fit_surface(dart: Dart, body: BodyModel) -> FitSurface:
    """The body in the DART's shape, plus the lower-body hull the DART carries (skirts, dresses)."""
    shaped, _ = body.shaped(dart.body_betas if len(dart.body_betas) else None)
    hull = None if dart.hull_vertices is None else (dart.hull_vertices, dart.hull_faces)
    return FitSurface(shaped[0].double().detach().numpy(), body.faces, hull)


def handle_targets(garment: WeldedGarment, targets: dict[str, np.ndarray], match=correspond,
                   vertices: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(handle vertex indices [H], matched target points [H,3]) over every line with a target, each
    line's vertices (at ``vertices`` [V,3], the garment's rest shape unless given) matched to its
    target loop by ``match`` (arc length, ``correspond``, unless told)."""
    import torch

    vertices = garment.vertices if vertices is None else vertices
    handles, points = [], []
    for name, loop in garment.lines.items():
        if name not in targets:
            continue
        pairing = match(vertices[loop], targets[name])
        handles.append(loop)
        points.append(pairing.points(torch.as_tensor(targets[name])).numpy())
    if not handles:
        raise DartsInputError(None, "no target line matches a line of the garment")
    return np.concatenate(handles), np.concatenate(points)


def deform_dart(dart: Dart, body: BodyModel, targets: dict[str, np.ndarray], solver: str = "local-global",
                weights: CrdlWeights | None = None, silhouette=None, clearance: float | None = None,
                **solve_options) -> tuple[Dart, dict]:
    """The deformed DART and the report (arap_energy, handle_rmse, penetration, iterations, ...).
    With ``clearance`` (metres) target points closer to the fit surface are first moved out to it
    (procedural targets: a hem moved down a leg would otherwise be asked to go inside it)."""
    if solver not in SOLVERS:
        raise DartsInputError(None, f"unknown solver '{solver}' (one of {', '.join(SOLVERS)})")
    garment = weld_garment(dart)
    surface = fit_surface(dart, body)
    if clearance is not None:
        targets = {name: surface.push_out(points, clearance) for name, points in targets.items()}
    handles, points = handle_targets(garment, targets)
    layer = Crdl(garment.vertices, garment.faces, handles, surface, weights, silhouette)
    result: CrdlResult = (layer.solve_local_global if solver == "local-global" else layer.solve_adam)(points, **solve_options)
    if not np.isfinite(result.vertices).all():
        raise RuntimeError("the CRDL produced non-finite vertices")
    deformed = replace(dart, vertices=result.vertices[garment.index].astype(np.float32))
    return deformed, result.report(surface.inside_fraction(result.vertices), solver)
