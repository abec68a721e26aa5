"""Semi-implicit mass-spring solver (Baraff & Witkin 1998): one linearised backward-Euler step.

Per substep solve (M + h^2 H) dv = h (f + h g M) - h^2 H v with H the stiffness matrix (springs:
k [n n^T + max(0, 1 - L/l)(I - n n^T)], kept positive semi-definite; hinges: kappa g g^T), by a
fixed number of Jacobi-preconditioned conjugate-gradient iterations started from free fall,
dv0 = h g (exact for a garment in free fall), all on the device;
then x += h v, contacts and friction as in XPBD, v = dx / h.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.engine import kernels
from sim.engine.solvers.base import Solver, hinge_rest_cos_sin, hinge_stiffness

wp = warp()


@wp.func
def _spring_block(d: wp.vec3, rest: float, stiffness: float):
    length = wp.length(d)
    if length < 1.0e-9:
        return wp.vec3(0.0), stiffness * wp.identity(n=3, dtype=float)
    n = d / length
    nn = wp.outer(n, n)
    slack = wp.max(0.0, 1.0 - rest / length)
    return -stiffness * (length - rest) * n, stiffness * (nn + slack * (wp.identity(n=3, dtype=float) - nn))


@wp.kernel
def spring_forces(pairs: wp.array2d(dtype=wp.int32), rest: wp.array(dtype=float), stiffness: wp.array(dtype=float),
                  x: wp.array(dtype=wp.vec3), force: wp.array(dtype=wp.vec3), blocks: wp.array(dtype=wp.mat33),
                  diagonal: wp.array(dtype=float)):
    """Spring force f_a = -k (l - L) n (f_b = -f_a), its stiffness block, and the block's trace / 3."""
    c = wp.tid()
    a, b = pairs[c, 0], pairs[c, 1]
    f, block = _spring_block(x[a] - x[b], rest[c], stiffness[c])
    blocks[c] = block
    wp.atomic_add(force, a, f)
    wp.atomic_sub(force, b, f)
    t = (block[0, 0] + block[1, 1] + block[2, 2]) / 3.0
    wp.atomic_add(diagonal, a, t)
    wp.atomic_add(diagonal, b, t)


@wp.kernel
def hinge_forces(hinges: wp.array2d(dtype=wp.int32), rest_cos: wp.array(dtype=float), rest_sin: wp.array(dtype=float),
                 kappa: wp.array(dtype=float), x: wp.array(dtype=wp.vec3), force: wp.array(dtype=wp.vec3),
                 gradients: wp.array2d(dtype=wp.vec3), diagonal: wp.array(dtype=float)):
    """Bending force f = -kappa (angle - rest) d(angle)/dx and its Gauss-Newton stiffness kappa g g^T."""
    h = wp.tid()
    c, gi, gj, gk, gl, ok = kernels.dihedral_gradient(x[hinges[h, 0]], x[hinges[h, 1]], x[hinges[h, 2]], x[hinges[h, 3]],
                                                      rest_cos[h], rest_sin[h])  # (zeros where degenerate)
    gradients[h, 0] = gi
    gradients[h, 1] = gj
    gradients[h, 2] = gk
    gradients[h, 3] = gl
    for corner in range(4):
        g = gradients[h, corner]
        wp.atomic_add(force, hinges[h, corner], -kappa[h] * c * g)
        wp.atomic_add(diagonal, hinges[h, corner], kappa[h] * wp.dot(g, g) / 3.0)


@wp.kernel
def mass_times(mass: wp.array(dtype=float), scale: float, p: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
    """out = scale * M p (the start of a matrix-vector product)."""
    i = wp.tid()
    out[i] = scale * mass[i] * p[i]


@wp.kernel
def add_spring_product(pairs: wp.array2d(dtype=wp.int32), blocks: wp.array(dtype=wp.mat33), scale: float,
                       p: wp.array(dtype=wp.vec3), out: wp.array(dtype=wp.vec3)):
    """out += scale * H_springs p."""
    c = wp.tid()
    a, b = pairs[c, 0], pairs[c, 1]
    y = scale * (blocks[c] * (p[a] - p[b]))
    wp.atomic_add(out, a, y)
    wp.atomic_sub(out, b, y)


@wp.kernel
def add_hinge_product(hinges: wp.array2d(dtype=wp.int32), gradients: wp.array2d(dtype=wp.vec3),
                      kappa: wp.array(dtype=float), scale: float, p: wp.array(dtype=wp.vec3),
                      out: wp.array(dtype=wp.vec3)):
    """out += scale * kappa g (g . p) over the hinge's four corners."""
    h = wp.tid()
    s = float(0.0)
    for corner in range(4):
        s += wp.dot(gradients[h, corner], p[hinges[h, corner]])
    for corner in range(4):
        wp.atomic_add(out, hinges[h, corner], (scale * kappa[h] * s) * gradients[h, corner])


@wp.kernel
def gravity_guess(v: wp.array(dtype=wp.vec3), gravity: wp.vec3, dt: float, dv: wp.array(dtype=wp.vec3),
                  v_guess: wp.array(dtype=wp.vec3)):
    """Start from free fall, dv0 = h g; v_guess = v + dv0."""
    i = wp.tid()
    dv[i] = dt * gravity
    v_guess[i] = v[i] + dt * gravity


@wp.kernel
def start_solve(force: wp.array(dtype=wp.vec3), dt: float, stiffness_v: wp.array(dtype=wp.vec3),
                mass: wp.array(dtype=float), diagonal: wp.array(dtype=float), scale: float,
                residual: wp.array(dtype=wp.vec3), z: wp.array(dtype=wp.vec3), direction: wp.array(dtype=wp.vec3),
                rz: wp.array(dtype=float)):
    """r = b - A dv0 = h f - h^2 H (v + dv0) (the gravity terms cancel); z = P^-1 r; p = z; rz = r.z."""
    i = wp.tid()
    r = dt * force[i] - stiffness_v[i]
    zi = r / (mass[i] + scale * diagonal[i])
    residual[i] = r
    z[i] = zi
    direction[i] = zi
    wp.atomic_add(rz, 0, wp.dot(r, zi))


@wp.kernel
def dot_into(a: wp.array(dtype=wp.vec3), b: wp.array(dtype=wp.vec3), out: wp.array(dtype=float)):
    """out[0] += a . b."""
    i = wp.tid()
    wp.atomic_add(out, 0, wp.dot(a[i], b[i]))


@wp.kernel
def cg_update(direction: wp.array(dtype=wp.vec3), product: wp.array(dtype=wp.vec3), rz: wp.array(dtype=float),
              p_ap: wp.array(dtype=float), mass: wp.array(dtype=float), diagonal: wp.array(dtype=float),
              scale: float, dv: wp.array(dtype=wp.vec3), residual: wp.array(dtype=wp.vec3),
              z: wp.array(dtype=wp.vec3), rz_next: wp.array(dtype=float)):
    """alpha = r.z / p.Ap; dv += alpha p; r -= alpha Ap; z = P^-1 r; accumulate the new r.z."""
    i = wp.tid()
    alpha = float(0.0)
    if p_ap[0] > 1.0e-30:
        alpha = rz[0] / p_ap[0]
    dv[i] = dv[i] + alpha * direction[i]
    r = residual[i] - alpha * product[i]
    residual[i] = r
    zi = r / (mass[i] + scale * diagonal[i])
    z[i] = zi
    wp.atomic_add(rz_next, 0, wp.dot(r, zi))


@wp.kernel
def cg_direction(z: wp.array(dtype=wp.vec3), rz: wp.array(dtype=float), rz_next: wp.array(dtype=float),
                 direction: wp.array(dtype=wp.vec3)):
    """p = z + beta p with beta = r.z (new) / r.z (old)."""
    i = wp.tid()
    beta = float(0.0)
    if rz[0] > 1.0e-30:
        beta = rz_next[0] / rz[0]
    direction[i] = z[i] + beta * direction[i]


@wp.kernel
def advance(x_in: wp.array(dtype=wp.vec3), v_in: wp.array(dtype=wp.vec3), dv: wp.array(dtype=wp.vec3), dt: float,
            damping: float, x_out: wp.array(dtype=wp.vec3), v_out: wp.array(dtype=wp.vec3)):
    """v <- d (v + dv); x <- x + h v."""
    i = wp.tid()
    vi = damping * (v_in[i] + dv[i])
    v_out[i] = vi
    x_out[i] = x_in[i] + dt * vi


class MassSpringSolver(Solver):
    """``--solver mass-spring``: springs on every edge (the material's stretch stiffness) and seam
    pair, hinges with kappa from ``hinge_stiffness``, integrated semi-implicitly."""

    name = "mass-spring"
    default_substeps = 10

    def __init__(self, model, state, settings):
        super().__init__(model, state, settings)
        device = self.device
        pairs, rest, stiffness = model.springs_and_edges()
        self.pairs = wp.array(pairs, dtype=wp.int32, device=device)
        self.rest = wp.array(rest.astype(np.float32), device=device)
        self.stiffness = wp.array(stiffness.astype(np.float32), device=device)
        self.hinges = wp.array(model.hinges.astype(np.int32), dtype=wp.int32, device=device)
        self.rest_cos, self.rest_sin = (wp.array(values.astype(np.float32), device=device)
                                        for values in hinge_rest_cos_sin(model))
        self.kappa = wp.array(hinge_stiffness(model).astype(np.float32), device=device)
        self.blocks = wp.zeros(len(pairs), dtype=wp.mat33, device=device)
        self.gradients = wp.zeros((len(model.hinges), 4), dtype=wp.vec3, device=device)
        n = self.count
        self.diagonal = wp.zeros(n, dtype=float, device=device)
        self.dv, self.residual, self.z, self.direction, self.product = (
            wp.zeros(n, dtype=wp.vec3, device=device) for _ in range(5))
        self.scalars = wp.zeros(2 * settings.cg_iterations + 1, dtype=float, device=device)  # r.z, p.Ap, ...
        self.scalar = [self.scalars[k:k + 1] for k in range(len(self.scalars))]  # one view each, made once

    def _stiffness_product(self, p, scale: float, mass_scale: float) -> None:
        """product = mass_scale M p + scale H p."""
        self.launch(mass_times, self.count, [self.mass, mass_scale, p, self.product])
        self.launch(add_spring_product, self.pairs.shape[0], [self.pairs, self.blocks, scale, p, self.product])
        self.launch(add_hinge_product, self.hinges.shape[0], [self.hinges, self.gradients, self.kappa, scale, p, self.product])

    def step(self, state_in, state_out, collider, dt, time, substep):
        h2 = dt * dt
        self.external_forces(state_in, time)
        self.diagonal.zero_()
        self.scalars.zero_()
        self.launch(spring_forces, self.pairs.shape[0],
                    [self.pairs, self.rest, self.stiffness, state_in.x, self.force, self.blocks, self.diagonal])
        self.launch(hinge_forces, self.hinges.shape[0],
                    [self.hinges, self.rest_cos, self.rest_sin, self.kappa, state_in.x, self.force, self.gradients,
                     self.diagonal])
        self.launch(gravity_guess, self.count, [state_in.v, wp.vec3(*self.settings.gravity), dt, self.dv, self.z])
        self._stiffness_product(self.z, h2, 0.0)  # h^2 H (v + dv0)
        rz = self.scalar[0]
        self.launch(start_solve, self.count, [self.force, dt, self.product, self.mass, self.diagonal, h2, self.residual,
                                              self.z, self.direction, rz])
        for k in range(self.settings.cg_iterations):
            p_ap, rz_next = self.scalar[2 * k + 1], self.scalar[2 * k + 2]
            self._stiffness_product(self.direction, h2, 1.0)
            self.launch(dot_into, self.count, [self.direction, self.product, p_ap])
            self.launch(cg_update, self.count, [self.direction, self.product, rz, p_ap, self.mass, self.diagonal, h2,
                                                self.dv, self.residual, self.z, rz_next])
            self.launch(cg_direction, self.count, [self.z, rz, rz_next, self.direction])
            rz = rz_next
        self.launch(advance, self.count, [state_in.x, state_in.v, self.dv, dt, self.damping, state_out.x, state_out.v])
        self.find_contacts(state_in, state_out, collider, dt, substep)
        self.resolve_contacts(state_out, collider)
        self.finish(state_in, state_out, collider, dt)
