"""Warp kernels of the cloth step that more than one part of the engine uses (world frame, Z up, SI
units): air forces and velocities (both integrators), the inside-the-body test (the collider's
contacts and the frame's measures), the dihedral angle's gradient (bending in both integrators),
the frame's measures and the edges through a mesh (an outfit's layers). The body contact's own
kernels are in ``collider_kernels``, each solver's beside it (``solvers/xpbd_kernels``).

Constraint kernels take an ``offset`` so that one launch can cover one colour of a colour-sorted
constraint list (race-free on CUDA) or, on the CPU backend, which runs a launch's threads in order,
the whole list at once with the same result.
"""
from __future__ import annotations

from darts.geometry.warp_runtime import warp

wp = warp()


@wp.kernel
def aerodynamic_forces(faces: wp.array2d(dtype=wp.int32), x: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3),
                       wind: wp.vec3, air_density: float, drag_coefficient: float, force: wp.array(dtype=wp.vec3)):
    """Wind and air drag on each face: F = 1/2 rho C_d A (u.n)|u.n| n, u = wind - face velocity."""
    f = wp.tid()
    a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
    scaled = wp.cross(x[b] - x[a], x[c] - x[a])
    double_area = wp.length(scaled)
    if double_area < 1.0e-12:
        return
    n = scaled / double_area
    u = wind - (v[a] + v[b] + v[c]) / 3.0
    un = wp.dot(u, n)
    share = (0.5 * air_density * drag_coefficient * 0.5 * double_area * un * wp.abs(un) / 3.0) * n
    wp.atomic_add(force, a, share)
    wp.atomic_add(force, b, share)
    wp.atomic_add(force, c, share)


@wp.kernel
def velocities_from_positions(x: wp.array(dtype=wp.vec3), x_start: wp.array(dtype=wp.vec3), dt: float,
                              v: wp.array(dtype=wp.vec3)):
    """v = (x - x_start) / dt."""
    i = wp.tid()
    v[i] = (x[i] - x_start[i]) / dt


@wp.kernel
def velocities_less_push_out(x: wp.array(dtype=wp.vec3), x_start: wp.array(dtype=wp.vec3), dt: float,
                             contact_point: wp.array(dtype=wp.vec3), normal: wp.array(dtype=wp.vec3),
                             surface_velocity: wp.array(dtype=wp.vec3), contact_face: wp.array(dtype=wp.int32),
                             thickness: float, offset: wp.array(dtype=float), v: wp.array(dtype=wp.vec3)):
    """v = (x - x_start - e n) / dt, e = min(d0, max(0, (x - x_start - u dt).n)): the part of the
    move out along the contact normal n (relative to the surface, moving at u) that only undid the
    particle's depth d0 = max(0, thickness + offset - (x_start - (point - u dt)).n) inside its
    contact's thickness at the substep's start (against the plane where its face was then) is a
    correction, not motion (pre-stabilisation, Macklin et al. 2014, 4.4: the correction applied to the
    start position too), so a particle pushed out of a depth it already had does not fly on."""
    i = wp.tid()
    move = x[i] - x_start[i]
    if contact_face[i] >= 0:
        n = normal[i]
        start_point = contact_point[i] - surface_velocity[i] * dt
        depth = wp.max(thickness + offset[i] - wp.dot(x_start[i] - start_point, n), 0.0)
        if depth > 0.0:
            out = wp.dot(move - surface_velocity[i] * dt, n)
            move = move - wp.min(depth, wp.max(out, 0.0)) * n
    v[i] = move / dt


@wp.kernel
def track_fastest(v: wp.array(dtype=wp.vec3), world: wp.array(dtype=wp.int32), fastest: wp.array(dtype=float)):
    """fastest[w] = max(fastest[w], |v_i|) over the particles i of each world w: the largest speed of
    any substep (reset once a frame), which tells cloth buzzing between contacts inside the substeps
    from what the recorded frames show."""
    i = wp.tid()
    wp.atomic_max(fastest, world[i], wp.length(v[i]))


@wp.func
def inside_body(mesh: wp.uint64, p: wp.vec3, reach: float):
    """Is p inside the body, less than ``reach`` from its surface (the sign of its closest point)."""
    query = wp.mesh_query_point_sign_normal(mesh, p, reach)
    return query.result and query.sign < 0.0


#: m a ray from a body surface point looks along its outward direction for the surface of another
#: body part it lies inside of (deeper than the deepest overlap of two posed parts: a calf folded
#: into a thigh)
BURIED_REACH = wp.constant(0.25)


@wp.func
def buried(mesh: wp.uint64, point: wp.vec3, out: wp.vec3):
    """Is the body surface at ``point`` (outward direction ``out``) inside another part of the body,
    where the posed body overlaps itself? Then the first surface a ray from it along ``out`` meets is
    that part's, from behind (one ray; the closest point's sign cannot tell: near a buried face its
    own face is the closest)."""
    hit = wp.mesh_query_ray(mesh, point + 1.0e-4 * out, out, BURIED_REACH)
    return hit.result and hit.sign < 0.0


@wp.func
def angle_of(sine: float, cosine: float):
    """atan2(sine, cosine) (the two scaled alike): where |angle| < 45 degrees (cosine > |sine|: every
    hinge near its rest angle), an odd minimax polynomial of t = sine / cosine, arctan t within
    1.7e-6 rad on [-1, 1] (cheaper than libm's atan2: the bending sweep 24 % faster); atan2 elsewhere."""
    if cosine > wp.abs(sine):
        t = sine / cosine
        t2 = t * t
        return t * (0.999977218 + t2 * (-0.332622808 + t2 * (0.193540258 + t2 * (-0.116426204 + t2 * (
            0.052647065 + t2 * -0.011719029)))))
    return wp.atan2(sine, cosine)


@wp.func
def dihedral_gradient(xi: wp.vec3, xj: wp.vec3, xk: wp.vec3, xl: wp.vec3, rest_cos: float, rest_sin: float):
    """Angle of the hinge (edge i-j; triangles (i, j, k) and (j, i, l); 0 when flat) less its rest
    angle (given by its cosine and sine), wrapped into [-pi, pi], and the angle's gradient."""
    e = xj - xi
    e_len2 = wp.dot(e, e)
    n1 = wp.cross(e, xk - xi)
    n2 = wp.cross(xl - xi, e)
    a1_2 = wp.dot(n1, n1)  # (twice the triangles' areas)^2
    a2_2 = wp.dot(n2, n2)
    if e_len2 < 1.0e-16 or a1_2 < 1.0e-32 or a2_2 < 1.0e-32:
        return 0.0, wp.vec3(0.0), wp.vec3(0.0), wp.vec3(0.0), wp.vec3(0.0), 0
    e_len = wp.sqrt(e_len2)
    inverse_e_len2 = 1.0 / e_len2
    # cos and sin of the angle, both times |n1| |n2| |e| (no normalising: angle_of takes their ratio);
    # those of (angle - rest) by the difference formulas, so no wrapping is needed
    cosine = wp.dot(n1, n2) * e_len
    sine = wp.dot(wp.cross(n1, n2), e)
    error = angle_of(sine * rest_cos - cosine * rest_sin, cosine * rest_cos + sine * rest_sin)
    # d(angle)/dx_k = -n1 |e| / |n1|^2 and d(angle)/dx_l = -n2 |e| / |n2|^2 (the unit normal over the
    # distance of k, l from the edge line); the edge ends take the rest so that the gradient is
    # translation and rotation invariant.
    gk = -n1 * (e_len / a1_2)
    gl = -n2 * (e_len / a2_2)
    sk = wp.dot(xk - xi, e) * inverse_e_len2
    sl = wp.dot(xl - xi, e) * inverse_e_len2
    gi = -(1.0 - sk) * gk - (1.0 - sl) * gl
    gj = -sk * gk - sl * gl
    return error, gi, gj, gk, gl, 1


@wp.kernel
def frame_measures(mesh: wp.uint64, winding_mesh: wp.uint64, bodies: int, winding: int, x: wp.array(dtype=wp.vec3),
                   v: wp.array(dtype=wp.vec3), world: wp.array(dtype=wp.int32),
                   inside: wp.array2d(dtype=wp.int32), max_speed: wp.array(dtype=float),
                   finite: wp.array(dtype=wp.int32)):
    """Per frame and per world w (``world[i]``: particle i's): particles inside the body (sign by the
    angle-weighted pseudo-normal at the closest point, exact for a closed body that does not
    intersect itself) in inside[w, 0], those of them whose closest body point is ``buried`` inside
    another part of the body (the posed body overlaps itself there) in inside[w, 1], inside the body
    by its winding number in inside[w, 2] (``winding``), those of them it covers twice (winding
    number > 1.5: inside two parts where the posed body overlaps itself) in inside[w, 3], the largest
    speed in max_speed[w], any non-finite value (finite[w] = 0).
    ``bodies`` 0: only the speed and the finite check (no body query)."""
    i = wp.tid()
    p = x[i]
    vi = v[i]
    w = world[i]
    if not (wp.isfinite(p) and wp.isfinite(vi)):
        wp.atomic_min(finite, w, 0)
        return
    wp.atomic_max(max_speed, w, wp.length(vi))
    if bodies == 0:
        return
    query = wp.mesh_query_point_sign_normal(mesh, p, 10.0)
    if query.result and query.sign < 0.0:
        wp.atomic_add(inside, w, 0, 1)
        if buried(mesh, wp.mesh_eval_position(mesh, query.face, query.u, query.v), wp.mesh_eval_face_normal(mesh, query.face)):
            wp.atomic_add(inside, w, 1, 1)
    if winding != 0:
        by_winding = wp.mesh_query_point_sign_winding_number(winding_mesh, p, 10.0)
        if by_winding.result and by_winding.sign < 0.0:
            wp.atomic_add(inside, w, 2, 1)
            twice = wp.mesh_query_point_sign_winding_number(winding_mesh, p, 10.0, 2.0, 1.5)
            if twice.result and twice.sign < 0.0:
                wp.atomic_add(inside, w, 3, 1)


@wp.kernel
def edges_through_mesh(mesh: wp.uint64, x: wp.array(dtype=wp.vec3), edges: wp.array2d(dtype=wp.int32),
                       hits: wp.array(dtype=wp.int32)):
    """hits[e] = 1 where edge e (particles ``edges[e]`` at ``x``) passes through a triangle of ``mesh``."""
    e = wp.tid()
    a = x[edges[e, 0]]
    d = x[edges[e, 1]] - a
    length = wp.length(d)
    if length < 1.0e-9:
        return
    query = wp.mesh_query_ray(mesh, a, d / length, length)
    if query.result:
        hits[e] = 1
