"""Warp kernels of the body as a collider (``sim.engine.collider``; world frame, Z up, SI units):
the closest-face search with its skin, contacts tracked across the surface, the push off one face or
two (creases), and Coulomb friction against the moving body.
"""
from __future__ import annotations

from darts.geometry.warp_runtime import warp
from sim.engine.kernels import buried, inside_body

wp = warp()

#: A second contact face whose outward direction is within about 8 degrees of the first one's adds
#: no plane worth keeping off.
SAME_PLANE = wp.constant(0.99)
#: Two contact planes whose outward directions are more than about 154 degrees apart face each other
#: across a gap too narrow to sit a thickness off both (the point that does lies > 4.4 thicknesses
#: away along the crease): the first, nearer face alone keeps the particle off.
FACING = wp.constant(-0.9)


@wp.kernel
def body_frame(start: wp.array(dtype=wp.vec3), end: wp.array(dtype=wp.vec3), weight: float, fps: float,
               points: wp.array(dtype=wp.vec3), velocities: wp.array(dtype=wp.vec3)):
    """Body vertices between two frames: p = (1 - w) start + w end, v = (end - start) * fps."""
    i = wp.tid()
    points[i] = (1.0 - weight) * start[i] + weight * end[i]
    velocities[i] = (end[i] - start[i]) * fps


@wp.func
def face_frame(mesh: wp.uint64, face: int):
    """Orthonormal frame of a body face: first edge direction, its in-plane normal, the face normal."""
    a = wp.mesh_get_point(mesh, face * 3)
    b = wp.mesh_get_point(mesh, face * 3 + 1)
    c = wp.mesh_get_point(mesh, face * 3 + 2)
    n = wp.normalize(wp.cross(b - a, c - a))
    e1 = wp.normalize(b - a)
    return e1, wp.cross(n, e1), n


@wp.kernel
def find_contacts(mesh: wp.uint64, x: wp.array(dtype=wp.vec3), x_start: wp.array(dtype=wp.vec3),
                  world: wp.array(dtype=wp.int32), world_reach: wp.array(dtype=float),
                  thickness: float, continuous: int, min_path: float, elapsed: float, started: float, now: float,
                  window_start: wp.array(dtype=wp.vec3), skin: float, world_body_speed: wp.array(dtype=float),
                  query_time: wp.array(dtype=float), query_offset: wp.array(dtype=wp.vec3),
                  contact_face: wp.array(dtype=wp.int32), contact_uv: wp.array(dtype=wp.vec2),
                  contact_local: wp.array(dtype=wp.vec3), second: int, second_face: wp.array(dtype=wp.int32),
                  second_uv: wp.array(dtype=wp.vec2), second_local: wp.array(dtype=wp.vec3), release: int):
    """Closest body point within ``reach`` of each particle (face, barycentrics) and the outward
    direction there, stored in the face's own frame so that it turns with the face (face -1: none).
    ``reach`` and ``body_speed`` are the particle's world's (``world_reach[world[i]]``,
    ``world_body_speed[world[i]]``: each job's own body in a many-world model).

    A particle is queried again only once it may have changed (``skin`` > 0; 0 queries every one);
    one in a crease (with a second contact) always is, since its closest face changes fastest. With a
    contact, once its offset from its contact point (the same face and barycentrics on the
    body as it is now) has changed by ``skin`` since its query; without one, once its own path plus
    what the fastest body vertex (``body_speed``) can travel since its query reaches ``skin`` (the
    caller adds ``skin`` to ``reach``, so nothing came within the unskinned reach meanwhile). A
    particle's query keeps when it was made (``query_time``: the start of that substep; -1: never) and that
    offset (``query_offset``: from the contact point, or the position itself without a contact).

    With ``continuous`` set, the particle's path relative to the body since the last search,
    o -> x with o = window_start + v_body * elapsed (the body moving locally like the closest point,
    velocity v_body; 0 if none is within reach), is traced when it is longer than ``min_path`` (a
    shorter one cannot have reached past the middle of a body part, so the closest point is the way
    out) and starts outside the body: if it entered the body through a face (a ray hit on its front)
    whose outside, ``thickness`` off the hit, is free (not inside another part where the body
    overlaps itself), that face is the contact, so a particle that got past a thin part's middle,
    or right through it, goes back out the side it came in. ``window_start`` then takes ``x_start``
    (the start of this substep).

    With ``second`` set, a particle closer than ``thickness`` to its contact also looks where that
    contact alone would put it (a thickness off its plane): a face closer than a thickness to that
    point, turned more than SAME_PLANE away, is its second contact (``second_face``, -1: none),
    stored the same way. That is a crease: two faces of one part meeting at a concave angle, or two
    parts pressed together where the posed body overlaps itself (the belly and a thigh in a squat);
    one plane alone pushes the particle off one face into the other's thickness or inside it.

    With ``release`` set, a contact (first or second) whose body point is ``buried`` inside another
    part of the body is dropped: where the posed body overlaps itself (a calf folded into the thigh)
    no place a thickness off a buried face is outside the body, and keeping each particle off
    whichever buried face is closest pushed neighbours onto different parts' faces, stretching the
    cloth across the overlap. The particle then moves with the cloth around it until the overlap
    opens."""
    i = wp.tid()
    p = x[i]
    reach = world_reach[world[i]]
    body_speed = world_body_speed[world[i]]
    if skin > 0.0 and query_time[i] >= 0.0 and second_face[i] < 0:
        moved = float(0.0)
        if contact_face[i] >= 0:
            uv0 = contact_uv[i]
            moved = wp.length(p - wp.mesh_eval_position(mesh, contact_face[i], uv0[0], uv0[1]) - query_offset[i])
        else:
            moved = wp.length(p - query_offset[i]) + body_speed * (now - query_time[i])
        if moved < skin:  # (its path since the last search is shorter than min_path: no crossing)
            window_start[i] = x_start[i]
            return
    query = wp.mesh_query_point_sign_normal(mesh, p, reach)
    face = int(-1)
    uv = wp.vec2(0.0)
    out = wp.vec3(0.0)
    body_velocity = wp.vec3(0.0)
    if query.result:
        face = query.face
        uv = wp.vec2(query.u, query.v)
        out = wp.mesh_eval_face_normal(mesh, face)
        c = wp.mesh_eval_position(mesh, face, query.u, query.v)
        gap = wp.length(p - c)
        if gap > 1.0e-6:
            out = query.sign * (p - c) / gap
        body_velocity = wp.mesh_eval_velocity(mesh, face, query.u, query.v)
    if continuous != 0:
        origin = window_start[i] + body_velocity * elapsed
        path = p - origin
        length = wp.length(path)
        if length > min_path and not inside_body(mesh, origin, reach):
            direction = path / length
            hit = wp.mesh_query_ray(mesh, origin, direction, length)
            if hit.result and hit.sign > 0.0 and not inside_body(mesh, origin + hit.t * direction + thickness * hit.normal,
                                                                 reach):
                face = hit.face
                uv = wp.vec2(hit.u, hit.v)
                out = wp.mesh_eval_face_normal(mesh, face)
    if release != 0 and face >= 0:
        if buried(mesh, wp.mesh_eval_position(mesh, face, uv[0], uv[1]), out):
            face = -1
    contact_face[i] = face
    other = int(-1)
    if face >= 0:
        e1, e2, n = face_frame(mesh, face)
        contact_uv[i] = uv
        contact_local[i] = wp.vec3(wp.dot(out, e1), wp.dot(out, e2), wp.dot(out, n))
        # Where the first contact would put the particle, is another face closer than a thickness?
        # Then the particle sits in a crease (or where the posed body overlaps itself) and must keep
        # off that face's plane too. (A particle a thickness off its closest face has none.)
        depth = thickness - wp.dot(p - wp.mesh_eval_position(mesh, face, uv[0], uv[1]), out)
        if second != 0 and depth > 0.0:
            target = p + depth * out
            near = wp.mesh_query_point_sign_normal(mesh, target, thickness)
            if near.result and near.face != face:
                c2 = wp.mesh_eval_position(mesh, near.face, near.u, near.v)
                out2 = wp.mesh_eval_face_normal(mesh, near.face)
                gap2 = wp.length(target - c2)
                if gap2 > 1.0e-6:
                    out2 = near.sign * (target - c2) / gap2
                if wp.dot(out2, out) < SAME_PLANE and not (release != 0 and buried(mesh, c2, out2)):
                    other = near.face
                    f1, f2, m = face_frame(mesh, other)
                    second_uv[i] = wp.vec2(near.u, near.v)
                    second_local[i] = wp.vec3(wp.dot(out2, f1), wp.dot(out2, f2), wp.dot(out2, m))
    second_face[i] = other
    window_start[i] = x_start[i]
    query_time[i] = started
    query_offset[i] = p
    if face >= 0:
        query_offset[i] = p - wp.mesh_eval_position(mesh, face, uv[0], uv[1])


@wp.func
def track_contact(mesh: wp.uint64, i: int, face: wp.array(dtype=wp.int32), uv: wp.array(dtype=wp.vec2),
                  local: wp.array(dtype=wp.vec3), point: wp.array(dtype=wp.vec3), normal: wp.array(dtype=wp.vec3),
                  velocity: wp.array(dtype=wp.vec3)):
    """Particle i's contact plane on the body as it is now: the same surface point and the same
    direction in the face's frame (exact for a face that moves rigidly), with the surface velocity there."""
    f = face[i]
    if f < 0:
        return
    at = uv[i]
    out = local[i]
    e1, e2, n = face_frame(mesh, f)
    point[i] = wp.mesh_eval_position(mesh, f, at[0], at[1])
    normal[i] = wp.normalize(out[0] * e1 + out[1] * e2 + out[2] * n)
    velocity[i] = wp.mesh_eval_velocity(mesh, f, at[0], at[1])


@wp.kernel
def track_contacts(mesh: wp.uint64, face: wp.array(dtype=wp.int32), uv: wp.array(dtype=wp.vec2),
                   local: wp.array(dtype=wp.vec3), point: wp.array(dtype=wp.vec3), normal: wp.array(dtype=wp.vec3),
                   velocity: wp.array(dtype=wp.vec3), second_face: wp.array(dtype=wp.int32),
                   second_uv: wp.array(dtype=wp.vec2), second_local: wp.array(dtype=wp.vec3),
                   second_point: wp.array(dtype=wp.vec3), second_normal: wp.array(dtype=wp.vec3),
                   second_velocity: wp.array(dtype=wp.vec3)):
    """Each particle's contact and second contact (``track_contact``)."""
    i = wp.tid()
    track_contact(mesh, i, face, uv, local, point, normal, velocity)
    track_contact(mesh, i, second_face, second_uv, second_local, second_point, second_normal, second_velocity)


@wp.func
def two_plane_push(d1: float, n1: wp.vec3, d2: float, n2: wp.vec3):
    """Smallest move m with m.n1 >= d1 and m.n2 >= d2 (the particle ``d`` too close to each plane):
    one plane's push if it also clears the other, else m = a n1 + b n2 on both planes,
    [1 c; c 1][a; b] = [d1; d2] with c = n1.n2. Planes facing each other (c < FACING) leave
    the nearer one, the first, in charge."""
    m1 = wp.max(d1, 0.0) * n1
    if wp.dot(m1, n2) >= d2:
        return m1
    m2 = wp.max(d2, 0.0) * n2
    if wp.dot(m2, n1) >= d1:
        return m2
    c = wp.dot(n1, n2)
    if c < FACING:
        return m1
    det = 1.0 - c * c
    return ((d1 - c * d2) / det) * n1 + ((d2 - c * d1) / det) * n2


@wp.kernel
def resolve_contacts(x: wp.array(dtype=wp.vec3), contact_point: wp.array(dtype=wp.vec3),
                     contact_normal: wp.array(dtype=wp.vec3), contact_face: wp.array(dtype=wp.int32),
                     second_point: wp.array(dtype=wp.vec3), second_normal: wp.array(dtype=wp.vec3),
                     second_face: wp.array(dtype=wp.int32),
                     thickness: float, offset: wp.array(dtype=float), limit: float, crease_limit: float, ground: int,
                     ground_height: float, body_push: wp.array(dtype=float), ground_push: wp.array(dtype=float)):
    """Move particles to ``thickness`` + their ``offset`` (an outer layer's, over the layers under
    it) outside the body's tangent plane at their contact, and that of their second contact where
    they have one (the smallest move clearing both), but by at most ``limit`` (m) — a particle
    found deep inside the body comes out over several sweeps instead of leaping out in one — and
    ``thickness`` above the ground plane z = ground_height, adding up how far each was pushed.

    In a crease the move is held to ``crease_limit`` (m) a sweep: the move onto both planes grows as
    1 / (1 + n1.n2) as they turn to face each other, and where an arm presses a sleeve against the
    torso such moves threw the folded layers through each other. Between two planes that face each
    other (n1.n2 < FACING: two body parts pressed together) a gap g = (point2 - point1).n1 too
    narrow for the particle and a layer beside it (g < 2 off + thickness) shrinks the offset off
    both to off g / (2 off + thickness) (0 where the parts overlap): the squeezed cloth stays
    outside both parts, in the middle of the gap, instead of being pushed off one part into the
    other."""
    i = wp.tid()
    p = x[i]
    if contact_face[i] >= 0:
        off = thickness + offset[i]
        n1 = contact_normal[i]
        d1 = off - wp.dot(p - contact_point[i], n1)
        move = wp.max(d1, 0.0) * n1
        cap = limit
        if second_face[i] >= 0:
            n2 = second_normal[i]
            if wp.dot(n1, n2) < FACING:
                gap = wp.dot(second_point[i] - contact_point[i], n1)
                off = off * wp.clamp(gap / (2.0 * off + thickness), 0.0, 1.0)
                d1 = off - wp.dot(p - contact_point[i], n1)
            move = two_plane_push(d1, n1, off - wp.dot(p - second_point[i], n2), n2)
            cap = wp.min(limit, crease_limit)
        push = wp.length(move)
        if push > cap:
            move = move * (cap / push)
            push = cap
        if push > 0.0:
            p = p + move
            body_push[i] = body_push[i] + push
    if ground == 1:
        depth = ground_height + thickness - p[2]
        if depth > 0.0:
            p = wp.vec3(p[0], p[1], ground_height + thickness)
            ground_push[i] = ground_push[i] + depth
    x[i] = p


@wp.func
def _coulomb(p: wp.vec3, start: wp.vec3, normal: wp.vec3, crease: wp.vec3, surface_velocity: wp.vec3, push: float,
             friction: float, dt: float):
    """Remove the tangential motion relative to the surface, up to friction * normal push. With a
    second contact plane (``crease``, its normal; zero if none) only motion along the crease line
    n x crease is tangential: the rest is what the two planes push."""
    slide = (p - start) - surface_velocity * dt
    tangential = slide - wp.dot(slide, normal) * normal
    line = wp.cross(normal, crease)
    if wp.length(line) > 1.0e-3:
        line = wp.normalize(line)
        tangential = wp.dot(slide, line) * line
    length = wp.length(tangential)
    if length <= friction * push:
        return p - tangential
    return p - tangential * (friction * push / length)


@wp.kernel
def apply_friction(x: wp.array(dtype=wp.vec3), x_start: wp.array(dtype=wp.vec3),
                   contact_normal: wp.array(dtype=wp.vec3), contact_velocity: wp.array(dtype=wp.vec3),
                   contact_face: wp.array(dtype=wp.int32), second_normal: wp.array(dtype=wp.vec3),
                   second_face: wp.array(dtype=wp.int32), friction: float, grip: wp.array(dtype=float),
                   face_grips: wp.array(dtype=float), dt: float, body_push: wp.array(dtype=float),
                   ground_push: wp.array(dtype=float)):
    """Coulomb friction once per substep, from the total normal push of the contact sweeps: the
    material's ``friction``, raised to the particle's ``grip[i]`` (a waistband) where its contact
    face grips (``face_grips[f]`` 1: the torso and hips; 0: an arm brushing past)."""
    i = wp.tid()
    p = x[i]
    if body_push[i] > 0.0:
        crease = wp.vec3(0.0)
        if second_face[i] >= 0:
            crease = second_normal[i]
        mu = friction
        face = contact_face[i]
        if face >= 0:
            mu = friction + (grip[i] - friction) * face_grips[face]
        p = _coulomb(p, x_start[i], contact_normal[i], crease, contact_velocity[i], body_push[i], mu, dt)
    if ground_push[i] > 0.0:
        p = _coulomb(p, x_start[i], wp.vec3(0.0, 0.0, 1.0), wp.vec3(0.0), wp.vec3(0.0), ground_push[i], friction, dt)
    x[i] = p
    body_push[i] = 0.0
    ground_push[i] = 0.0
