"""Warp kernels of the XPBD solver (``sim.engine.solvers.xpbd``; world frame, Z up, SI units): the
prediction, distance and tether constraints, bending. Constraint kernels take an ``offset`` (one
colour of a colour-sorted list per launch, or the whole list on the CPU backend).
"""
from __future__ import annotations

from darts.geometry.warp_runtime import warp
from sim.engine.kernels import dihedral_gradient

wp = warp()


@wp.kernel
def predict(x_in: wp.array(dtype=wp.vec3), v_in: wp.array(dtype=wp.vec3), force: wp.array(dtype=wp.vec3),
            inverse_mass: wp.array(dtype=float), gravity: wp.vec3, dt: float, damping: float,
            x_out: wp.array(dtype=wp.vec3), v_out: wp.array(dtype=wp.vec3)):
    """Explicit velocity step then position prediction: v <- d (v + dt (g + f / m)), x <- x + dt v."""
    i = wp.tid()
    vi = damping * (v_in[i] + dt * (gravity + force[i] * inverse_mass[i]))
    v_out[i] = vi
    x_out[i] = x_in[i] + dt * vi


@wp.kernel
def solve_distances(offset: int, pairs: wp.array2d(dtype=wp.int32), rest: wp.array(dtype=float),
                    compliance: wp.array(dtype=float), anchors: wp.array2d(dtype=wp.int32),
                    inverse_mass: wp.array(dtype=float), dt: float, multiplier: wp.array(dtype=float),
                    x: wp.array(dtype=wp.vec3)):
    """XPBD distance constraint C = |x_a - x_b| - L with compliance 1/k.

    When the ends coincide and L > 0 (a repulsive seam), they separate along their anchors: each end
    retreats towards an interior particle of its own panel."""
    c = wp.tid() + offset
    a, b = pairs[c, 0], pairs[c, 1]
    wa, wb = inverse_mass[a], inverse_mass[b]
    d = x[a] - x[b]
    length = wp.length(d)
    if length < 1.0e-7:
        if rest[c] <= 0.0 or anchors[c, 0] < 0 or anchors[c, 1] < 0:
            return
        d = (x[anchors[c, 0]] - x[a]) - (x[anchors[c, 1]] - x[b])
        if wp.length(d) < 1.0e-9:
            return
        d = wp.normalize(d) * 1.0e-7
        length = 1.0e-7
    n = d / length
    alpha = compliance[c] / (dt * dt)
    step = (-(length - rest[c]) - alpha * multiplier[c]) / (wa + wb + alpha)
    multiplier[c] = multiplier[c] + step
    x[a] = x[a] + wa * step * n
    x[b] = x[b] - wb * step * n


@wp.kernel
def solve_max_distances(offset: int, pairs: wp.array2d(dtype=wp.int32), limit: wp.array(dtype=float),
                        inverse_mass: wp.array(dtype=float), x: wp.array(dtype=wp.vec3)):
    """Unilateral distance limit (a tether) C = |x_a - x_b| - limit <= 0, zero compliance: only a
    pair farther apart than its limit is moved, back to it, by inverse mass."""
    c = wp.tid() + offset
    a, b = pairs[c, 0], pairs[c, 1]
    d = x[a] - x[b]
    length2 = wp.dot(d, d)
    if length2 <= limit[c] * limit[c]:  # slack (most tethers): no square root
        return
    wa, wb = inverse_mass[a], inverse_mass[b]
    if wa + wb <= 0.0:
        return
    length = wp.sqrt(length2)
    step = (limit[c] - length) / (wa + wb)
    n = d / length
    x[a] = x[a] + wa * step * n
    x[b] = x[b] - wb * step * n


@wp.kernel
def solve_bending(offset: int, hinges: wp.array2d(dtype=wp.int32), rest_cos: wp.array(dtype=float),
                  rest_sin: wp.array(dtype=float), compliance: wp.array(dtype=float),
                  inverse_mass: wp.array(dtype=float), dt: float, multiplier: wp.array(dtype=float),
                  x: wp.array(dtype=wp.vec3)):
    """XPBD dihedral constraint C = angle - rest angle (wrapped to [-pi, pi]) with compliance 1/kappa."""
    h = wp.tid() + offset
    i, j, k, l = hinges[h, 0], hinges[h, 1], hinges[h, 2], hinges[h, 3]
    c, gi, gj, gk, gl, ok = dihedral_gradient(x[i], x[j], x[k], x[l], rest_cos[h], rest_sin[h])
    if ok == 0:
        return
    wi, wj, wk, wl = inverse_mass[i], inverse_mass[j], inverse_mass[k], inverse_mass[l]
    weight = wi * wp.dot(gi, gi) + wj * wp.dot(gj, gj) + wk * wp.dot(gk, gk) + wl * wp.dot(gl, gl)
    alpha = compliance[h] / (dt * dt)
    if weight + alpha < 1.0e-20:
        return
    step = (-c - alpha * multiplier[h]) / (weight + alpha)
    multiplier[h] = multiplier[h] + step
    x[i] = x[i] + wi * step * gi
    x[j] = x[j] + wj * step * gj
    x[k] = x[k] + wk * step * gk
    x[l] = x[l] + wl * step * gl
