"""Placing an imported garment on the body: the rigid motion x -> R x + t (or, asked, the similarity
x -> s R x + t; canonical frame, Y up, metres) that puts the mesh's openings where the category
template's feature lines are.

1. For each start (the mesh turned by 0, 90, 180 and 270 degrees about the vertical), the mesh's
   boundary loops are named as the template's are (``name_loops``) and matched point to point to
   the template's lines by arc length; Umeyama's closed form on those pairs gives R, t, and s, the
   estimated scale.
2. Iterative closest points refine it: mesh points paired with their closest points on the
   template surface, the loop pairs (weight ``LOOP_WEIGHT`` per point), and points that land in
   or near the body paired with their place ``CLEARANCE`` outside it (``BODY_WEIGHT``), Umeyama
   again: the placement keeps the garment outside the body.
3. The start with the smallest mean two-way surface distance after a few steps wins and is refined
   further, from the line it hangs from alone (neckline or waist, at ``ANCHOR_WEIGHT`` a point: a
   hem or cuff elsewhere than the template's is the user's design) and the closest half of the
   surface pairs (a longer hem's pairs lie far, at the template's hem: trimmed ICP). A line whose
   loop lies on the garment's own surface (``folded_over``: a collar's outer edge, which is the
   mesh's neckline opening) is not paired so; instead the template's line is paired with the
   closest points of the mesh's surface (the neckline where the collar is sewn on). A collared
   T-shirt anchored on its collar's edge was placed 5.7 mm off on average, by its surface alone
   2.4 mm, so 0.6 mm (a collared long-sleeve shirt 1.7, 0.8 and 0.8 mm). A top with a hem 4.5 cm
   and sleeves 7.5 cm longer than the template's: every loop at the loops' weight placed
   it 13 mm too high, this 1 mm; shorts 5.4 cm shorter: 19 mm too low, this 0.2 mm.
   **Mirror plane.** Garments are left-right symmetric, and so are the templates (their reflected
   points lie 0.4-0.5 mm from their surfaces; the round trip's edited, remeshed garments 0.4-0.8
   mm). When the mesh is too (``darts.geometry.symmetry``, within ``MIRROR_RESIDUAL``), every final
   step is the best placement that keeps its mirror plane parallel to the template's
   (``umeyama_mirrored``): the turn about the vertical and the roll come from the plane, the tilt
   and the translation from the pairs. A short skirt flared 12 cm wider was placed turned 7 deg
   and tilted 2 (6.5 mm off on average): its round waist does not fix the turn, and its flare pairs
   with the narrower template's surface unevenly; so 0.6 deg (1.8 mm), and with the surface pairs
   trimmed to the closest half (``TRIMMED_SHARE``; was 80 %) 0.1 deg (0.5 mm). Over the round
   trip's 20 garments without a collar the placement alone is 0.31 mm off on average (was 0.68).
   Pairing each waist point with the closest point of the template's waist instead (free to slide
   along it) turned that skirt 2.6 deg but placed four other skirts and flared dresses 1-4 mm
   worse (a long skirt 14 cm wider: 0.11 -> 3.97 mm), so the arc-length pairs stay.
4. Placement is rigid by default (s = 1, the garment keeps its size: its units are known, and a
   hem, sleeve or width that differs from the template's is the user's design, which a fitted
   scale would undo: a top with sleeves 10 cm shorter was scaled up 8.5 %), or, with
   ``fit_scale``, a similarity (a garment made for another avatar, resized to this body).
The scale fitted while screening (``Alignment.estimated_scale``) is kept within ``SCALE_RANGE``; a
mesh that needs more was modelled in other units.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation

from darts.crdl.targets import correspond
from darts.geometry.distance import SurfaceDistance
from darts.geometry.loops import resample_loop
from darts.geometry.mesh import unique_edges
from darts.geometry.symmetry import MirrorPlane, mirror_plane, plane_axes
from darts.templates.build import name_loops
from darts.templates.categories import Category

SCALE_RANGE = (0.5, 2.0)
LOOP_SAMPLES = 48
#: Weight of one loop point against one surface point in the refinement.
LOOP_WEIGHT = 4.0
#: Weight of a point within CLEARANCE of the body (paired with its place CLEARANCE outside).
BODY_WEIGHT = 1000.0
CLEARANCE = 0.002
ICP_ITERATIONS = 40
#: The lines a garment hangs from, which alone place it in the final steps, and the weight of each
#: of their points there (against one surface point's 1: the line fixes the translation, the
#: surface the turn about it).
ANCHOR_LINES = ("neckline", "waist")
ANCHOR_WEIGHT = 200.0
#: An anchor line whose points lie (median) within FOLD_DISTANCE of the garment's own surface
#: farther than FOLD_GEODESIC from it along the mesh is the edge of something folded over the
#: garment (a collar's edge lies on the shirt: 6-7 mm; openings: 34-45 mm over the round trip's
#: 22 garments and Newton's shirt), not where the garment hangs from.
FOLD_GEODESIC = 0.04
FOLD_DISTANCE = 0.015
#: The final steps' surface pairs up to this percentile of distance count (placement alone over the
#: round trip's 20 garments without a collar, with the mirror plane: 35 % 0.29 mm, 50 % 0.31,
#: 65 % 0.33, 80 % 0.41 mm off on average; a flared skirt 0.3, 0.5, 0.8 and 1.8 mm).
TRIMMED_SHARE = 50
#: ICP steps every start gets before the closest one alone goes on.
SCREEN_ITERATIONS = 5
#: Iterations between re-pairings of the loops (arc-length matching is the costly part).
PAIRING_INTERVAL = 5
SURFACE_SAMPLES = 3000
#: A mesh (and template) is taken as left-right symmetric when its reflected points lie this close
#: (mean, metres) to its surface (``darts.geometry.symmetry``), and its plane is used when the
#: screened placement puts it within MIRROR_TURN degrees of the template's.
MIRROR_RESIDUAL = 0.002
MIRROR_TURN = 20.0


@dataclass
class Alignment:
    """``matrix`` [4,4] (canonical mesh -> on the body), the mesh's loops by line name, the mean
    two-way surface distance (metres) between the placed mesh and the template, the ``scale`` the
    matrix applies and the one the screening's similarity found (``estimated_scale``: how far the
    units are off), and the anchor lines whose loops are a folded-over edge (``folded_over``):
    placed by the template's line put on the mesh's surface, not by the loop, and left out of the
    registration's line targets; ``mirror``: the mesh's mirror plane (canonical frame, before
    placing) and the template's, where the placement kept them parallel (``umeyama_mirrored``)."""

    matrix: np.ndarray
    lines: dict[str, np.ndarray]
    distance: float
    scale: float
    estimated_scale: float
    folded: tuple[str, ...] = ()
    mirror: tuple[MirrorPlane, MirrorPlane] | None = None

    @property
    def line_targets(self) -> dict[str, np.ndarray]:
        """The loops the registration pulls the template's lines onto: every named one but the folded."""
        return {name: loop for name, loop in self.lines.items() if name not in self.folded}


def umeyama(source: np.ndarray, target: np.ndarray, weights: np.ndarray | None = None,
            scale_range: tuple[float, float] = SCALE_RANGE) -> tuple[float, np.ndarray, np.ndarray]:
    """(s, R, t) minimising sum_i w_i |s R x_i + t - y_i|^2 (Umeyama 1991): R by weighted Kabsch
    on the centred points, s = sum w (R x_c).y_c / sum w |x_c|^2 clipped to ``scale_range``,
    t = mean(y) - s R mean(x)."""
    w = np.ones(len(source)) if weights is None else np.asarray(weights, np.float64)
    w = w / w.sum()
    mean_x, mean_y = w @ source, w @ target
    xc, yc = source - mean_x, target - mean_y
    rotation, _ = Rotation.align_vectors(yc, xc, weights=w)
    turned = rotation.apply(xc)
    scale = float(np.clip((w * (turned * yc).sum(1)).sum() / (w * (xc * xc).sum(1)).sum(), *scale_range))
    matrix = rotation.as_matrix()
    return scale, matrix, mean_y - scale * matrix @ mean_x


def similarity_matrix(scale: float, rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """The 4x4 matrix of x -> scale R x + t."""
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = scale * rotation, translation
    return out


def apply_matrix(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``points`` [N,3] moved by the 4x4 affine ``matrix`` (column vectors: x' = M x)."""
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def folded_over(vertices: np.ndarray, faces: np.ndarray, loop: np.ndarray) -> bool:
    """Whether the boundary ``loop`` lies on the garment's own surface (``FOLD_DISTANCE``): the median
    of its vertices' distances to the mesh vertices more than ``FOLD_GEODESIC`` from the loop along
    the mesh's edges (Dijkstra)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra
    from scipy.spatial import cKDTree

    edges = unique_edges(np.asarray(faces))
    lengths = np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1)
    graph = coo_matrix((lengths, (edges[:, 0], edges[:, 1])), shape=(len(vertices),) * 2).tocsr()
    far = ~np.isfinite(dijkstra(graph, directed=False, indices=loop, limit=FOLD_GEODESIC, min_only=True))
    if not far.any():
        return False
    return float(np.median(cKDTree(vertices[far]).query(vertices[loop])[0])) < FOLD_DISTANCE


def _folded_anchors(vertices: np.ndarray, faces: np.ndarray, lines: dict[str, np.ndarray]) -> tuple[str, ...]:
    """The ``ANCHOR_LINES`` among ``lines`` whose loops are ``folded_over``."""
    return tuple(name for name in ANCHOR_LINES if name in lines and folded_over(vertices, faces, lines[name]))


def loop_pairs(vertices, lines, template_vertices, template_lines) -> tuple[np.ndarray, np.ndarray]:
    """Mesh loop points and the template line points they match (arc length, best start)."""
    if not lines:
        return np.zeros((0, 3)), np.zeros((0, 3))
    sources, targets = [], []
    centre = vertices.mean(0)
    for name, loop in lines.items():
        template = resample_loop(template_vertices[template_lines[name]], LOOP_SAMPLES, centre)
        points = resample_loop(vertices[loop], LOOP_SAMPLES, centre)
        match = correspond(template, points, shifts=LOOP_SAMPLES)
        sources.append((1 - match.weight)[:, None] * points[match.first] + match.weight[:, None] * points[match.second])
        targets.append(template)
    return np.concatenate(sources), np.concatenate(targets)


def sample_points(points: np.ndarray, rng) -> np.ndarray:
    """At most SURFACE_SAMPLES of ``points``, drawn without replacement."""
    return points[rng.choice(len(points), min(SURFACE_SAMPLES, len(points)), replace=False)]


def _yaw(degrees: float, about: np.ndarray) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = Rotation.from_euler("y", degrees, degrees=True).as_matrix()
    matrix[:3, 3] = about - matrix[:3, :3] @ about
    return matrix


def _inside_pairs(fit, points: np.ndarray, placed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ``points`` whose placement lies within ``CLEARANCE`` of the body (or inside it), and the
    places ``CLEARANCE`` outside it they are paired with."""
    signed, closest, normal = fit.query(placed, winding=False)
    near = signed < CLEARANCE
    return points[near], closest[near] + CLEARANCE * normal[near]


def _least_turn(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The rotation [3,3] of least angle taking the unit vector ``source`` to ``target``."""
    axis = np.cross(source, target)
    angle = np.arctan2(np.linalg.norm(axis), source @ target)
    return Rotation.from_rotvec(axis / max(np.linalg.norm(axis), 1e-12) * angle).as_matrix()


def umeyama_mirrored(source: np.ndarray, target: np.ndarray, weights: np.ndarray,
                     mirror: tuple[MirrorPlane, MirrorPlane],
                     scale_range: tuple[float, float] = SCALE_RANGE) -> tuple[float, np.ndarray, np.ndarray]:
    """``umeyama`` restricted to the rotations that keep the source's mirror plane (``mirror[0]``)
    parallel to the target's (``mirror[1]``, normals oriented alike): R = T(theta) R0, R0 the least
    turn from one normal n0 to the other n1 and T(theta) a turn about n1. Theta, the scale and the
    translation in the plane are the two-dimensional Umeyama of the turned points' in-plane
    coordinates; the translation along n1 matches the weighted means there (the plane's offset is
    left to the pairs: an edited garment's plane lies up to 1 mm off its template's)."""
    source_plane, target_plane = mirror
    normal = target_plane.normal
    least_turn = _least_turn(source_plane.normal, normal)
    turned = source @ least_turn.T
    basis = np.stack([*plane_axes(normal), normal])
    x, y = (turned @ basis.T)[:, :2], (target @ basis.T)[:, :2]
    w = weights / weights.sum()
    xc, yc = x - w @ x, y - w @ y
    theta = np.arctan2((w * (xc[:, 0] * yc[:, 1] - xc[:, 1] * yc[:, 0])).sum(), (w * (xc * yc).sum(1)).sum())
    in_plane = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    scale = float(np.clip((w * ((xc @ in_plane.T) * yc).sum(1)).sum() / (w * (xc * xc).sum(1)).sum(), *scale_range))
    shift = w @ y - scale * in_plane @ (w @ x)
    about_normal = np.eye(3)
    about_normal[:2, :2] = in_plane
    rotation = basis.T @ about_normal @ basis @ least_turn
    along = w @ (target @ normal) - scale * (w @ (turned @ normal))
    translation = basis[:2].T @ shift + along * normal
    return scale, rotation, translation


def best_motion(source: np.ndarray, target: np.ndarray, weights: np.ndarray,
                mirror: tuple[MirrorPlane, MirrorPlane] | None,
                scale_range: tuple[float, float]) -> tuple[float, np.ndarray, np.ndarray]:
    """(s, R, t): ``umeyama`` of the weighted pairs, or ``umeyama_mirrored`` keeping the ``mirror``
    planes parallel where they are given."""
    if mirror is None:
        return umeyama(source, target, weights, scale_range)
    return umeyama_mirrored(source, target, weights, mirror, scale_range)


def _refine(similarity, turned, turned_sample, lines, template_surface, template_vertices, template_lines, fit,
            iterations: int, scale_range: tuple[float, float] = SCALE_RANGE, final: bool = False,
            folded: tuple[str, ...] = (), faces: np.ndarray | None = None,
            mirror: tuple[MirrorPlane, MirrorPlane] | None = None):
    """``iterations`` ICP steps from ``similarity`` (s, R, t) of the turned mesh; every fit is from
    the turned mesh itself, so the scale stays within ``scale_range`` ((1, 1): rigid). The
    ``final`` steps pair only the ``ANCHOR_LINES`` of the loops given (and, for the ``folded``
    ones, the template's line with the mesh's surface, ``faces``) and leave out the surface pairs
    beyond the ``TRIMMED_SHARE`` percentile of distance (trimmed ICP). With ``mirror`` (the mesh's
    and the template's mirror planes) each step is the best placement that puts one plane on the
    other (``umeyama_mirrored``)."""
    if final:  # lengths and widths are the design: only the line the garment hangs from places it
        lines = {name: loop for name, loop in lines.items() if name in ANCHOR_LINES and name not in folded}
    # a folded line (a collar's edge): the template's line put on the mesh's surface, where the collar
    # is sewn on; closest points commute with the placement, so the turned mesh's surface serves
    line_points = np.concatenate([template_vertices[template_lines[name]] for name in folded] or [np.zeros((0, 3))])
    folded_surface = SurfaceDistance(turned, faces) if folded else None
    s, r, t = similarity
    for step in range(iterations):
        placed = similarity_matrix(s, r, t)
        gap, closest, _ = template_surface.query(apply_matrix(placed, turned_sample), winding=False)
        if step % PAIRING_INTERVAL == 0:
            loop_source, loop_target = loop_pairs(apply_matrix(placed, turned), lines, template_vertices, template_lines)
            loop_source = apply_matrix(np.linalg.inv(placed), loop_source)
        on_mesh = np.zeros((0, 3)) if folded_surface is None else \
            folded_surface.query(apply_matrix(np.linalg.inv(placed), line_points), winding=False)[1]
        pairs_source, pairs_target = np.r_[loop_source, on_mesh], np.r_[loop_target, line_points]
        inside, outside = _inside_pairs(fit, turned_sample, apply_matrix(placed, turned_sample))
        surface_weights = np.ones(len(turned_sample))
        if final:  # what the template lacks (a longer hem or sleeve) pairs far away: left out
            surface_weights[np.abs(gap) > np.percentile(np.abs(gap), TRIMMED_SHARE)] = 0.0
        weights = np.r_[surface_weights, np.full(len(pairs_source), ANCHOR_WEIGHT if final else LOOP_WEIGHT),
                        np.full(len(inside), BODY_WEIGHT)]
        source, target = np.r_[turned_sample, pairs_source, inside], np.r_[closest, pairs_target, outside]
        s, r, t = best_motion(source, target, weights, mirror, scale_range)
    return s, r, t


def align_to_template(vertices: np.ndarray, faces: np.ndarray, loops: list[np.ndarray], category: Category,
                      template_vertices: np.ndarray, template_faces: np.ndarray,
                      template_lines: dict[str, np.ndarray], fit, seed: int = 0, fit_scale: bool = False) -> Alignment:
    """The best placement of the mesh (canonical frame, its ``loops`` one per line of ``category``)
    on the template (welded vertices, faces, lines) and outside ``fit`` (the body's FitSurface);
    see the module docstring. Each start gets ``SCREEN_ITERATIONS`` steps; the closest goes on to
    ``ICP_ITERATIONS``; rigid unless ``fit_scale``. The scale of the loops' similarity at each start
    is the ``estimated_scale``."""
    template_surface = SurfaceDistance(template_vertices, template_faces)
    rng = np.random.default_rng(seed)
    sample, template_sample = sample_points(vertices, rng), sample_points(template_vertices, rng)

    def placement(start, similarity, lines, estimated_scale):
        matrix = similarity_matrix(*similarity) @ start
        distance = _two_way_distance(apply_matrix(matrix, sample), template_surface, template_sample,
                                     SurfaceDistance(apply_matrix(matrix, vertices), faces))
        return Alignment(matrix, lines, distance, similarity[0], estimated_scale)

    scale_range = SCALE_RANGE if fit_scale else (1.0, 1.0)
    screened = []
    for degrees in (0.0, 90.0, 180.0, 270.0):
        start = _yaw(degrees, vertices.mean(0))
        turned, turned_sample = apply_matrix(start, vertices), apply_matrix(start, sample)
        lines = name_loops(category, turned, loops)
        pairs = loop_pairs(turned, lines, template_vertices, template_lines)
        estimated_scale = umeyama(*pairs)[0]
        similarity = _refine(umeyama(*pairs, scale_range=scale_range), turned, turned_sample, lines, template_surface,
                             template_vertices, template_lines, fit, SCREEN_ITERATIONS, scale_range)
        screened.append((placement(start, similarity, lines, estimated_scale), start, similarity, turned, turned_sample))
    best, start, similarity, turned, turned_sample = min(screened, key=lambda entry: entry[0].distance)
    folded = _folded_anchors(vertices, faces, best.lines)
    mirror = _mirrors(turned, faces, turned_sample, similarity, template_vertices, template_faces)
    similarity = _refine(similarity, turned, turned_sample, best.lines, template_surface, template_vertices,
                         template_lines, fit, ICP_ITERATIONS - SCREEN_ITERATIONS, scale_range, final=True,
                         folded=folded, faces=faces, mirror=mirror)
    mirror = None if mirror is None else (mirror[0].moved(np.linalg.inv(start)), mirror[1])
    return replace(placement(start, similarity, best.lines, best.estimated_scale), folded=folded, mirror=mirror)


def _mirrors(turned, faces, turned_sample, similarity, template_vertices, template_faces):
    """The turned mesh's and the template's mirror planes, the mesh's searched from the one the
    screened ``similarity`` puts on the template's left-right plane; None unless both are
    symmetric (``MIRROR_RESIDUAL``) and the planes lie within ``MIRROR_TURN`` of each other."""
    template_plane = mirror_plane(template_vertices, template_faces, np.array([1.0, 0.0, 0.0]))
    mesh_plane = mirror_plane(turned, faces, similarity[1].T @ template_plane.normal, turned_sample)
    alike = float(similarity[1] @ mesh_plane.normal @ template_plane.normal)
    if alike < 0:  # the same plane, its normal turned the template's way
        mesh_plane = replace(mesh_plane, normal=-mesh_plane.normal, offset=-mesh_plane.offset)
    symmetric = max(mesh_plane.residual, template_plane.residual) <= MIRROR_RESIDUAL
    return (mesh_plane, template_plane) if symmetric and np.degrees(np.arccos(min(1.0, abs(alike)))) <= MIRROR_TURN \
        else None


def _two_way_distance(placed_sample, template_surface, template_sample, placed_surface) -> float:
    """Mean of the mesh-to-template and template-to-mesh point-to-surface distances (metres)."""
    there, _, _ = template_surface.query(placed_sample, winding=False)
    back, _, _ = placed_surface.query(template_sample, winding=False)
    return 0.5 * float(np.abs(there).mean() + np.abs(back).mean())


def naming_only(vertices: np.ndarray, faces: np.ndarray, loops: list[np.ndarray], category: Category,
                matrix: np.ndarray, template, seed: int = 0) -> Alignment:
    """The placement ``matrix`` as given (``--transform``): loops named where it puts them, and its
    distance to the ``template`` (a WeldedGarment) measured as ``align_to_template`` does."""
    rng = np.random.default_rng(seed)
    placed = apply_matrix(matrix, vertices)
    sample, template_sample = sample_points(placed, rng), sample_points(template.vertices, rng)
    distance = _two_way_distance(sample, SurfaceDistance(template.vertices, template.faces), template_sample,
                                 SurfaceDistance(placed, faces))
    scale = float(np.cbrt(np.linalg.det(matrix[:3, :3])))
    lines = name_loops(category, placed, loops)
    return Alignment(matrix, lines, distance, scale, scale, _folded_anchors(placed, faces, lines))
