"""The ARAP energy (paper, Eq. 2; Sorkine & Alexa 2007) of a deformed mesh against its rest shape.

E(p) = sum_i sum_{j in N(i)} w_ij |(p_i - p_j) - R_i (r_i - r_j)|^2 over the spokes (directed edges)
of every vertex, w_ij = (cot a_ij + cot b_ij) / 2 (clamped to stay positive), R_i the rotation that
best maps vertex i's rest spokes onto its deformed ones. Arrays are [V,3] in the frame of the
template (the body's canonical frame, Y up), metres.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import torch

from darts.geometry.warp_runtime import warp

wp = warp()

#: Smallest cotangent weight kept: obtuse triangles give negative weights, which make the energy
#: indefinite; clamping them is the usual remedy.
MIN_WEIGHT = 1.0e-3


@dataclass
class ArapSystem:
    """Spokes of a rest mesh: directed edges ``heads`` -> ``tails`` [E] with weights [E] and rest
    vectors r_head - r_tail [E,3] (float64 tensors)."""

    rest: torch.Tensor
    heads: torch.Tensor
    tails: torch.Tensor
    weights: torch.Tensor
    rest_spokes: torch.Tensor

    @property
    def vertex_count(self) -> int:
        return self.rest.shape[0]

    def incidence(self) -> sp.csr_matrix:
        """K [E,V]: (K p)_e = p_head - p_tail, so that E = |sqrt(W) (K p - R r)|^2."""
        count = len(self.heads)
        rows = np.concatenate([np.arange(count), np.arange(count)])
        cols = np.concatenate([self.heads.numpy(), self.tails.numpy()])
        values = np.concatenate([np.ones(count), -np.ones(count)])
        return sp.csr_matrix((values, (rows, cols)), shape=(count, self.vertex_count))

    def laplacian(self) -> sp.csc_matrix:
        """K^T W K [V,V]: the matrix of the global step (twice the cotangent Laplacian)."""
        k = self.incidence()
        return (k.T @ sp.diags(self.weights.numpy()) @ k).tocsc()


def arap_system(vertices: np.ndarray, faces: np.ndarray) -> ArapSystem:
    """Spokes and cotangent weights of the rest mesh (vertices [V,3], faces [F,3])."""
    import gpytoolbox

    vertices = np.asarray(vertices, np.float64)
    faces = np.asarray(faces, np.int64)
    half = gpytoolbox.cotangent_weights(vertices, faces)  # [F,3]: cot/2 of the corner opposite each half-edge
    starts = np.concatenate([faces[:, 1], faces[:, 2], faces[:, 0]])
    ends = np.concatenate([faces[:, 2], faces[:, 0], faces[:, 1]])
    lo, hi = np.minimum(starts, ends), np.maximum(starts, ends)
    edges, inverse = np.unique(np.stack([lo, hi], 1), axis=0, return_inverse=True)
    weight = np.maximum(np.bincount(inverse.reshape(-1), weights=half.T.reshape(-1), minlength=len(edges)), MIN_WEIGHT)
    heads = np.concatenate([edges[:, 0], edges[:, 1]])
    tails = np.concatenate([edges[:, 1], edges[:, 0]])
    rest = torch.as_tensor(vertices)
    heads_t, tails_t = torch.as_tensor(heads), torch.as_tensor(tails)
    return ArapSystem(rest, heads_t, tails_t, torch.as_tensor(np.concatenate([weight, weight])),
                      rest[heads_t] - rest[tails_t])


@wp.func
def horn_matrix(m: wp.mat33d):
    """Horn's (1987) symmetric 4x4 N(m): q^T N q = tr(R(q) m) for a unit quaternion q = (w, x, y, z)."""
    return wp.mat44d(m[0, 0] + m[1, 1] + m[2, 2], m[1, 2] - m[2, 1], m[2, 0] - m[0, 2], m[0, 1] - m[1, 0],
                     m[1, 2] - m[2, 1], m[0, 0] - m[1, 1] - m[2, 2], m[0, 1] + m[1, 0], m[2, 0] + m[0, 2],
                     m[2, 0] - m[0, 2], m[0, 1] + m[1, 0], -m[0, 0] + m[1, 1] - m[2, 2], m[1, 2] + m[2, 1],
                     m[0, 1] - m[1, 0], m[2, 0] + m[0, 2], m[1, 2] + m[2, 1], -m[0, 0] - m[1, 1] + m[2, 2])


@wp.func
def quaternion_matrix(q: wp.vec4d):
    """The rotation matrix of the unit quaternion q = (w, x, y, z)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    one, two = wp.float64(1.0), wp.float64(2.0)
    return wp.mat33d(one - two * (y * y + z * z), two * (x * y - w * z), two * (x * z + w * y),
                     two * (x * y + w * z), one - two * (x * x + z * z), two * (y * z - w * x),
                     two * (x * z - w * y), two * (y * z + w * x), one - two * (x * x + y * y))


@wp.func
def minor(b: wp.mat44d, r0: int, r1: int, r2: int, c0: int, c1: int, c2: int):
    """Determinant of the 3x3 submatrix of b on rows r0, r1, r2 and columns c0, c1, c2."""
    return (b[r0, c0] * (b[r1, c1] * b[r2, c2] - b[r1, c2] * b[r2, c1])
            - b[r0, c1] * (b[r1, c0] * b[r2, c2] - b[r1, c2] * b[r2, c0])
            + b[r0, c2] * (b[r1, c0] * b[r2, c1] - b[r1, c1] * b[r2, c0]))


@wp.func
def null_vector(b: wp.mat44d):
    """Unit q with b q = 0 for a symmetric b of rank 3: b's adjugate is c q q^T, so q is its column
    of the largest diagonal entry (the principal minors), the best conditioned one."""
    d0 = minor(b, 1, 2, 3, 1, 2, 3)
    d1 = minor(b, 0, 2, 3, 0, 2, 3)
    d2 = minor(b, 0, 1, 3, 0, 1, 3)
    d3 = minor(b, 0, 1, 2, 0, 1, 2)
    q = wp.vec4d()
    if wp.abs(d0) >= wp.abs(d1) and wp.abs(d0) >= wp.abs(d2) and wp.abs(d0) >= wp.abs(d3):
        q = wp.vec4d(d0, -minor(b, 0, 2, 3, 1, 2, 3), minor(b, 0, 1, 3, 1, 2, 3), -minor(b, 0, 1, 2, 1, 2, 3))
    elif wp.abs(d1) >= wp.abs(d2) and wp.abs(d1) >= wp.abs(d3):
        q = wp.vec4d(-minor(b, 1, 2, 3, 0, 2, 3), d1, -minor(b, 0, 1, 3, 0, 2, 3), minor(b, 0, 1, 2, 0, 2, 3))
    elif wp.abs(d2) >= wp.abs(d3):
        q = wp.vec4d(minor(b, 1, 2, 3, 0, 1, 3), -minor(b, 0, 2, 3, 0, 1, 3), d2, -minor(b, 0, 1, 2, 0, 1, 3))
    else:
        q = wp.vec4d(-minor(b, 1, 2, 3, 0, 1, 2), minor(b, 0, 2, 3, 0, 1, 2), -minor(b, 0, 1, 3, 0, 1, 2), d3)
    return wp.normalize(q)


@wp.func
def nearest_rotation(covariance: wp.mat33d):
    """argmax_R tr(R S) over rotations for S = covariance (= V U^T from S = U diag(s) V^T with U's
    column of the smallest s negated if det < 0): the unit quaternion of N(S)'s largest eigenvalue
    (Horn 1987), reflections excluded by construction. The eigenvalue by Newton on the
    characteristic polynomial l^4 - 2|S|^2 l^2 - 8 det(S) l + det(N) from the bound sqrt(3)|S| down
    (monotone, stays above it), the eigenvector as the null vector of N - l I (its adjugate).
    Agrees with the SVD to 1e-12 and costs a sixth of Warp's svd3 on the CPU."""
    norm = wp.sqrt(wp.ddot(covariance, covariance))
    if norm == wp.float64(0.0):
        return wp.identity(n=3, dtype=wp.float64)
    m = covariance / norm  # |m| = 1: the eigenvalues lie in [-sqrt(3), sqrt(3)]
    n = horn_matrix(m)
    det_m = wp.determinant(m)
    det_n = wp.determinant(n)
    largest = wp.sqrt(wp.float64(3.0))
    for _ in range(60):
        value = ((largest * largest - wp.float64(2.0)) * largest - wp.float64(8.0) * det_m) * largest + det_n
        slope = wp.float64(4.0) * largest * largest * largest - wp.float64(4.0) * largest - wp.float64(8.0) * det_m
        step = value / slope
        largest = largest - step
        if wp.abs(step) < wp.float64(1.0e-15):
            break
    return quaternion_matrix(null_vector(n - largest * wp.identity(n=4, dtype=wp.float64)))


@wp.kernel
def _rotations_from_covariances(covariance: wp.array(dtype=wp.mat33d), rotation: wp.array(dtype=wp.mat33d)):
    i = wp.tid()
    rotation[i] = nearest_rotation(covariance[i])


def best_rotations(system: ArapSystem, vertices: torch.Tensor) -> torch.Tensor:
    """R_i [V,3,3] = V_i U_i^T from the SVD of S_i = sum_j w_ij (r_i - r_j)(p_i - p_j)^T, with the
    sign of U's column of the smallest singular value flipped where det(V U^T) < 0 (so that R_i is
    a rotation, not a reflection). Differentiable (torch's SVD) when ``vertices`` needs a gradient,
    else the same rotation by Horn's quaternion method in Warp (``nearest_rotation``, several times faster)."""
    spokes = vertices[system.heads] - vertices[system.tails]
    outer = system.weights[:, None, None] * system.rest_spokes[:, :, None] * spokes[:, None, :]
    covariance = torch.zeros(system.vertex_count, 3, 3, dtype=vertices.dtype).index_add(0, system.heads, outer)
    if not (torch.is_grad_enabled() and covariance.requires_grad):
        result = wp.zeros(system.vertex_count, dtype=wp.mat33d, device="cpu")
        wp.launch(_rotations_from_covariances, dim=system.vertex_count,
                  inputs=[wp.array(covariance.double().contiguous().numpy(), dtype=wp.mat33d, device="cpu"), result],
                  device="cpu")
        return torch.from_numpy(result.numpy()).to(vertices.dtype)
    u, _, vh = torch.linalg.svd(covariance)
    flip = torch.ones(system.vertex_count, 3, dtype=vertices.dtype)
    flip[:, 2] = torch.sign(torch.linalg.det(vh.transpose(1, 2) @ u.transpose(1, 2))).detach()
    flip[:, 2][flip[:, 2] == 0] = 1.0
    return vh.transpose(1, 2) @ (u * flip[:, None, :]).transpose(1, 2)


def rotated_rest_spokes(system: ArapSystem, rotations: torch.Tensor) -> torch.Tensor:
    """R_head (r_head - r_tail) [E,3]: where each spoke should point."""
    return torch.einsum("eab,eb->ea", rotations[system.heads], system.rest_spokes)


def arap_energy(system: ArapSystem, vertices: torch.Tensor, rotations: torch.Tensor | None = None) -> torch.Tensor:
    """E of Eq. 2. Without ``rotations`` the best ones are used, detached: the energy is minimal in
    them, so dE/dp at fixed R is the exact gradient."""
    if rotations is None:
        rotations = best_rotations(system, vertices.detach())
    spokes = vertices[system.heads] - vertices[system.tails]
    residual = spokes - rotated_rest_spokes(system, rotations)
    return (system.weights * (residual * residual).sum(1)).sum()
