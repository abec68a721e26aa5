"""Building a garment template from a body: cut, remesh, insert seams, add ease, name feature lines.

Tops, dresses' bodices and pants are cut from the body surface along feature-line fields (head,
hands and feet never included). Skirts and dresses' skirts are one tube cut from the remeshed
convex hull of the lower body (paper, Fig. 3); a dress's bodice and skirt are joined by a strip and
remeshed as one surface. Everything is in the body's canonical frame (Y up), in metres.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from darts.body.model import BodyModel
from darts.errors import DartsInputError
from darts.geometry.levelset import compact, insert_level_set, keep_side
from darts.geometry.mesh import boundary_loops, directed_edges, smoothed_vertex_normals, unique_edges, vertex_normals
from darts.geometry.remesh import remesh
from darts.geometry.slivers import remove_slivers
from darts.templates.categories import CATEGORIES, SIDES, Category, seam_fields
from darts.templates.defaults import (
    CROTCH_EASE_TAPER,
    DEFAULT_EASE,
    DEFAULT_EDGE_LENGTH,
    EASE_RANGE,
    EDGE_LENGTH_RANGE,
    SEAT_EASE_TAPER,
)
from darts.templates.landmarks import Landmarks, above_field, arm_field, below_field, landmarks, neckline_field

#: rings of neighbours a trousers' sitting allowance's offset direction is averaged over (``_add_ease``)
DEEP_EASE_RINGS = 10
#: edges shorter than this fraction of the median edge are collapsed (seam insertion leaves them)
MIN_EDGE_FRACTION = 1 / 3


@dataclass
class Template:
    """A garment surface before it is split into panels. ``seam_edges`` maps seam names to
    undirected edges [E,2]; ``lines`` maps feature-line names to ordered closed vertex loops."""

    category: str
    vertices: np.ndarray
    faces: np.ndarray
    lines: dict[str, np.ndarray]
    seam_edges: dict[str, np.ndarray]
    hull: tuple[np.ndarray, np.ndarray] | None = None
    landmarks: Landmarks | None = field(default=None, repr=False)


def _component_near(vertices, faces, seed: np.ndarray):
    """Keep the connected component nearest to ``seed``."""
    edges = directed_edges(faces)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(vertices),) * 2)
    _, labels = connected_components(graph, directed=False)
    keep = labels[np.argmin(np.linalg.norm(vertices - seed, axis=1))]
    v, f, _ = compact(vertices, faces[labels[faces[:, 0]] == keep])
    return v, f


def _cut(vertices, faces, fields, seed):
    for fn in fields:
        vertices, faces, _ = keep_side(vertices, faces, fn(vertices))
        vertices, faces = _component_near(vertices, faces, seed)
    return vertices, faces


def _body_cuts(category: Category, lm: Landmarks, bottom: float | None) -> list:
    """Fields removing what a top/bodice/pants does not cover."""
    if category.family == "pants":
        hem = category.hem(lm)
        return [lambda p: above_field(lm.waist_y, p), lambda p: below_field(hem, p)]
    cuts = [lambda p: neckline_field(lm, p)]
    position = 0.0 if category.sleeve is None else category.sleeve
    cuts += [lambda p, s=s: arm_field(lm, p, s, position) for s in SIDES]
    cuts.append(lambda p: below_field(bottom, p))
    return cuts


def lower_body_hull(body_vertices: np.ndarray, lm: Landmarks, edge_length: float):
    """The convex hull of the body below the waist, isotropically remeshed (closed)."""
    hull = trimesh.convex.convex_hull(body_vertices[body_vertices[:, 1] < lm.waist_y + 0.03])
    v, f = np.asarray(hull.vertices, np.float64), np.asarray(hull.faces, np.int64)
    # Split the long hull facets first so the remesher projects onto the hull, not across it.
    v, f = trimesh.remesh.subdivide_to_size(v, f, max_edge=edge_length * 2)
    return remesh(v, f, edge_length)


def _bridge(vertices, faces, upper_loop, lower_loop):
    """Join two loops around the vertical axis with a strip of triangles, oriented like ``faces``."""
    centre = vertices[upper_loop].mean(0)

    def ordered(loop):
        """The loop turning counter-clockwise about the axis from its smallest angle, with its
        unwrapped angles (plus the closing one)."""
        angle = np.arctan2(vertices[loop, 0] - centre[0], vertices[loop, 2] - centre[2])
        wrap = lambda d: (d + np.pi) % (2 * np.pi) - np.pi  # noqa: E731
        if wrap(np.diff(np.append(angle, angle[0]))).sum() < 0:
            loop, angle = loop[::-1], angle[::-1]
        start = np.argmin(np.mod(angle, 2 * np.pi))
        loop, angle = np.roll(loop, -start), np.roll(angle, -start)
        unwrapped = np.mod(angle[0], 2 * np.pi) + np.concatenate([[0.0], np.cumsum(wrap(np.diff(angle)))])
        return loop, np.append(unwrapped, unwrapped[0] + 2 * np.pi)

    a, ta = ordered(upper_loop)
    b, tb = ordered(lower_loop)
    i = j = 0
    strip = []
    while i < len(a) or j < len(b):
        if j >= len(b) or (i < len(a) and ta[i + 1] <= tb[j + 1]):
            strip.append((a[i], a[(i + 1) % len(a)], b[j % len(b)]))
            i += 1
        else:
            strip.append((a[i % len(a)], b[(j + 1) % len(b)], b[j]))
            j += 1
    strip = np.array(strip, np.int64)
    half = {(int(x), int(y)) for x, y in directed_edges(faces)}
    if any((int(x), int(y)) in half for x, y in directed_edges(strip)):
        strip = strip[:, ::-1]  # the strip must run against the loops' boundary half-edges
    return np.concatenate([faces, strip])


def _base_surface(category: Category, body_vertices, body_faces, lm: Landmarks, edge_length: float):
    """The garment surface (remeshed) and, for skirts and dresses, the lower-body hull."""
    hem = category.hem(lm)
    seed = lm.j("spine2") if category.family in ("top", "dress") else lm.j("pelvis") - [0, 0.08, 0]
    hull = None
    if category.family in ("top", "pants"):
        v, f = _cut(body_vertices, body_faces, _body_cuts(category, lm, hem), seed)
        return (*remesh(v, f, edge_length), hull)
    hull = lower_body_hull(body_vertices, lm, edge_length)
    top = lm.waist_y if category.family == "skirt" else lm.waist_y - 0.03
    tube = _cut(hull[0], hull[1], [lambda p: above_field(top, p), lambda p: below_field(hem, p)], lm.j("pelvis"))
    if category.family == "skirt":
        return (*remesh(*tube, edge_length), hull)
    bodice = _cut(body_vertices, body_faces, _body_cuts(category, lm, lm.waist_y + 0.03), seed)
    offset = len(bodice[0])
    vertices = np.concatenate([bodice[0], tube[0]])
    faces = np.concatenate([bodice[1], tube[1] + offset])
    bottom = min(boundary_loops(bodice[1]), key=lambda loop: bodice[0][loop, 1].mean())
    top_loop = max(boundary_loops(tube[1]), key=lambda loop: tube[0][loop, 1].mean()) + offset
    faces = _bridge(vertices, faces, bottom, top_loop)
    # Remesh twice: the first pass evens out the strip, the second projects onto a smooth surface.
    return (*remesh(*remesh(vertices, faces, edge_length), edge_length), hull)


def _insert_seams(vertices, faces, category: Category, lm: Landmarks):
    """Insert every seam's zero set as mesh edges and name the edges that carry a seam."""
    fields = seam_fields(category, lm)
    locked = np.zeros(len(vertices), bool)
    locked[np.concatenate(boundary_loops(faces))] = True
    for seam in fields:
        vertices, faces, values = insert_level_set(vertices, faces, seam.field(vertices), locked=locked)
        locked = np.concatenate([locked, np.zeros(len(vertices) - len(locked), bool)]) | (values == 0)
    seams: dict[str, list] = {}
    edges = unique_edges(faces)
    for seam in fields:
        values = seam.field(vertices)
        scale = np.abs(values).max() + 1e-12
        on = (np.abs(values[edges]) < 1e-9 * scale + 1e-12).all(1)
        names = seam.name(0.5 * (vertices[edges[on, 0]] + vertices[edges[on, 1]]))
        for name in np.unique(names):
            if name:
                seams.setdefault(str(name), []).append(edges[on][names == name])
    return vertices, faces, {name: np.concatenate(parts) for name, parts in seams.items()}


def ease_profile(vertices: np.ndarray, ease: float, seat_ease: float | None) -> np.ndarray:
    """Each vertex's ease (m, [V]) for a cut surface ``vertices`` (canonical frame, Y up): ``ease``
    everywhere, or with a ``seat_ease`` (trousers' sitting allowance) ``ease`` at the waist line (the
    top, y_max) growing linearly to ``seat_ease`` at ``SEAT_EASE_TAPER`` below it,
    e(v) = ease + (seat_ease - ease) * clip((y_max - y_v) / SEAT_EASE_TAPER, 0, 1) * clip(|v - c| /
    CROTCH_EASE_TAPER, 0, 1), c the crotch point (the lowest vertex within 1 cm of the mid-plane
    x = 0), which keeps ``ease``: a snug waistband and crotch around room for the seat, thighs and
    knees to fold into."""
    if seat_ease is None:
        return np.full(len(vertices), ease)
    depth = vertices[:, 1].max() - vertices[:, 1]
    middle = np.flatnonzero(np.abs(vertices[:, 0]) < 0.01)
    crotch = vertices[middle[np.argmin(vertices[middle, 1])]]
    away = np.linalg.norm(vertices - crotch, axis=1)
    return ease + (seat_ease - ease) * np.clip(depth / SEAT_EASE_TAPER, 0.0, 1.0) * np.clip(away / CROTCH_EASE_TAPER, 0.0, 1.0)


def _add_ease(vertices, faces, body_vertices, body_faces, ease: np.ndarray, snug: float):
    """Offset each vertex by its ``ease`` (m, [V]): ``snug`` along its normal and the rest
    (``ease - snug``, trousers' sitting allowance) along the normals smoothed over
    ``DEEP_EASE_RINGS`` rings (offset 3 cm along its own normals, the seat's cleft folded the
    trousers' back over itself); then push any vertex still closer than half its ease to the body
    out to its ease along the body normal at its closest point."""
    from darts.geometry.distance import SurfaceDistance  # starts Warp only when needed

    deep = ease - snug
    moved = vertices + snug * vertex_normals(vertices, faces)
    if deep.any():
        moved = moved + deep[:, None] * smoothed_vertex_normals(vertices, faces, DEEP_EASE_RINGS)
    distance = SurfaceDistance(body_vertices, body_faces)
    for _ in range(5):
        signed, closest, normal = distance.query(moved)
        close = signed < 0.5 * ease
        if not close.any():
            break
        moved[close] = closest[close] + ease[close, None] * normal[close]
    return moved


def _wearing_ease(vertices: np.ndarray, faces: np.ndarray, extra: np.ndarray) -> np.ndarray:
    """``vertices`` moved ``extra`` (m, [V]) further off the body along their normals smoothed over
    ``DEEP_EASE_RINGS`` rings: a smooth outward offset, which keeps every edge about as long as it was
    (cut that far along each vertex's own normal, before the slivers were removed, the junctions of
    seams at the shoulders crowded into edges of a millimetre the sliver pass could not remove)."""
    return vertices + extra[:, None] * smoothed_vertex_normals(vertices, faces, DEEP_EASE_RINGS)


def _without_slivers(vertices: np.ndarray, faces: np.ndarray, seams: dict) -> tuple[np.ndarray, np.ndarray, dict]:
    """``remove_slivers`` of every edge under ``MIN_EDGE_FRACTION`` x the median edge."""
    edges = unique_edges(faces)
    median = float(np.median(np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1)))
    vertices, faces, seams, _ = remove_slivers(vertices, faces, seams, MIN_EDGE_FRACTION * median)
    return vertices, faces, seams


def name_loops(category: Category, vertices: np.ndarray, loops: list[np.ndarray]) -> dict[str, np.ndarray]:
    """The category's feature lines among ``loops`` (one per line name), named by where their
    centres sit in the canonical frame (Y up, left +X): cuffs leftmost and rightmost, then the
    neckline highest and the hem lowest (tops, dresses); the waist highest, then the leg hems
    left and right (pants); the waist above the hem (skirts)."""
    centre = {k: vertices[loop].mean(0) for k, loop in enumerate(loops)}
    remaining = set(centre)

    def take(key):
        k = max(remaining, key=key)
        remaining.discard(k)
        return loops[k]

    lines = {}
    if category.family in ("top", "dress"):
        lines["left_cuff"] = take(lambda k: centre[k][0])
        lines["right_cuff"] = take(lambda k: -centre[k][0])
        lines["neckline"] = take(lambda k: centre[k][1])
        lines["hem"] = take(lambda k: -centre[k][1])
    elif category.family == "pants":
        lines["waist"] = take(lambda k: centre[k][1])
        lines["left_hem"] = take(lambda k: centre[k][0])
        lines["right_hem"] = take(lambda k: -centre[k][0])
    else:
        lines["waist"] = take(lambda k: centre[k][1])
        lines["hem"] = take(lambda k: -centre[k][1])
    return lines


def _name_lines(category: Category, vertices: np.ndarray, faces: np.ndarray) -> dict[str, np.ndarray]:
    loops = boundary_loops(faces)
    if len(loops) != len(category.line_names):
        raise RuntimeError(f"{category.id}: expected {len(category.line_names)} boundary loops, got {len(loops)}")
    return name_loops(category, vertices, loops)


def build_template(category_id: str, body: BodyModel, betas=None, edge_length: float = DEFAULT_EDGE_LENGTH,
                   ease: float | None = None, seat_ease: float | None = None) -> Template:
    """The template of ``category_id`` for ``body`` with shape ``betas`` (canonical frame, metres),
    cut ``ease`` off the body (``ease_profile``; None: the category's own, ``Category.ease``), below
    a trousers' waistband ``seat_ease`` (None: the category's own, ``Category.seat_ease``; give
    ``ease`` again for one ease everywhere)."""
    if category_id not in CATEGORIES:
        raise DartsInputError(None, f"unknown category '{category_id}' (known: {', '.join(CATEGORIES)})")
    if not (EDGE_LENGTH_RANGE[0] <= edge_length <= EDGE_LENGTH_RANGE[1]):
        raise DartsInputError(None, f"edge length must be between {EDGE_LENGTH_RANGE[0]:g} and {EDGE_LENGTH_RANGE[1]:g} m, "
                                    f"got {edge_length}")
    category = CATEGORIES[category_id]
    if seat_ease is not None and category.seat_ease is None:
        trousers = ", ".join(name for name, c in CATEGORIES.items() if c.seat_ease is not None)
        raise DartsInputError(None, f"seat_ease is for trousers ({trousers}), not {category_id}")
    ease = category.ease if ease is None else ease
    seat_ease = category.seat_ease if seat_ease is None else seat_ease
    for name, value in (("ease", ease), ("seat ease", seat_ease)):
        if value is not None and not (EASE_RANGE[0] <= value <= EASE_RANGE[1]):
            raise DartsInputError(None, f"{name} must be between {EASE_RANGE[0]:g} and {EASE_RANGE[1]:g} m, got {value}")
    shaped, joints = body.shaped(betas)
    body_vertices, joints = shaped[0].double().detach().numpy(), joints[0].double().detach().numpy()
    try:
        return _cut_from_body(category, body, body_vertices, joints, edge_length, ease, seat_ease)
    except DartsInputError:
        raise
    except (RuntimeError, ValueError) as exc:  # the cut's own checks, on a body no human surface
        raise DartsInputError(None, f"no {category_id} could be cut from the body '{body.name}' ({exc}): its surface "
                                    "is not a smooth human one (tangled, noisy or out of proportion)") from None


def _cut_from_body(category: Category, body: BodyModel, body_vertices: np.ndarray, joints: np.ndarray,
                   edge_length: float, ease: float, seat_ease: float | None) -> Template:
    """``build_template``'s template of ``category`` cut from the shaped body (``body_vertices``,
    ``joints``; canonical frame, metres)."""
    lm = landmarks(body_vertices, joints, body.joint_names)
    vertices, faces, hull = _base_surface(category, body_vertices, body.faces, lm, edge_length)
    vertices, faces, seams = _insert_seams(vertices, faces, category, lm)
    cut = min(ease, DEFAULT_EASE)  # the rest of a larger ease (a wearing ease) once the slivers are gone
    vertices = _add_ease(vertices, faces, body_vertices, body.faces, ease_profile(vertices, cut, seat_ease), cut)
    vertices, faces, seams = _without_slivers(vertices, faces, seams)
    if ease > cut:  # a smooth offset: it shortens an edge only a little, in a hollow (an armpit's)
        extra = ease_profile(vertices, ease, seat_ease) - ease_profile(vertices, cut, seat_ease)
        vertices, faces, seams = _without_slivers(_wearing_ease(vertices, faces, extra), faces, seams)
    return Template(category.id, vertices, faces, _name_lines(category, vertices, faces), seams, hull, lm)
