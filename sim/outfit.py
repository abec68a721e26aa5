"""Outfits: several DARTs on one body in one simulation, in layer order (inner first).

The garments become one ``ClothModel``: their particles, constraints and loops side by side (each
garment's indices shifted past the ones before), each edge and hinge with its own garment's
stiffness, each particle with its layer. Self-contact then covers garment against garment as well
as each garment against itself: ``sim.engine.solvers.base.exclusion_rest`` moves every layer far from the
others when it tells rest neighbours apart, so two garments lying on each other always collide.
Thickness and friction are one per model: the outfit takes the largest of its garments'.

Templates are all cut at the same ease from the body, so an outer garment lies on the inner one
where they overlap. ``separate_layers`` starts them apart: each outer particle within
``COVER`` of an inner garment is lifted along the body's normal until it is ``LAYER_GAP``
thicknesses outside the inner surface, and the lift is spread a few edge rings so that it fades
instead of stepping. The lifted shape is the outer garment's rest shape too (an outer garment
is cut larger where it covers another), so the drape starts without intersections and without
stretch. Everything here is in the body's canonical frame (Y up, metres).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from darts.dart.model import Dart
from darts.errors import DartsInputError
from sim.engine.layers import COVER, covering_offsets
from sim.engine.model import ClothModel, cloth_model, dihedral_angles, join_models

#: thicknesses between two layers where they overlap, at the start
LAYER_GAP = 2.0
#: metres an outer particle is lifted at most (over a flared skirt a top's hem goes out 6-7 cm)
MAX_LIFT = 0.1
#: edge rings over which a lift fades out
LIFT_RINGS = 6


@dataclass
class Outfit:
    """Garments (``darts``, named ``names``) joined into ``model``. The outfit's vertices are the
    garments' vertices one after the other: garment k's are ``vertex_slices[k]``; its particles are
    ``particle_slices[k]``; ``lift`` [P] is how far ``separate_layers`` moved each particle (m)."""

    darts: list[Dart]
    names: list[str]
    model: ClothModel
    vertex_slices: list[slice]
    particle_slices: list[slice]
    lift: np.ndarray
    caps: np.ndarray  # [C,3] particle triangles closing the inner garments' openings (``opening_caps``)

    def split(self, vertices: np.ndarray) -> list[np.ndarray]:
        """The outfit's vertices [V,3] as one array per garment."""
        return [vertices[s] for s in self.vertex_slices]


def garment_names(labels: list[str]) -> list[str]:
    """Unique names for the garments (USD prims, stats keys): each label made a valid identifier,
    with _2, _3 ... where two garments share one."""
    names = []
    for label in labels:
        base = "".join(c if c.isalnum() else "_" for c in label) or "garment"
        base = base if not base[0].isdigit() else f"g_{base}"
        name, k = base, 2
        while name in names:
            name, k = f"{base}_{k}", k + 1
        names.append(name)
    return names


def _ring_mean(values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Each particle's mean over its edge neighbours (itself where it has none)."""
    total = np.zeros_like(values)
    count = np.zeros(len(values))
    np.add.at(total, edges[:, 0], values[edges[:, 1]])
    np.add.at(total, edges[:, 1], values[edges[:, 0]])
    np.add.at(count, edges.reshape(-1), 1.0)
    return np.where(count > 0, total / np.maximum(count, 1.0), values)


def separate_layers(models: list[ClothModel], body_vertices: np.ndarray, body_faces: np.ndarray) -> list[np.ndarray]:
    """The lift (m, along the body's normal) of every particle of each model, inner first, so that
    where an outer garment covers an inner one it starts ``LAYER_GAP`` thicknesses outside it
    (module docstring); the models' rest shapes are moved by the lift in place.

    A covered particle p, with q its closest point on an inner garment and n the outward normal
    there, needs (p + t d - q).n >= LAYER_GAP thickness along the body's normal d: t = (gap - (p -
    q).n) / max(d.n, 0.3), where p - q crosses the inner surface rather than runs along it (beside
    an open edge), at most ``MAX_LIFT``; three rounds, the closest points taken again after each."""
    from darts.geometry.distance import SurfaceDistance

    body = SurfaceDistance(body_vertices, body_faces)
    thickness = max(float(m.material["thickness"]) for m in models)
    gap = LAYER_GAP * thickness
    lifts = [np.zeros(len(models[0].rest))]
    for k in range(1, len(models)):
        outer = models[k]
        _, closest, _ = body.query(outer.rest, winding=False)
        away = outer.rest - closest
        direction = away / np.maximum(np.linalg.norm(away, axis=1), 1e-9)[:, None]
        inner_surfaces = [SurfaceDistance(inner.rest, inner.faces) for inner in models[:k]]
        lift = np.zeros(len(outer.rest))
        for _ in range(3):
            for surface in inner_surfaces:
                points = outer.rest + lift[:, None] * direction
                distance, at, normal = surface.query(points, max_dist=COVER, winding=False)
                covered = np.abs(distance) < 0.99 * COVER  # the query answers max_dist (in float32) where nothing is near
                side = np.einsum("ij,ij->i", points - at, normal)
                # over or under the inner surface, not beside its open edge (there p - q runs along it)
                across = np.abs(side) >= 0.5 * np.linalg.norm(points - at, axis=1)
                short = covered & across & (side < gap)
                facing = np.maximum(np.einsum("ij,ij->i", direction, normal), 0.3)
                lift[short] += (gap - side[short]) / facing[short]
        lift = np.minimum(lift, MAX_LIFT)
        for _ in range(LIFT_RINGS):
            lift = np.maximum(lift, 0.7 * _ring_mean(lift, outer.edges))
        outer.rest[:] = outer.rest + lift[:, None] * direction
        lifts.append(lift)
    return lifts


def outfit_model(darts: list[Dart], labels: list[str], body_vertices: np.ndarray, body_faces: np.ndarray) -> Outfit:
    """``darts`` (inner first) as one model on the body at rest (canonical frame): the garments'
    models joined after ``separate_layers``; rest lengths and angles of lifted garments re-measured,
    and the layers' offsets off the body (``sim.engine.layers.covering_offsets``) found on the rest shape."""
    if len({d.body_model for d in darts}) > 1:
        raise DartsInputError(None, "the garments of an outfit must be made for the same body "
                                    f"(found {', '.join(sorted({d.body_model for d in darts}))})")
    if any(not np.allclose(np.pad(d.body_betas, (0, 16))[:16], np.pad(darts[0].body_betas, (0, 16))[:16]) for d in darts):
        raise DartsInputError(None, "the garments of an outfit must be made for the same body shape (betas)")
    names = garment_names(labels)
    models = [cloth_model(dart) for dart in darts]
    lifts = separate_layers(models, body_vertices, body_faces)
    models = [_remeasured(m) if lift.any() else m for m, lift in zip(models, lifts)]
    vertex_edges = np.cumsum([0] + [len(d.vertices) for d in darts])
    particle_edges = np.cumsum([0] + [len(m.rest) for m in models])
    model = join_models(models, names)
    outfit = Outfit(darts=list(darts), names=names, model=model,
                    vertex_slices=[slice(a, b) for a, b in zip(vertex_edges[:-1], vertex_edges[1:])],
                    particle_slices=[slice(a, b) for a, b in zip(particle_edges[:-1], particle_edges[1:])],
                    lift=np.concatenate(lifts), caps=opening_caps(model, model.rest))
    model.body_offset = covering_offsets(model, model.rest)
    return outfit


def _remeasured(model: ClothModel) -> ClothModel:
    """``model`` with its edge rest lengths and hinge rest angles measured on its (lifted) rest shape."""
    return replace(model, edge_rest=np.linalg.norm(model.rest[model.edges[:, 0]] - model.rest[model.edges[:, 1]], axis=1),
                   hinge_rest_angle=dihedral_angles(model.rest, model.hinges))


def loop_cap(loop: np.ndarray) -> np.ndarray:
    """Triangles [n-2, 3] closing a loop of n particle indices without a new point: a strip zigzagging
    between its two ends towards the far side (i, i+1, j), (i+1, j-1, j), ..., each triangle's corners
    in loop order, so all of them turn the way the loop does."""
    n = len(loop)
    i, j, triangles = 0, n - 1, []
    while j - i >= 2:
        triangles.append((loop[i], loop[i + 1], loop[j]))
        i += 1
        if j - i >= 2:
            triangles.append((loop[i], loop[j - 1], loop[j]))
            j -= 1
    return np.asarray(triangles, np.int64).reshape(-1, 3)


def opening_caps(model: ClothModel, particles: np.ndarray) -> np.ndarray:
    """[C,3]: every feature-line loop of every garment but the outermost closed by ``loop_cap``,
    facing away from its garment's centroid (``particles`` [P,3] is where the garments are: every
    opening of a template is a feature line: waist, hems, cuffs or armholes, neckline). With its
    caps an inner garment is a closed surface (for ``layer_order``'s winding number)."""
    outermost = model.layer.max()
    caps = []
    for loop in model.loops.values():
        layer = model.layer[loop[0]]
        if layer == outermost or len(loop) < 3:
            continue
        cap = loop_cap(np.asarray(loop))
        centroid = particles[model.layer == layer].mean(axis=0)
        a, b, c = (particles[cap[:, k]] for k in range(3))
        if np.dot(np.cross(b - a, c - a).sum(axis=0), particles[loop].mean(axis=0) - centroid) < 0:
            cap = cap[:, [0, 2, 1]]
        caps.append(cap)
    return np.concatenate(caps) if caps else np.zeros((0, 3), np.int64)


def closed_surface(outfit: Outfit, layer: int) -> np.ndarray:
    """Garment ``layer``'s triangles with its openings closed (``Outfit.caps``), indexing the
    outfit's particles."""
    model = outfit.model
    faces = np.concatenate([model.faces, outfit.caps])
    return faces[model.layer[faces[:, 0]] == layer]


def layer_order(outfit: Outfit, particles: np.ndarray, body_vertices: np.ndarray,
                body_faces: np.ndarray) -> tuple[dict[str, float], dict[str, float]]:
    """For each pair of garments (inner, outer), keyed ``"outer in inner"``: the fraction of the outer
    garment's particles under the inner garment's cloth, and the fraction inside its closed surface.

    Inside: the winding number (> 1/2) of the inner garment closed by its caps (``closed_surface``;
    open, a sleeve passing an armhole would count as inside it). Under the cloth: inside, and the
    inner garment's cloth lies over the particle: the
    segment of ``COVER`` from it along the body's outward normal at its closest body point passes
    through an inner triangle. A particle inside but not under the cloth lies in an opening that the
    body fills, on the skin (the top's underarm in a sleeveless dress's armhole, pressed into the
    armpit by the arm), where a flat cap cannot follow the body."""
    from darts.geometry.distance import SurfaceDistance

    body = SurfaceDistance(body_vertices, body_faces)
    model = outfit.model
    under, inside = {}, {}
    for j in range(len(outfit.names) - 1):
        surface = SurfaceDistance(particles, closed_surface(outfit, j))
        cloth = model.faces[model.layer[model.faces[:, 0]] == j]
        for k in range(j + 1, len(outfit.names)):
            outer = particles[outfit.particle_slices[k]]
            sign, _, _ = surface.query(outer, winding=True)
            found = outer[sign < 0]
            covered = 0
            if len(found):
                _, _, normal = body.query(found, winding=False)
                points = np.concatenate([particles, found, found + COVER * normal])
                start = len(particles) + np.arange(len(found))
                covered = int(edges_through(points, cloth, np.stack([start, start + len(found)], 1)).sum())
            key = f"{outfit.names[k]} in {outfit.names[j]}"
            under[key], inside[key] = covered / len(outer), len(found) / len(outer)
    return under, inside


def edges_through(points: np.ndarray, faces: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Mask [E]: which segments ``edges`` [E,2] (indices into ``points`` [N,3]) pass through a
    triangle ``faces`` [F,3] (``kernels.edges_through_mesh``), on the CPU: a measure of a frame's
    host copy, whatever device the run steps on."""
    from darts.geometry.warp_runtime import warp
    from sim.engine import kernels

    wp = warp()
    x = wp.array(np.ascontiguousarray(points, np.float32), dtype=wp.vec3, device="cpu")
    mesh = wp.Mesh(points=x, indices=wp.array(np.ascontiguousarray(faces, np.int32).reshape(-1), dtype=wp.int32,
                                              device="cpu"))
    segments = wp.array(np.ascontiguousarray(edges, np.int32), dtype=wp.int32, device="cpu")
    hits = wp.zeros(len(edges), dtype=wp.int32, device="cpu")
    wp.launch(kernels.edges_through_mesh, dim=len(edges), inputs=[mesh.id, x, segments, hits], device="cpu")
    return hits.numpy().astype(bool)


def layer_crossings(outfit: Outfit, particles: np.ndarray) -> dict[str, int]:
    """For each pair of garments: how many edges of either pass through a triangle of the other
    right now (``edges_through``), keyed ``"outer x inner"``. A garment's crossings with itself are
    counted with the rest in ``FrameMeasure.self_intersections``."""
    model = outfit.model
    edge_layer, face_layer = model.layer[model.edges[:, 0]], model.layer[model.faces[:, 0]]
    found = {}
    for j in range(len(outfit.names) - 1):
        for k in range(j + 1, len(outfit.names)):
            found[f"{outfit.names[k]} x {outfit.names[j]}"] = sum(
                int(edges_through(particles, model.faces[face_layer == faces_of], model.edges[edge_layer == edges_of]).sum())
                for edges_of, faces_of in ((k, j), (j, k)))
    return found
