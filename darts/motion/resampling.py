"""Resampling a motion to another frame rate: slerp for rotations, lerp for translation."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from darts import arguments as check
from darts.motion.amass import FPS_RANGE, Motion
from darts.motion.budget import check_frames


def slerp_rotvecs(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Slerp between axis-angles a and b [..., 3] at fractions t [...]: a * exp(t log(a^-1 b))."""
    ra, rb = Rotation.from_rotvec(a.reshape(-1, 3)), Rotation.from_rotvec(b.reshape(-1, 3))
    delta = (ra.inv() * rb).as_rotvec() * np.broadcast_to(t, a.shape[:-1]).reshape(-1, 1)
    return (ra * Rotation.from_rotvec(delta)).as_rotvec().reshape(a.shape)


def resample(motion: Motion, fps: float) -> Motion:
    """The motion sampled at ``fps`` over the same duration (first frame kept, last one not passed)."""
    if not isinstance(motion, Motion):
        raise check.refuse("motion", "a Motion", motion)
    fps = check.number(fps, "fps", *FPS_RANGE)
    # Rates like AMASS's 120.00004577 are nominal: a frame within 0.1 % of the end still counts.
    count = np.floor(motion.duration * fps + 1e-3) + 1
    check_frames(count, motion.path, f"the motion resampled to {fps:g} fps")
    count = int(count)
    src = np.arange(count) * (motion.fps / fps)
    lo = np.minimum(np.floor(src).astype(int), motion.num_frames - 1)
    hi = np.minimum(lo + 1, motion.num_frames - 1)
    frac = src - lo
    fields = {name: slerp_rotvecs(arr[lo], arr[hi], np.broadcast_to(frac[:, None], (count, arr.shape[1])))
              for name, arr in motion.parts().items()}
    trans = motion.trans[lo] * (1 - frac[:, None]) + motion.trans[hi] * frac[:, None]
    return motion.with_frames(trans=trans, fps=float(fps), **fields)
