"""Recorded launches (sim.launch.Launcher) run a kernel exactly as wp.launch does: the arrays they
were recorded with, and scalar arguments that change between calls."""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.launch import Launcher

wp = warp()


@wp.kernel
def add_scaled(source: wp.array(dtype=wp.vec3), scale: float, offset: wp.vec3, target: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    target[i] = target[i] + scale * source[i] + offset


def test_replayed_launch_takes_new_scalars_and_keeps_arrays_apart():
    launch = Launcher("cpu")
    source = wp.array(np.arange(12, dtype=np.float32).reshape(4, 3), dtype=wp.vec3)
    first, second = (wp.zeros(4, dtype=wp.vec3) for _ in range(2))
    launch(add_scaled, 4, [source, 1.0, wp.vec3(0.0, 0.0, 1.0), first])
    launch(add_scaled, 4, [source, 2.0, wp.vec3(0.0, 0.0, 1.0), first])  # replayed, scale changed
    launch(add_scaled, 4, [source, 2.0, wp.vec3(1.0, 0.0, 0.0), first])  # replayed, offset changed
    launch(add_scaled, 4, [source, 0.5, wp.vec3(0.0, 0.0, 0.0), second])  # another target: its own record
    base = np.arange(12, dtype=np.float32).reshape(4, 3)
    np.testing.assert_allclose(first.numpy(), 5.0 * base + [1.0, 0.0, 2.0])
    np.testing.assert_allclose(second.numpy(), 0.5 * base)
    launch(add_scaled, 0, [source, 1.0, wp.vec3(0.0), second])  # an empty launch does nothing
    np.testing.assert_allclose(second.numpy(), 0.5 * base)
