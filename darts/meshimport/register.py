"""Registering a category template onto an imported garment mesh with the CRDL (non-rigid ICP).

The template (its seams welded) is deformed by the CRDL (``darts.crdl.layer``) with two kinds of
handle: every feature-line vertex pulled to its match on the mesh's loop of that name, and every
vertex pulled to its closest point on the mesh, moved ``CLEARANCE`` out of the body where it lies
in or near it (multiplier m_r).

The first round is the lines alone, and it is the CRDL edit the mesh's openings came from: for each
line, the length and width edit of ``darts.deform`` (``darts.crdl.targets.length_and_width_edited``: moved along
its axis, let out from its centre) that best takes the template's line onto the mesh's loop
(``fit_loop_edit``; the report's ``line_edits``, cm), pushed ``DEFAULT_EASE`` out of the body and
matched to the line's vertices by arc length, as ``darts.deform`` makes an edit, then solved as it
solves one (``FIRST_ROUND_ITERATIONS``, its start raced between the rest shape and the rest shape
with the line vertices on their targets).
The panels stretch as the garment's own edit stretched them and its seams land where that edit put
them. Matching the template's lines to the mesh's loops directly instead — by angle about each loop's
centre — left every seam vertex within 5 mm on 17 of the round trip's 22 garments (the farthest
5.1-8.3 mm off, at the hems of trousers let out and shortened: a loop let out by a fixed width keeps
its points' angles, but the arc-length match of the edit does not); started from the closest points,
a sleeve 7.5 cm longer left the armhole seams 28 mm off. Each later round then pulls every line
vertex to the mesh's loop at its angle about the loop's centre from where the first round put it
(``darts.crdl.targets.correspond_around``; arc length where a loop is not star-shaped about it)
(multiplier 1), and rounds r recompute the closest points from the last result, with m_r rising
along ``STIFFNESS_SCHEDULE``: the pull is stiff, so the template turns and slides as a whole before
it follows the surface's detail, the fit term keeping it outside the body throughout. A vertex
whose closest point lies on a part of the mesh that faces the other way (vertex normal against the
mesh's face normal there, the mesh's winding oriented to the template's by the median) is not
pulled that round: it is under something folded over the garment — a collar's fall lies on the
shoulders, and pulled onto it the shoulder seams of the round trip's collared tops came 6.1-6.6 mm
off the originals' (now 2.2-2.7 mm). The result
keeps the template's panels, seams, regimes and accessories: it is a full DART in the canonical
frame (Y up, metres).

``placed_on_edit`` refines a placement (``darts.meshimport.align``) on the same first round's
shape: the placement pairs the mesh with the unedited template, which a hem taken up or let out
pulls off; the edit's shape has the hem where the mesh has it.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from darts.body.model import BodyModel
from darts.body.segmentation import PART_NAMES, body_segmentation
from darts.crdl.deform import WeldedGarment, fit_surface, handle_targets, weld_garment
from darts.crdl.fit import FitSurface
from darts.crdl.layer import Crdl, CrdlWeights
from darts.crdl.targets import correspond_around, fit_loop_edit, length_and_width_edited
from darts.dart.model import Dart
from darts.geometry.distance import SurfaceDistance
from darts.geometry.loops import distance_to_loop
from darts.geometry.mesh import vertex_normals
from darts.meshimport.align import (
    ANCHOR_LINES,
    ANCHOR_WEIGHT,
    Alignment,
    apply_matrix,
    best_motion,
    loop_pairs,
    sample_points,
    similarity_matrix,
)
from darts.templates.defaults import DEFAULT_EASE

#: Multipliers (of the handle weight) of the closest-point pull, one CRDL solve per round.
STIFFNESS_SCHEDULE = (0.002, 0.01, 0.03, 0.1, 0.3, 0.3)
#: Metres outside the body (or the skirts' hull) the closest-point targets are kept: the CRDL's margin.
CLEARANCE = CrdlWeights().margin
#: Local-global iterations per round, and at most for the first (the lines alone, to convergence).
ROUND_ITERATIONS = 60
FIRST_ROUND_ITERATIONS = 300


#: How many places a direction's ``worst`` lists.
WORST_PANELS = 3


def distance_stats(values: np.ndarray) -> dict:
    values = np.abs(values)
    return {"mean_mm": 1e3 * float(values.mean()), "p95_mm": 1e3 * float(np.percentile(values, 95)),
            "max_mm": 1e3 * float(values.max())}


def _worst(values: np.ndarray, places: np.ndarray, names: list[str], kind: str) -> list[dict]:
    """Where the farthest of the distances ``values`` [N] (m) lie — those at or beyond their 95th
    percentile: the places (``places`` [N], indices into ``names``, each a ``kind`` of place) holding
    most of them, each with its share of them and its largest distance (mm), most first, at most
    ``WORST_PANELS``."""
    values = np.abs(values)
    far = values >= np.percentile(values, 95)
    found, counts = np.unique(places[far], return_counts=True)
    return [{kind: names[k], "share": float(c / far.sum()), "max_mm": 1e3 * float(values[far & (places == k)].max())}
            for k, c in sorted(zip(found, counts), key=lambda item: -item[1])[:WORST_PANELS]]


def distance_summary(values: np.ndarray, panels: np.ndarray, names: list[str]) -> dict:
    """Mean, 95th percentile and largest of the distances ``values`` [N] (m, reported in mm), and
    ``worst``: the DART panels (``panels`` [N], indices into ``names``) holding the farthest (``_worst``)."""
    return {**distance_stats(values), "worst": _worst(values, panels, names, "panel")}


@dataclass
class RegistrationDistances:
    """Per point, metres: each DART vertex to the mesh (``dart_to_mesh`` [V]) and each mesh vertex to
    the DART (``mesh_to_dart`` [N]), as the report summarises them."""

    dart_to_mesh: np.ndarray
    mesh_to_dart: np.ndarray


def edit_shape(garment: WeldedGarment, surface: FitSurface, loops: dict[str, np.ndarray], held: tuple[str, ...] = ()
               ) -> tuple[dict[str, tuple[float, float]], np.ndarray, np.ndarray]:
    """The registration's first round: each line's fitted edit (``fit_loop_edit``: length, width, metres,
    onto the mesh's loop of its name in ``loops``, canonical frame; the lines ``held`` keep their
    length, only their width is the loop's), the handles (welded vertex indices) of the lines, and the
    welded template's vertices [V,3] under that edit — the edited lines pushed ``DEFAULT_EASE`` out of
    the body, matched by arc length and solved by the CRDL alone (``FIRST_ROUND_ITERATIONS``), as
    ``darts.deform`` makes an edit."""
    centre = garment.vertices.mean(0)
    line_edits = {name: fit_loop_edit(garment.vertices[garment.lines[name]], loop, centre) for name, loop in loops.items()}
    line_edits = {name: (0.0 if name in held else length, width) for name, (length, width) in line_edits.items()}
    edited = {name: surface.push_out(length_and_width_edited(garment.vertices[garment.lines[name]], length, width, centre),
                                     DEFAULT_EASE) for name, (length, width) in line_edits.items()}
    line_handles, edit_points = handle_targets(garment, edited)
    lines_alone = Crdl(garment.vertices, garment.faces, line_handles, surface)
    return line_edits, line_handles, lines_alone.solve_local_global(edit_points, iterations=FIRST_ROUND_ITERATIONS).vertices


def register_template(template: Dart, body: BodyModel, vertices: np.ndarray, faces: np.ndarray,
                      lines: dict[str, np.ndarray], surface: FitSurface | None = None
                      ) -> tuple[Dart, dict, RegistrationDistances]:
    """The template deformed onto the mesh (``vertices`` [N,3] placed on the body, canonical frame;
    ``surface``: the body in the template's pose, by default ``darts.crdl.deform.fit_surface`` at rest;
    ``lines``: its loops by the template's line names), and the report: surface distances both ways
    (``dart_to_mesh``, ``mesh_to_dart``: point to surface, mm, with the panels where the farthest
    5 % lie, ``distance_summary``; a mesh point's panel is that of its closest DART face, and
    ``worst_body_parts`` the body parts its farthest points lie over), each line's residual (distance of the
    DART's line vertices to the mesh's loop, mm), the fraction of vertices inside the body and each
    line's fitted edit (``line_edits``: length and width, cm, as ``darts deform --edit`` takes them); and the
    distances it summarises, per point."""
    garment = weld_garment(template)
    surface = surface or fit_surface(template, body)
    mesh = SurfaceDistance(vertices, faces)
    loops = {name: vertices[loop] for name, loop in lines.items() if name in garment.lines}
    line_edits, line_handles, points = edit_shape(garment, surface, loops)
    _, line_points = handle_targets(garment, loops, match=correspond_around, vertices=points)
    line_points = surface.push_out(line_points, CLEARANCE)
    count = len(garment.vertices)
    handles = np.concatenate([line_handles, np.arange(count)])
    orientation = None  # the mesh's winding against the template's: +1 or -1
    for multiplier in STIFFNESS_SCHEDULE:
        _, closest, mesh_normal = mesh.query(points, winding=False)
        facing = (vertex_normals(points, garment.faces) * mesh_normal).sum(1)
        orientation = orientation or (1.0 if np.median(facing) >= 0 else -1.0)
        layer = Crdl(garment.vertices, garment.faces, handles, surface,
                     handle_weights=np.r_[np.ones(len(line_handles)), np.where(orientation * facing > 0, multiplier, 0.0)])
        closest = surface.push_out(closest, CLEARANCE)
        points = layer.solve_local_global(np.concatenate([line_points, closest]), iterations=ROUND_ITERATIONS).vertices
    if not np.isfinite(points).all():
        raise RuntimeError("the registration produced non-finite vertices")
    dart = replace(template, vertices=points[garment.index].astype(np.float32))
    to_mesh, _, _ = mesh.query(points, winding=False)
    registered = SurfaceDistance(points, garment.faces)
    to_dart, _, _ = registered.query(vertices, winding=False)
    vertex_panel = np.zeros(count, np.int64)
    vertex_panel[garment.faces.reshape(-1)] = np.repeat(template.panel, 3)  # welded faces keep the DART's order
    nearest_face, _ = registered.closest_faces(vertices)
    residuals = {name: distance_stats(distance_to_loop(points[garment.lines[name]], vertices[loop]))
                 for name, loop in lines.items()}
    names = list(template.panel_names)
    body_face, _ = surface.body.closest_faces(vertices)
    body_part = body_segmentation(body)[body.faces[np.maximum(body_face, 0), 0]]
    by_part = _worst(to_dart, body_part, list(PART_NAMES), "body_part")
    report = {"dart_to_mesh": distance_summary(to_mesh, vertex_panel, names),
              "mesh_to_dart": {**distance_summary(to_dart, template.panel[np.maximum(nearest_face, 0)], names),
                               "worst_body_parts": by_part},
              "feature_lines": residuals, "inside_body": surface.inside_fraction(points),
              "line_edits": {name: {"length_cm": 100 * length, "width_cm": 100 * width}
                             for name, (length, width) in line_edits.items()}}
    return dart, report, RegistrationDistances(np.abs(to_mesh[garment.index]), np.abs(to_dart))


#: Rigid ICP steps placing the mesh on its openings' edit (on ``sample_points`` of it, seeded).
PLACEMENT_STEPS = 10


def placed_on_edit(alignment: Alignment, vertices: np.ndarray, template: Dart, surface: FitSurface,
                   lines: dict[str, np.ndarray]) -> Alignment:
    """``alignment`` refined on the shape its openings' edit gives the template. The mesh
    (``vertices`` [N,3], canonical frame, before placing; ``lines``: its loops by line name) placed
    by it; the template deformed by the edit fitted to those loops (``edit_shape``), the lines it
    hangs from (``ANCHOR_LINES``, which ``darts.deform`` only widens) kept at their height; then
    rigid ICP steps minimising sum_i |R x_i + t - c_i|^2 + w sum_j |R y_j + t - z_j|^2 (Umeyama, no
    scale): sampled mesh points x_i and their closest points c_i on that shape, the mesh's anchor loop
    points y_j and the shape's anchor line points z_j matched by arc length (``loop_pairs``,
    w = ``ANCHOR_WEIGHT``). The placement proper pairs the mesh with the unedited template and keeps it
    ``CLEARANCE`` out of the body, so a hem let out or taken up pulls it off: long pants 8.3 cm shorter
    and 4.6 cm wider at the hems came out 5.8 mm low, this puts them within 0.1 mm; refitting the
    anchors' length too let the shape follow the mesh down (3.5 mm after ten steps).
    ``darts.meshimport.pipeline`` keeps it only when its registration fits better."""
    garment = weld_garment(template)
    sample = sample_points(vertices, np.random.default_rng(0))
    placed = apply_matrix(alignment.matrix, vertices)
    loops = {name: placed[loop] for name, loop in lines.items() if name in garment.lines}
    shape_vertices = edit_shape(garment, surface, loops, held=ANCHOR_LINES)[2]
    shape = SurfaceDistance(shape_vertices, garment.faces)
    anchors = {name: loop for name, loop in lines.items() if name in ANCHOR_LINES}
    matrix = alignment.matrix
    for _ in range(PLACEMENT_STEPS):
        moved = apply_matrix(matrix, sample)
        _, closest, _ = shape.query(moved, winding=False)
        loop_points, line_points = loop_pairs(apply_matrix(matrix, vertices), anchors, shape_vertices, garment.lines)
        weights = np.r_[np.ones(len(moved)), np.full(len(loop_points), ANCHOR_WEIGHT)]
        source, target = np.r_[moved, loop_points], np.r_[closest, line_points]
        mirror = None if alignment.mirror is None else (alignment.mirror[0].moved(matrix), alignment.mirror[1])
        matrix = similarity_matrix(*best_motion(source, target, weights, mirror, (1.0, 1.0))) @ matrix
    return replace(alignment, matrix=matrix)
