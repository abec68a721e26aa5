"""Self-contact of the garment: vertex-triangle repulsion with side memory, and a crossing count.

Every search (with the body's, every ``contact_interval`` substeps) refits a BVH over the garment's
own triangles (the particle array itself, so never rebuilt) and gives each particle its closest
triangle within reach that is not its neighbour on the rest garment, with the side it is on. Each
sweep then keeps the particle ``separation`` away from that triangle's plane on that side, sharing
the correction with the triangle's corners by inverse mass and barycentric weight (an XPBD contact
with zero compliance). Remembering the side means a particle that has already passed the plane is
pulled back instead of pushed through; edge-edge crossings are covered by the separation, which
is larger than the edges' sag between vertices.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp

wp = warp()


@wp.func
def closest_on_triangle(p: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3):
    """Barycentric weights (of a, b, c) of the point of triangle abc closest to p (Ericson 5.1.5)."""
    ab = b - a
    ac = c - a
    ap = p - a
    d1 = wp.dot(ab, ap)
    d2 = wp.dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return wp.vec3(1.0, 0.0, 0.0)
    bp = p - b
    d3 = wp.dot(ab, bp)
    d4 = wp.dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return wp.vec3(0.0, 1.0, 0.0)
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        return wp.vec3(1.0 - t, t, 0.0)
    cp = p - c
    d5 = wp.dot(ab, cp)
    d6 = wp.dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return wp.vec3(0.0, 0.0, 1.0)
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        return wp.vec3(1.0 - t, 0.0, t)
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return wp.vec3(0.0, 1.0 - t, t)
    denominator = 1.0 / (va + vb + vc)
    v = vb * denominator
    w = vc * denominator
    return wp.vec3(1.0 - v - w, v, w)


@wp.func
def near_on_rest(rest: wp.array(dtype=wp.vec3), i: int, a: int, b: int, c: int, exclusion: float):
    """Is a corner of triangle abc within ``exclusion`` of particle i on the rest garment."""
    return (wp.length(rest[a] - rest[i]) < exclusion or wp.length(rest[b] - rest[i]) < exclusion
            or wp.length(rest[c] - rest[i]) < exclusion)


@wp.func
def face_normal(x: wp.array(dtype=wp.vec3), faces: wp.array2d(dtype=wp.int32), face: int):
    """Unit normal of a garment triangle."""
    a = x[faces[face, 0]]
    return wp.normalize(wp.cross(x[faces[face, 1]] - a, x[faces[face, 2]] - a))


@wp.kernel
def find_self_contacts(mesh: wp.uint64, faces: wp.array2d(dtype=wp.int32), x: wp.array(dtype=wp.vec3),
                       x_start: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), reach: float, exclusion: float,
                       contact_face: wp.array(dtype=wp.int32), contact_bary: wp.array(dtype=wp.vec3),
                       contact_side: wp.array(dtype=float)):
    """Closest garment triangle within ``reach`` of each particle, facing it, whose corners are all
    farther than ``exclusion`` from it on the rest garment (-1: none), its barycentrics, and the side of its plane
    the particle must not leave: kept from the last search for the same triangle, else the side it
    was on at the start of the substep (``x_start``, after the last projection)."""
    i = wp.tid()
    p = x[i]
    if not wp.isfinite(p):  # a blown-up particle: the run is about to stop; do not walk the BVH
        contact_face[i] = -1
        return
    r = wp.vec3(reach)
    query = wp.mesh_query_aabb(mesh, p - r, p + r)
    face = int(0)
    best = int(-1)
    best_distance = reach
    best_bary = wp.vec3(0.0)
    while wp.mesh_query_aabb_next(query, face):
        a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
        if near_on_rest(rest, i, a, b, c, exclusion):
            continue
        bary = closest_on_triangle(p, x[a], x[b], x[c])
        d = p - (bary[0] * x[a] + bary[1] * x[b] + bary[2] * x[c])
        distance = wp.length(d)
        # Only a triangle the particle faces (within 60 degrees of its normal): one beside it, in its
        # own plane, is the particle's own layer a little further on, with no side to keep.
        facing = wp.abs(wp.dot(d, wp.normalize(wp.cross(x[b] - x[a], x[c] - x[a])))) >= 0.5 * distance
        if distance < best_distance and facing:
            best = face
            best_distance = distance
            best_bary = bary
    if best >= 0 and best != contact_face[i]:
        contact_side[i] = wp.sign(wp.dot(x_start[i] - x_start[faces[best, 0]], face_normal(x_start, faces, best)))
    contact_face[i] = best
    contact_bary[i] = best_bary


@wp.func
def pinned_weight(inverse_mass: wp.array(dtype=float), body_push: wp.array(dtype=float), i: int):
    """Inverse mass for self-contact, a tenth of it for a particle the body pushed this substep,
    so that the layer outside moves off the layer held by the body instead of into it."""
    if body_push[i] > 0.0:
        return 0.1 * inverse_mass[i]
    return inverse_mass[i]


@wp.kernel
def resolve_self_contacts(faces: wp.array2d(dtype=wp.int32), contact_face: wp.array(dtype=wp.int32),
                          contact_bary: wp.array(dtype=wp.vec3), contact_side: wp.array(dtype=float),
                          inverse_mass: wp.array(dtype=float), body_push: wp.array(dtype=float), separation: float,
                          reach: float, x: wp.array(dtype=wp.vec3), delta: wp.array(dtype=wp.vec3),
                          hits: wp.array(dtype=float)):
    """C = |x_i - q| - separation >= 0 with q = sum_k b_k x_k while x_i is on its side of the plane,
    else C = side (x_i - q) . n - separation, projected with weights w_i and b_k^2 w_k into ``delta``
    (``hits`` counts the corrections each particle gets); a particle more than ``reach`` behind the
    plane is left alone (a stale contact, not a crossing to undo)."""
    i = wp.tid()
    face = contact_face[i]
    if face < 0 or contact_side[i] == 0.0:
        return
    bary = contact_bary[i]
    a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
    xa, xb, xc = x[a], x[b], x[c]
    scaled = wp.cross(xb - xa, xc - xa)
    area2 = wp.length(scaled)
    if area2 < 1.0e-12:
        return
    n = contact_side[i] * scaled / area2
    q = bary[0] * xa + bary[1] * xb + bary[2] * xc
    d = x[i] - q
    height = wp.dot(d, n)
    distance = wp.length(d)
    if height > 0.0 and distance > 1.0e-9:
        n = d / distance  # still on its side: keep the distance, also off the triangle's edges
        height = distance
    constraint = height - separation
    if constraint >= 0.0 or height < -reach:
        return  # apart, or so far behind that the contact is stale (its triangle has moved on)
    wi, wa, wb, wc = (pinned_weight(inverse_mass, body_push, i), pinned_weight(inverse_mass, body_push, a),
                      pinned_weight(inverse_mass, body_push, b), pinned_weight(inverse_mass, body_push, c))
    weight = wi + bary[0] * bary[0] * wa + bary[1] * bary[1] * wb + bary[2] * bary[2] * wc
    step = -constraint / weight
    depth = -constraint  # no particle moves further than the violation (a light corner under a heavy particle would)
    wp.atomic_add(delta, i, wp.min(wi * step, depth) * n)
    wp.atomic_sub(delta, a, wp.min(wa * bary[0] * step, depth) * n)
    wp.atomic_sub(delta, b, wp.min(wb * bary[1] * step, depth) * n)
    wp.atomic_sub(delta, c, wp.min(wc * bary[2] * step, depth) * n)
    wp.atomic_add(hits, i, 1.0)
    wp.atomic_add(hits, a, 1.0)
    wp.atomic_add(hits, b, 1.0)
    wp.atomic_add(hits, c, 1.0)


@wp.kernel
def apply_averaged(delta: wp.array(dtype=wp.vec3), hits: wp.array(dtype=float), x: wp.array(dtype=wp.vec3)):
    """x_i += delta_i / hits_i: each particle moves by the mean of its contact corrections (Jacobi
    with averaging, so that a triangle many particles lean on is not pushed once per particle)."""
    i = wp.tid()
    if hits[i] > 0.0:
        x[i] = x[i] + delta[i] / hits[i]


@wp.func
def segment_hits_triangle(origin: wp.vec3, direction: wp.vec3, length: float, a: wp.vec3, b: wp.vec3, c: wp.vec3):
    """Moeller-Trumbore: does origin + t direction, 0 <= t <= length, pass through triangle abc."""
    e1 = b - a
    e2 = c - a
    h = wp.cross(direction, e2)
    det = wp.dot(e1, h)
    if wp.abs(det) < 1.0e-14:
        return False
    inv = 1.0 / det
    s = origin - a
    u = inv * wp.dot(s, h)
    if u < 0.0 or u > 1.0:
        return False
    q = wp.cross(s, e1)
    v = inv * wp.dot(direction, q)
    if v < 0.0 or u + v > 1.0:
        return False
    t = inv * wp.dot(e2, q)
    return t >= 0.0 and t <= length


@wp.kernel
def count_crossings(mesh: wp.uint64, faces: wp.array2d(dtype=wp.int32), edges: wp.array2d(dtype=wp.int32),
                    x: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), exclusion: float,
                    crossing: wp.array(dtype=wp.int32)):
    """Edges of the garment that pass through one of its triangles (a self-intersection), leaving out
    triangles within ``exclusion`` of the edge's ends on the rest garment (its neighbours, never
    contacts); each edge is shortened by 0.1 % at both ends."""
    e = wp.tid()
    a, b = edges[e, 0], edges[e, 1]
    d = x[b] - x[a]
    length = wp.length(d)
    if length < 1.0e-9:
        return
    direction = d / length
    start = x[a] + 0.001 * d
    query = wp.mesh_query_aabb(mesh, wp.min(x[a], x[b]), wp.max(x[a], x[b]))
    face = int(0)
    while wp.mesh_query_aabb_next(query, face):
        i, j, k = faces[face, 0], faces[face, 1], faces[face, 2]
        if near_on_rest(rest, a, i, j, k, exclusion) or near_on_rest(rest, b, i, j, k, exclusion):
            continue
        if segment_hits_triangle(start, direction, 0.998 * length, x[i], x[j], x[k]):
            crossing[e] = 1
            return


class SelfContact:
    """The garment's self-contact state on the device; positions are the solver's particle array."""

    def __init__(self, x, rest: np.ndarray, faces: np.ndarray, edges: np.ndarray, separation: float,
                 exclusion: float, device: str):
        self.x, self.device, self.count = x, device, x.shape[0]
        self.separation, self.exclusion = float(separation), float(exclusion)
        self.reach = float(exclusion)
        self.faces = wp.array(np.ascontiguousarray(faces, np.int32), dtype=wp.int32, device=device)
        self.edges = wp.array(np.ascontiguousarray(edges, np.int32), dtype=wp.int32, device=device)
        self.rest = wp.array(np.ascontiguousarray(rest, np.float32), dtype=wp.vec3, device=device)
        self.mesh = wp.Mesh(points=x, indices=wp.array(np.ascontiguousarray(faces, np.int32).reshape(-1), dtype=wp.int32,
                                                       device=device))
        self.face = wp.full(self.count, -1, dtype=wp.int32, device=device)
        self.bary = wp.zeros(self.count, dtype=wp.vec3, device=device)
        self.side = wp.zeros(self.count, dtype=float, device=device)
        self._delta = wp.zeros(self.count, dtype=wp.vec3, device=device)
        self._hits = wp.zeros(self.count, dtype=float, device=device)
        self._crossing = wp.zeros(self.edges.shape[0], dtype=wp.int32, device=device)

    def search(self, x_start, reach: float) -> None:
        """Refit the garment's BVH to the particles and find each one's closest non-neighbour triangle
        (``x_start``: the positions the sides are taken from)."""
        self.reach = float(reach)
        self.mesh.refit()
        wp.launch(find_self_contacts, dim=self.count,
                  inputs=[self.mesh.id, self.faces, self.x, x_start, self.rest, reach, self.exclusion, self.face, self.bary,
                          self.side], device=self.device)

    def resolve(self, inverse_mass, body_push) -> None:
        """One sweep keeping every particle ``separation`` off its triangle, on its side (particles
        the body pushed this substep, ``body_push`` > 0, count ten times heavier), each particle
        moved by the mean of its corrections."""
        self._delta.zero_()
        self._hits.zero_()
        wp.launch(resolve_self_contacts, dim=self.count,
                  inputs=[self.faces, self.face, self.bary, self.side, inverse_mass, body_push, self.separation,
                          self.reach, self.x, self._delta, self._hits],
                  device=self.device)
        wp.launch(apply_averaged, dim=self.count, inputs=[self._delta, self._hits, self.x], device=self.device)

    def crossing_edges(self) -> np.ndarray:
        """Mask [E] of the garment edges that pass through a garment triangle right now."""
        self.mesh.refit()
        self._crossing.zero_()
        wp.launch(count_crossings, dim=self.edges.shape[0], inputs=[self.mesh.id, self.faces, self.edges, self.x,
                                                                     self.rest, self.exclusion, self._crossing],
                  device=self.device)
        return self._crossing.numpy().astype(bool)
