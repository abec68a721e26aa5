"""Test data builders."""
from __future__ import annotations

import numpy as np


def random_motion_arrays(frames: int, seed: int = 0, scale: float = 0.4) -> dict:
    """A classic SMPL-H AMASS dict with random poses (radians) and translations."""
    rng = np.random.default_rng(seed)
    return {
        "poses": rng.normal(0, scale, (frames, 156)),
        "trans": rng.normal(0, 0.3, (frames, 3)) + [0, 0, 1.0],
        "betas": np.zeros(16),
        "gender": np.array("neutral"),
        "mocap_framerate": np.array(30.0),
    }
