"""Warp kernels of the garment's self-contact (``sim.engine.self_contact``, its host class; world
frame, Z up, SI units): closest points on triangles and between segments, the broad phase's
candidate lists, the vertex-triangle and edge-edge searches with side memory, the XPBD projections
and their averaging, friction between layers, and the crossing count.
"""
from __future__ import annotations

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


@wp.func
def reach_of(i: int, v: wp.array(dtype=wp.vec3), reach: float, mean_velocity: wp.array(dtype=wp.vec3),
             other_speed: wp.array(dtype=float), world: wp.array(dtype=wp.int32), lookahead: float, max_speed: float):
    """reach_i = ``reach`` + ``lookahead`` min(|v_i - v̄_w| + s_w, ``max_speed``), w = ``world[i]``,
    v̄_w = ``mean_velocity[w]``, s_w = ``other_speed[w]``: what particle i and a triangle of its world
    moving at s_w can close in ``lookahead`` seconds."""
    w = world[i]
    radius = reach + lookahead * wp.min(wp.length(v[i] - mean_velocity[w]) + other_speed[w], max_speed)
    if not wp.isfinite(radius):
        radius = reach
    return radius


@wp.kernel
def gather_candidates(mesh: wp.uint64, faces: wp.array2d(dtype=wp.int32), x: wp.array(dtype=wp.vec3),
                      v: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), reach: float,
                      mean_velocity: wp.array(dtype=wp.vec3), other_speed: wp.array(dtype=float),
                      world: wp.array(dtype=wp.int32), lookahead: float, max_speed: float,
                      most: float, exclusion: float, candidates: wp.array2d(dtype=wp.int32),
                      distances: wp.array2d(dtype=float), count: wp.array(dtype=wp.int32)):
    """Broad phase: the garment triangles within reach_i (``reach_of``) of each particle whose corners
    are all farther than ``exclusion`` from it on the rest garment, nearest first, at most
    ``candidates.shape[1]`` of them (the nearest kept), their distances, and how many. A particle
    whose reach_i is over ``most`` gets no list (count -1): it searches the BVH itself."""
    i = wp.tid()
    p = x[i]
    count[i] = 0
    if not wp.isfinite(p):  # a blown-up particle: the run is about to stop; do not walk the BVH
        return
    radius = reach_of(i, v, reach, mean_velocity, other_speed, world, lookahead, max_speed)
    if radius > most:
        count[i] = -1
        return
    r = wp.vec3(radius)
    query = wp.mesh_query_aabb(mesh, p - r, p + r)
    capacity = candidates.shape[1]
    n = int(0)
    face = int(0)
    while wp.mesh_query_aabb_next(query, face):
        a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
        if near_on_rest(rest, i, a, b, c, exclusion):
            continue
        bary = closest_on_triangle(p, x[a], x[b], x[c])
        distance = wp.length(p - (bary[0] * x[a] + bary[1] * x[b] + bary[2] * x[c]))
        if distance >= radius or (n == capacity and distance >= distances[i, n - 1]):
            continue
        slot = wp.min(n, capacity - 1)  # insertion sort; when full, the farthest drops out
        while slot > 0 and distances[i, slot - 1] > distance:
            distances[i, slot] = distances[i, slot - 1]
            candidates[i, slot] = candidates[i, slot - 1]
            slot -= 1
        distances[i, slot] = distance
        candidates[i, slot] = face
        n = wp.min(n + 1, capacity)
    count[i] = n


@wp.func
def facing_distance(x: wp.array(dtype=wp.vec3), faces: wp.array2d(dtype=wp.int32), p: wp.vec3, face: int):
    """Distance from p to the closest point of a garment triangle and its barycentrics; the distance
    is infinite unless p faces the triangle (the closest point within 60 degrees of its normal: one
    beside it, in its own plane, is the particle's own layer a little further on, with no side to keep)."""
    a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
    bary = closest_on_triangle(p, x[a], x[b], x[c])
    d = p - (bary[0] * x[a] + bary[1] * x[b] + bary[2] * x[c])
    distance = wp.length(d)
    if wp.abs(wp.dot(d, wp.normalize(wp.cross(x[b] - x[a], x[c] - x[a])))) < 0.5 * distance:
        distance = float(1.0e30)
    return distance, bary


@wp.func
def side_carries(x: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), faces: wp.array2d(dtype=wp.int32),
                 layer: wp.array(dtype=wp.int32), last: int, new: int, carry: float):
    """Is triangle ``new`` on the same smooth layer as ``last`` (the same garment, a corner within
    ``carry`` of ``last``'s first corner on the rest garment, normals within 60 degrees), so that a
    side of ``last`` is the same side of ``new``."""
    a = faces[last, 0]
    return (layer[faces[new, 0]] == layer[a] and near_on_rest(rest, a, faces[new, 0], faces[new, 1], faces[new, 2], carry)
            and wp.dot(face_normal(x, faces, last), face_normal(x, faces, new)) > 0.5)


@wp.kernel
def find_self_contacts(mesh: wp.uint64, faces: wp.array2d(dtype=wp.int32), x: wp.array(dtype=wp.vec3),
                       x_start: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3),
                       candidates: wp.array2d(dtype=wp.int32), candidate_count: wp.array(dtype=wp.int32),
                       reach: float, mean_velocity: wp.array(dtype=wp.vec3), other_speed: wp.array(dtype=float),
                       world: wp.array(dtype=wp.int32), lookahead: float, max_speed: float,
                       exclusion: float, carry: float, layer: wp.array(dtype=wp.int32),
                       contact_face: wp.array(dtype=wp.int32), contact_bary: wp.array(dtype=wp.vec3),
                       contact_side: wp.array(dtype=float)):
    """Search: each particle's closest facing triangle (``facing_distance``) within reach_i
    (``reach_of``) among its candidates, or, for a particle without a list, among the BVH's triangles
    whose corners are all farther than ``exclusion`` from it on the rest garment (-1: none); its
    barycentrics, and the side of its plane the particle must not leave. Between two garments of an
    outfit the side is known: an outer garment's particle stays on the outer side of an inner
    garment's triangle (its normal side: garments' triangles face away from the body) and an inner
    one on the inner side of an outer triangle, so a particle that has passed through another layer
    is pulled back. Within a garment it is kept from the last search for the same triangle, and
    carried over to a new triangle near the last one (a corner within ``carry`` of the last one's
    first corner on the rest garment) whose normal is within 60 degrees of the last one's: the
    garment's triangles are consistently oriented, so a particle sliding along a smooth layer is on
    the same side of every triangle of it, and one found behind the next triangle has passed through
    it (taking the side afresh there would keep it through). Else (a new layer, or a fold between the
    two triangles) it is the side the particle was on at the start of the substep (``x_start``,
    after the last projection)."""
    i = wp.tid()
    p = x[i]
    best = int(-1)
    best_distance = reach_of(i, v, reach, mean_velocity, other_speed, world, lookahead, max_speed)
    best_bary = wp.vec3(0.0)
    if candidate_count[i] >= 0:
        for k in range(candidate_count[i]):
            distance, bary = facing_distance(x, faces, p, candidates[i, k])
            if distance < best_distance:
                best = candidates[i, k]
                best_distance = distance
                best_bary = bary
    elif wp.isfinite(p):
        r = wp.vec3(best_distance)
        query = wp.mesh_query_aabb(mesh, p - r, p + r)
        face = int(0)
        while wp.mesh_query_aabb_next(query, face):
            if near_on_rest(rest, i, faces[face, 0], faces[face, 1], faces[face, 2], exclusion):
                continue
            distance, bary = facing_distance(x, faces, p, face)
            if distance < best_distance:
                best = face
                best_distance = distance
                best_bary = bary
    last = contact_face[i]
    if best >= 0 and layer[faces[best, 0]] != layer[i]:
        contact_side[i] = wp.where(layer[i] > layer[faces[best, 0]], 1.0, -1.0)
    elif best >= 0 and best != last and not (last >= 0 and contact_side[i] != 0.0
                                             and side_carries(x_start, rest, faces, layer, last, best, carry)):
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


@wp.func
def project_separation(index: wp.vec4i, coefficient: wp.vec4, normal: wp.vec3, separation: float, reach: float,
                       inverse_mass: wp.array(dtype=float), body_push: wp.array(dtype=float),
                       x: wp.array(dtype=wp.vec3), delta: wp.array(dtype=wp.vec3), hits: wp.array(dtype=float)):
    """One contact between the points g_+ and g_- of two garment features, gap g = sum_k c_k x_k
    (c_k > 0 on the first feature, < 0 on the second, |c| summing to 1 on each): C = |g| - separation
    >= 0 while g points along ``normal`` (the side to keep), else C = g . n - separation; projected
    with weights c_k^2 w_k into ``delta`` (``hits`` counts the corrections of each particle). No
    particle moves further than the violation (a light corner under a heavy particle would), and a
    contact more than ``reach`` behind is left alone (stale: its feature has moved on)."""
    size = wp.length(normal)
    if size < 1.0e-12:
        return
    n = normal / size
    gap = wp.vec3(0.0)
    for k in range(4):
        gap += coefficient[k] * x[index[k]]
    height = wp.dot(gap, n)
    distance = wp.length(gap)
    if height > 0.0 and distance > 1.0e-9:
        n = gap / distance  # still on its side: keep the distance, also off the features' ends
        height = distance
    constraint = height - separation
    if constraint >= 0.0 or height < -reach:
        return
    weight = float(0.0)
    for k in range(4):
        weight += coefficient[k] * coefficient[k] * pinned_weight(inverse_mass, body_push, index[k])
    step = -constraint / weight
    for k in range(4):
        move = wp.min(pinned_weight(inverse_mass, body_push, index[k]) * wp.abs(coefficient[k]) * step, -constraint)
        wp.atomic_add(delta, index[k], wp.sign(coefficient[k]) * move * n)
        wp.atomic_add(hits, index[k], 1.0)


@wp.kernel
def resolve_self_contacts(faces: wp.array2d(dtype=wp.int32), contact_face: wp.array(dtype=wp.int32),
                          contact_bary: wp.array(dtype=wp.vec3), contact_side: wp.array(dtype=float),
                          inverse_mass: wp.array(dtype=float), body_push: wp.array(dtype=float), separation: float,
                          reach: float, x: wp.array(dtype=wp.vec3), delta: wp.array(dtype=wp.vec3),
                          hits: wp.array(dtype=float)):
    """Particle i against the point q = sum_k b_k x_k of its triangle: ``project_separation`` with
    gap x_i - q, kept on its side of the triangle's plane."""
    i = wp.tid()
    face = contact_face[i]
    if face < 0 or contact_side[i] == 0.0:
        return
    bary = contact_bary[i]
    a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
    project_separation(wp.vec4i(i, a, b, c), wp.vec4(1.0, -bary[0], -bary[1], -bary[2]),
                       contact_side[i] * wp.cross(x[b] - x[a], x[c] - x[a]), separation, reach, inverse_mass,
                       body_push, x, delta, hits)


@wp.func
def closest_between_segments(p1: wp.vec3, q1: wp.vec3, p2: wp.vec3, q2: wp.vec3):
    """Parameters (s, t) of the closest points p1 + s (q1 - p1) and p2 + t (q2 - p2) of two
    segments of non-zero length (Ericson 5.1.9)."""
    d1 = q1 - p1
    d2 = q2 - p2
    r = p1 - p2
    a = wp.dot(d1, d1)
    e = wp.dot(d2, d2)
    f = wp.dot(d2, r)
    c = wp.dot(d1, r)
    b = wp.dot(d1, d2)
    denominator = a * e - b * b
    s = float(0.0)
    if denominator > 1.0e-12 * a * e:
        s = wp.clamp((b * f - c * e) / denominator, 0.0, 1.0)
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = wp.clamp(-c / a, 0.0, 1.0)
    elif t > 1.0:
        t = 1.0
        s = wp.clamp((b - c) / a, 0.0, 1.0)
    return wp.vec2(s, t)


@wp.func
def inside_both(st: wp.vec2):
    """Are both closest points strictly inside their segments (else a vertex is the closest point,
    and the vertex-triangle contact has it)."""
    return st[0] > 1.0e-4 and st[0] < 1.0 - 1.0e-4 and st[1] > 1.0e-4 and st[1] < 1.0 - 1.0e-4


@wp.func
def edge_near_on_rest(rest: wp.array(dtype=wp.vec3), a: int, b: int, c: int, d: int, exclusion: float):
    """Is an end of edge cd within ``exclusion`` of an end of edge ab on the rest garment."""
    return (wp.length(rest[c] - rest[a]) < exclusion or wp.length(rest[d] - rest[a]) < exclusion
            or wp.length(rest[c] - rest[b]) < exclusion or wp.length(rest[d] - rest[b]) < exclusion)


@wp.func
def edge_candidate(edges: wp.array2d(dtype=wp.int32), rest: wp.array(dtype=wp.vec3), x: wp.array(dtype=wp.vec3),
                   a: int, b: int, other: int, exclusion: float):
    """(distance, s, t) from edge ab to edge ``other`` = cd; distance 1e30 unless no end of cd is
    within ``exclusion`` of a or b on the rest garment, both closest points lie inside their segments,
    the edges are not within 6 degrees of parallel and the gap is within 60 degrees of their common
    normal ab x cd (a neighbour in the same layer has its gap in the layer)."""
    c, d = edges[other, 0], edges[other, 1]
    if edge_near_on_rest(rest, a, b, c, d, exclusion):
        return wp.vec3(1.0e30, 0.0, 0.0)
    st = closest_between_segments(x[a], x[b], x[c], x[d])
    if not inside_both(st):
        return wp.vec3(1.0e30, 0.0, 0.0)
    normal = wp.cross(x[b] - x[a], x[d] - x[c])
    gap = wp.lerp(x[a], x[b], st[0]) - wp.lerp(x[c], x[d], st[1])
    distance = wp.length(gap)
    crossed = wp.length(normal) >= 0.1 * wp.length(x[b] - x[a]) * wp.length(x[d] - x[c])
    facing = wp.abs(wp.dot(gap, wp.normalize(normal))) >= 0.5 * distance
    if not (crossed and facing):
        return wp.vec3(1.0e30, 0.0, 0.0)
    return wp.vec3(distance, st[0], st[1])


@wp.kernel
def find_edge_contacts(faces: wp.array2d(dtype=wp.int32), edges: wp.array2d(dtype=wp.int32),
                       vertex_edge_start: wp.array(dtype=wp.int32), vertex_edges: wp.array(dtype=wp.int32),
                       contact_face: wp.array(dtype=wp.int32), x: wp.array(dtype=wp.vec3),
                       x_start: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), reach: float, exclusion: float,
                       layer: wp.array(dtype=wp.int32), edge_face: wp.array(dtype=wp.int32),
                       partner: wp.array(dtype=wp.int32), partner_st: wp.array(dtype=wp.vec2),
                       partner_side: wp.array(dtype=float)):
    """For each garment edge ab, the closest edge cd (-1: none) within ``reach`` that passes
    ``edge_candidate``, among its last partner and the edges at the corners of the triangles that
    a's and b's vertex-triangle contacts found (the other layer, where it is near; no BVH walk); its
    closest-point parameters, and the side along n = ab x cd to keep. Between two garments of an
    outfit the side is known: the outer edge stays on the normal side of a triangle at the inner
    edge (``edge_face``). Within a garment it is kept from the last search for the same pair, else
    the side at the start of the substep (``x_start``)."""
    e = wp.tid()
    a, b = edges[e, 0], edges[e, 1]
    best = int(-1)
    best_distance = reach
    best_st = wp.vec2(0.0)
    if partner[e] >= 0:  # the last partner stays a candidate while the vertex contacts come and go
        candidate = edge_candidate(edges, rest, x, a, b, partner[e], exclusion)
        if candidate[0] < best_distance:
            best = partner[e]
            best_distance = candidate[0]
            best_st = wp.vec2(candidate[1], candidate[2])
    for end in range(2):
        face = int(contact_face[edges[e, end]])
        if face < 0:
            continue
        for corner in range(3):
            v = int(faces[face, corner])
            for k in range(vertex_edge_start[v], vertex_edge_start[v + 1]):
                other = int(vertex_edges[k])
                candidate = edge_candidate(edges, rest, x, a, b, other, exclusion)
                if candidate[0] < best_distance:
                    best = other
                    best_distance = candidate[0]
                    best_st = wp.vec2(candidate[1], candidate[2])
    known = int(0)
    if best >= 0 and layer[edges[best, 0]] != layer[a]:
        other_c, other_d = edges[best, 0], edges[best, 1]
        inner = wp.where(layer[a] < layer[other_c], e, best)  # the edge of the inner garment
        if edge_face[inner] >= 0:
            outward = face_normal(x, faces, edge_face[inner])
            # the gap (this edge minus the other) points out of the inner garment when this edge is outer
            outer_sign = wp.where(layer[a] > layer[other_c], 1.0, -1.0)
            partner_side[e] = wp.sign(outer_sign * wp.dot(outward, wp.cross(x[b] - x[a], x[other_d] - x[other_c])))
            known = 1
    if known == 0 and best >= 0 and best != partner[e]:
        c, d = edges[best, 0], edges[best, 1]
        gap = wp.lerp(x_start[a], x_start[b], best_st[0]) - wp.lerp(x_start[c], x_start[d], best_st[1])
        partner_side[e] = wp.sign(wp.dot(gap, wp.cross(x_start[b] - x_start[a], x_start[d] - x_start[c])))
    partner[e] = best
    partner_st[e] = best_st


@wp.kernel
def resolve_edge_contacts(edges: wp.array2d(dtype=wp.int32), partner: wp.array(dtype=wp.int32),
                          partner_st: wp.array(dtype=wp.vec2), partner_side: wp.array(dtype=float),
                          inverse_mass: wp.array(dtype=float), body_push: wp.array(dtype=float), separation: float,
                          reach: float, x: wp.array(dtype=wp.vec3), delta: wp.array(dtype=wp.vec3),
                          hits: wp.array(dtype=float)):
    """Edge ab against its partner cd: ``project_separation`` with gap lerp(a, b, s) - lerp(c, d, t),
    kept on its side along ab x cd."""
    e = wp.tid()
    other = partner[e]
    if other < 0 or partner_side[e] == 0.0:
        return
    a, b, c, d = edges[e, 0], edges[e, 1], edges[other, 0], edges[other, 1]
    s, t = partner_st[e][0], partner_st[e][1]
    project_separation(wp.vec4i(a, b, c, d), wp.vec4(1.0 - s, s, t - 1.0, -t),
                       partner_side[e] * wp.cross(x[b] - x[a], x[d] - x[c]), separation, reach, inverse_mass,
                       body_push, x, delta, hits)


@wp.kernel
def apply_averaged(delta: wp.array(dtype=wp.vec3), hits: wp.array(dtype=float), x: wp.array(dtype=wp.vec3),
                   pushed: wp.array(dtype=float)):
    """x_i += delta_i / hits_i: each particle moves by the mean of its contact corrections (Jacobi
    with averaging, so that a triangle many particles lean on is not pushed once per particle); how
    far adds up in ``pushed`` (for friction)."""
    i = wp.tid()
    if hits[i] > 0.0:
        move = delta[i] / hits[i]
        x[i] = x[i] + move
        pushed[i] = pushed[i] + wp.length(move)


@wp.kernel
def self_friction(faces: wp.array2d(dtype=wp.int32), contact_face: wp.array(dtype=wp.int32),
                  contact_bary: wp.array(dtype=wp.vec3), pushed: wp.array(dtype=float), friction: float,
                  layer: wp.array(dtype=wp.int32), inverse_mass: wp.array(dtype=float),
                  body_push: wp.array(dtype=float), x_start: wp.array(dtype=wp.vec3), x: wp.array(dtype=wp.vec3)):
    """Coulomb friction between a particle and its contact triangle on another layer (garment) of
    an outfit (Macklin et al. 2014; a garment's own folds slide freely, as they always have): the
    particle's motion over the substep relative to its triangle point q = sum_k b_k x_k, in the
    triangle's plane, is taken away up to ``friction`` times how far contacts pushed it apart (all
    of it below that: sticking), shared as a position constraint shares it: the particle moves
    -w_i / W of the cut and corner k b_k w_k / W, W = w_i + sum_k b_k^2 w_k (``pinned_weight``: a
    layer the body holds gives way a tenth as much), so that the relative motion loses exactly the
    cut."""
    i = wp.tid()
    face = contact_face[i]
    if face < 0 or pushed[i] <= 0.0:
        return
    a, b, c = faces[face, 0], faces[face, 1], faces[face, 2]
    if layer[a] == layer[i]:
        return
    w = contact_bary[i]
    n = wp.cross(x[b] - x[a], x[c] - x[a])
    size = wp.length(n)
    if size < 1.0e-12:
        return
    n = n / size
    q_move = w[0] * (x[a] - x_start[a]) + w[1] * (x[b] - x_start[b]) + w[2] * (x[c] - x_start[c])
    relative = (x[i] - x_start[i]) - q_move
    tangent = relative - wp.dot(relative, n) * n
    length = wp.length(tangent)
    if length < 1.0e-12:
        return
    cut = wp.min(length, friction * pushed[i]) / length * tangent
    wi = pinned_weight(inverse_mass, body_push, i)
    wa = pinned_weight(inverse_mass, body_push, a)
    wb = pinned_weight(inverse_mass, body_push, b)
    wc = pinned_weight(inverse_mass, body_push, c)
    total = wi + w[0] * w[0] * wa + w[1] * w[1] * wb + w[2] * w[2] * wc
    wp.atomic_sub(x, i, (wi / total) * cut)
    wp.atomic_add(x, a, (w[0] * wa / total) * cut)
    wp.atomic_add(x, b, (w[1] * wb / total) * cut)
    wp.atomic_add(x, c, (w[2] * wc / total) * cut)


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
def find_crossings(mesh: wp.uint64, faces: wp.array2d(dtype=wp.int32), edges: wp.array2d(dtype=wp.int32),
                   x: wp.array(dtype=wp.vec3), rest: wp.array(dtype=wp.vec3), exclusion: float,
                   candidate_count: wp.array(dtype=wp.int32), screen: float, crossed: wp.array(dtype=wp.int32)):
    """Edges of the garment that pass through one of its triangles (a self-intersection): crossed[e]
    is the first such triangle the BVH gives (-1: none), leaving out triangles within ``exclusion``
    of the edge's ends on the rest garment (its neighbours, never contacts); each edge is shortened
    by 0.1 % at both ends. With ``screen`` > 0 (the reach of the candidate lists just made), an edge
    shorter than 2 ``screen`` whose two ends have empty lists is not tested: the triangle it passes
    through would lie within ``screen`` of its nearer end, in that end's list or behind 16 nearer."""
    e = wp.tid()
    crossed[e] = -1
    a, b = edges[e, 0], edges[e, 1]
    d = x[b] - x[a]
    length = wp.length(d)
    if length < 1.0e-9:
        return
    if screen > 0.0 and candidate_count[a] == 0 and candidate_count[b] == 0 and length < 2.0 * screen:
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
            crossed[e] = face
            return


@wp.func
def contour_bend(faces: wp.array2d(dtype=wp.int32), edge_sides: wp.array2d(dtype=wp.int32),
                 x: wp.array(dtype=wp.vec3), e: int, a: int, b: int, n: wp.vec3):
    """w = q_1 + q_2: the unit directions in which the intersection contour of edge ab's surface with
    a plane of normal ``n`` leaves the crossing point, along the line where each triangle on a side
    of the edge meets the plane (n_f x n), into that triangle (towards its corner off the edge). The
    contour's length near the point falls fastest as the point moves along w: w is 0 where the
    contour runs straight through and points into its bend."""
    along = wp.normalize(x[b] - x[a])
    w = wp.vec3(0.0)
    for side in range(2):
        f = edge_sides[e, side]
        if f < 0:
            continue
        o = faces[f, 0] + faces[f, 1] + faces[f, 2] - a - b  # the corner off the edge
        line = wp.cross(face_normal(x, faces, f), n)
        size = wp.length(line)
        if size < 1.0e-6:
            continue
        inward = x[o] - x[a]
        inward = inward - wp.dot(inward, along) * along
        line = line / size
        if wp.dot(line, inward) < 0.0:
            line = -line
        w += line
    return w


@wp.kernel
def untangle_crossings(faces: wp.array2d(dtype=wp.int32), edges: wp.array2d(dtype=wp.int32),
                       edge_sides: wp.array2d(dtype=wp.int32), crossed: wp.array(dtype=wp.int32),
                       layer: wp.array(dtype=wp.int32), inverse_mass: wp.array(dtype=float), step: float,
                       x: wp.array(dtype=wp.vec3), delta: wp.array(dtype=wp.vec3), hits: wp.array(dtype=float)):
    """Intersection contour minimisation (after Volino and Magnenat-Thalmann 2006): edge ab that
    passes through triangle t (``crossed``, unit normal n) at p = lerp(a, b, s) is moved against t
    along n so that the contour where the two surfaces cut each other shrinks. p stays on the edge
    and in t's plane, so moving the edge's surface by d against t moves p by
    J d = d - (d . n) / (e . n) e (e = the edge's unit direction); the contour's length falls along
    w (``contour_bend``), so along J^T w, whose part along n is nu = -(e . w) / (e . n). The edge's
    point p minus t's point (barycentrics beta) is moved along n by m = step clamp(nu, -1, 1),
    shared as a position constraint shares it (particle k by c_k w_k m / sum_j c_j^2 w_j, c the
    weights 1 - s, s and -beta, w the inverse masses; none further than |m|), into ``delta``
    (``hits`` counts the moves of each particle). A contour that runs straight
    (w = 0) is left to its bends, and a pair that no longer crosses is left alone. Between two
    garments of an outfit (``layer``) the way is known: the outer garment's surface moves out (along
    the normal of an inner triangle, against an outer one) by the whole step."""
    e = wp.tid()
    t = crossed[e]
    if t < 0:
        return
    a, b = edges[e, 0], edges[e, 1]
    i, j, k = faces[t, 0], faces[t, 1], faces[t, 2]
    normal = wp.cross(x[j] - x[i], x[k] - x[i])
    if wp.length(normal) < 1.0e-12:
        return
    n = wp.normalize(normal)
    height_a = wp.dot(x[a] - x[i], n)
    height_b = wp.dot(x[b] - x[i], n)
    if height_a * height_b >= 0.0:
        return
    s = height_a / (height_a - height_b)
    p = wp.lerp(x[a], x[b], s)
    beta = closest_on_triangle(p, x[i], x[j], x[k])
    if wp.length(p - (beta[0] * x[i] + beta[1] * x[j] + beta[2] * x[k])) > 0.01 * wp.length(x[b] - x[a]):
        return  # the crossing has moved on to another triangle: the next search finds it
    along = wp.normalize(x[b] - x[a])
    across = wp.dot(along, n)
    if wp.abs(across) < 1.0e-6:
        return
    nu = -wp.dot(along, contour_bend(faces, edge_sides, x, e, a, b, n)) / across
    move = step * wp.clamp(nu, -1.0, 1.0)
    if layer[a] != layer[i]:  # two garments of an outfit: the outer one goes out (triangles face outwards)
        move = wp.where(layer[a] > layer[i], step, -step)
    if move == 0.0:
        return
    wa = inverse_mass[a]
    wb = inverse_mass[b]
    weight = (1.0 - s) * (1.0 - s) * wa + s * s * wb
    for c in range(3):
        weight += beta[c] * beta[c] * inverse_mass[faces[t, c]]
    if weight <= 0.0:
        return
    share = move / weight
    limit = wp.abs(move)  # no particle moves further than the pair (a light corner under a heavy one would)
    wp.atomic_add(delta, a, wp.clamp((1.0 - s) * wa * share, -limit, limit) * n)
    wp.atomic_add(delta, b, wp.clamp(s * wb * share, -limit, limit) * n)
    wp.atomic_add(hits, a, 1.0)
    wp.atomic_add(hits, b, 1.0)
    for c in range(3):
        corner = faces[t, c]
        wp.atomic_add(delta, corner,
                      -wp.clamp(beta[c] * inverse_mass[corner] * share, -limit, limit) * n)
        wp.atomic_add(hits, corner, 1.0)


@wp.kernel
def crossings_per_world(crossing: wp.array(dtype=wp.int32), edges: wp.array2d(dtype=wp.int32),
                        world: wp.array(dtype=wp.int32), counts: wp.array(dtype=wp.int32)):
    """counts[w] += 1 for each crossing edge (``find_crossings``) of world w (its first end's)."""
    e = wp.tid()
    if crossing[e] >= 0:
        wp.atomic_add(counts, world[edges[e, 0]], 1)


#: bins of the device-side median relative speed (``speed_histogram``), log-spaced from
#: ``SPEED_FLOOR`` to the speed cap: each bin is about 5 % wide at the default 50 m/s cap
SPEED_BINS = 256
SPEED_FLOOR = 1.0e-4  # m/s


@wp.kernel
def world_velocity_sums(v: wp.array(dtype=wp.vec3), world: wp.array(dtype=wp.int32), sums: wp.array(dtype=wp.vec3),
                        counts: wp.array(dtype=wp.int32)):
    """sums[w] += v_i and counts[w] += 1 over the finite velocities of each world w (``world[i]``)."""
    i = wp.tid()
    vi = v[i]
    if wp.isfinite(vi):
        wp.atomic_add(sums, world[i], vi)
        wp.atomic_add(counts, world[i], 1)


@wp.func
def speed_bin(speed: float, cap: float):
    """Bin of ``speed`` among ``SPEED_BINS`` log-spaced bins: 0 holds up to ``SPEED_FLOOR``, bin b >= 1
    holds (f r^(b-1), f r^b], f = SPEED_FLOOR, r = (cap / f)^(1 / (SPEED_BINS - 1))."""
    if speed <= SPEED_FLOOR:
        return 0
    step = wp.log(cap / SPEED_FLOOR) / float(SPEED_BINS - 1)
    return wp.clamp(int(wp.ceil(wp.log(speed / SPEED_FLOOR) / step)), 1, SPEED_BINS - 1)


@wp.kernel
def world_means(sums: wp.array(dtype=wp.vec3), counts: wp.array(dtype=wp.int32), mean: wp.array(dtype=wp.vec3)):
    """Each world's mean velocity v̄_w = sums[w] / counts[w] (0 without a finite velocity)."""
    w = wp.tid()
    mean[w] = sums[w] / float(wp.max(counts[w], 1))


@wp.kernel
def speed_histogram(v: wp.array(dtype=wp.vec3), world: wp.array(dtype=wp.int32), mean: wp.array(dtype=wp.vec3),
                    cap: float, bins: wp.array2d(dtype=wp.int32)):
    """The histogram over ``speed_bin`` of each world's |v_i - v̄_w|, its finite velocities only."""
    i = wp.tid()
    vi = v[i]
    if wp.isfinite(vi):
        wp.atomic_add(bins, world[i], speed_bin(wp.length(vi - mean[world[i]]), cap), 1)


@wp.kernel
def histogram_medians(bins: wp.array2d(dtype=wp.int32), counts: wp.array(dtype=wp.int32), cap: float,
                      spread: wp.array(dtype=float)):
    """spread[w] = the upper edge of the bin holding world w's median relative speed, at most ``cap``
    (0 for a world without a finite velocity): the host's median, rounded up by under one bin."""
    w = wp.tid()
    spread[w] = 0.0
    half = (counts[w] + 1) / 2
    running = int(0)
    step = wp.log(cap / SPEED_FLOOR) / float(SPEED_BINS - 1)
    for b in range(SPEED_BINS):
        running += bins[w, b]
        if counts[w] > 0 and running >= half:
            spread[w] = wp.min(SPEED_FLOOR * wp.exp(step * float(b)), cap)
            return
