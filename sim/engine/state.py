"""The cloth's state at one instant: particle positions and velocities on the device.

World frame (Z up), metres and metres per second. A ``Simulation`` keeps two: the state a substep
starts from (``state_in``) and the one it writes (``state_out``), which is always the same object so
that whatever is built on its positions (the self-contact BVH) stays valid.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp

wp = warp()


def on_cpu(device: str) -> bool:
    """Whether Warp's ``device`` is the CPU backend (the one device check of the engine: a CUDA
    device takes per-colour launches, graph capture and device-side reductions instead)."""
    return wp.get_device(device).is_cpu


def vec3_array(values: np.ndarray, device: str):
    """``values`` [N,3] as a Warp vec3 array (float32) on ``device``."""
    return wp.array(np.ascontiguousarray(values, np.float32), dtype=wp.vec3, device=device)


def int_array(values: np.ndarray, device: str):
    """``values`` as a Warp int32 array (any shape) on ``device``."""
    return wp.array(np.ascontiguousarray(values, np.int32), dtype=wp.int32, device=device)


def float_array(values: np.ndarray, device: str):
    """``values`` as a Warp float32 array on ``device``."""
    return wp.array(np.ascontiguousarray(values, np.float32), dtype=float, device=device)


class ClothState:
    """Particle positions ``x`` [P] and velocities ``v`` [P] (Warp vec3 arrays)."""

    def __init__(self, positions: np.ndarray, device: str):
        self.x = vec3_array(positions, device)
        self.v = wp.zeros_like(self.x)

    def assign(self, other: ClothState) -> None:
        """Copy ``other``'s positions and velocities into this state."""
        wp.copy(self.x, other.x)
        wp.copy(self.v, other.v)

    def positions(self) -> np.ndarray:
        """Positions [P,3] as a float64 copy."""
        return self.x.numpy().astype(np.float64)

    def velocities(self) -> np.ndarray:
        """Velocities [P,3] as a float64 copy."""
        return self.v.numpy().astype(np.float64)
