"""The ARAP local step in two Warp kernels (no gradient): best rotations, the global step's
right-hand side and the ARAP energy, walking each vertex's spokes (CSR) instead of building [E,3,3]
tensors. Same math as ``darts.crdl.arap`` (which stays the differentiable path):

    R_i = argmax_R tr(R S_i), S_i = sum_j w_ij (r_i - r_j)(p_i - p_j)^T   (Horn's quaternion method)
    b_i = sum_j w_ij (R_i + R_j)(r_i - r_j)                          (= K^T W (R r))
    E   = sum_i sum_j w_ij |(p_i - p_j) - R_i (r_i - r_j)|^2
"""
from __future__ import annotations

import numpy as np
import torch

from darts.crdl.arap import ArapSystem, nearest_rotation
from darts.geometry.warp_runtime import warp

wp = warp()


@wp.kernel
def _rotations(offsets: wp.array(dtype=wp.int32), tails: wp.array(dtype=wp.int32), weights: wp.array(dtype=wp.float64),
               rest_spokes: wp.array(dtype=wp.vec3d), x: wp.array(dtype=wp.vec3d), rotation: wp.array(dtype=wp.mat33d)):
    i = wp.tid()
    covariance = wp.mat33d()
    for k in range(offsets[i], offsets[i + 1]):
        covariance += weights[k] * wp.outer(rest_spokes[k], x[i] - x[tails[k]])
    rotation[i] = nearest_rotation(covariance)


@wp.kernel
def _rhs_and_energy(offsets: wp.array(dtype=wp.int32), tails: wp.array(dtype=wp.int32), weights: wp.array(dtype=wp.float64),
                    rest_spokes: wp.array(dtype=wp.vec3d), x: wp.array(dtype=wp.vec3d), rotation: wp.array(dtype=wp.mat33d),
                    rhs: wp.array(dtype=wp.vec3d), energy: wp.array(dtype=wp.float64)):
    i = wp.tid()
    b = wp.vec3d()
    e = wp.float64(0.0)
    for k in range(offsets[i], offsets[i + 1]):
        j = tails[k]
        rotated = rotation[i] * rest_spokes[k]
        b += weights[k] * (rotated + rotation[j] * rest_spokes[k])
        residual = x[i] - x[j] - rotated
        e += weights[k] * wp.dot(residual, residual)
    rhs[i] = b
    wp.atomic_add(energy, 0, e)


class LocalStep:
    """Best rotations, b = K^T W R r and E_arap at p, for one ArapSystem (Warp CPU)."""

    def __init__(self, system: ArapSystem):
        heads = system.heads.numpy()
        order = np.argsort(heads, kind="stable")
        counts = np.bincount(heads, minlength=system.vertex_count)
        self.count = system.vertex_count
        self.offsets = wp.array(np.concatenate([[0], np.cumsum(counts)]).astype(np.int32), dtype=wp.int32, device="cpu")
        self.tails = wp.array(system.tails.numpy()[order].astype(np.int32), dtype=wp.int32, device="cpu")
        self.weights = wp.array(system.weights.numpy()[order], dtype=wp.float64, device="cpu")
        self.rest_spokes = wp.array(system.rest_spokes.numpy()[order], dtype=wp.vec3d, device="cpu")
        self.x = wp.zeros(self.count, dtype=wp.vec3d, device="cpu")
        self.rotation = wp.zeros(self.count, dtype=wp.mat33d, device="cpu")
        self.rhs = wp.zeros(self.count, dtype=wp.vec3d, device="cpu")
        self.energy = wp.zeros(1, dtype=wp.float64, device="cpu")

    def __call__(self, vertices: torch.Tensor) -> tuple[float, torch.Tensor]:
        """(E_arap at the best rotations, b [V,3]) at ``vertices`` [V,3]."""
        self.x.assign(np.ascontiguousarray(vertices.detach().numpy(), np.float64))
        self.energy.zero_()
        inputs = [self.offsets, self.tails, self.weights, self.rest_spokes, self.x]
        wp.launch(_rotations, dim=self.count, inputs=[*inputs, self.rotation], device="cpu")
        wp.launch(_rhs_and_energy, dim=self.count, inputs=[*inputs, self.rotation, self.rhs, self.energy], device="cpu")
        return float(self.energy.numpy()[0]), torch.from_numpy(self.rhs.numpy().copy())
