"""Resampling a motion to another frame rate: slerp for rotations, lerp for translation, and a
tent filter first when the rate falls (anti-aliasing: 120 fps motion capture simulated at 30 fps)."""
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
    """The motion sampled at ``fps`` over the same duration (first frame kept, last one not passed).

    Each new frame is the motion at its time t (in source frames s = t x the source rate: slerp and
    lerp between the two frames around it); when the rate falls (r = source fps / ``fps`` > 1) it is
    the tent-weighted mean of the source frames within r of s instead, weights 1 - |k - s| / r,
    rotations averaged in the tangent space at the slerped one (q = q_s exp(sum w_k log(q_s^-1 q_k)
    / sum w_k)). That is the low-pass filter a decimation needs: picking every r-th frame of motion
    capture keeps its frame-to-frame jitter at full size (white jitter at 120 fps resampled to 30 comes
    out at about 0.4 of it) while a smooth motion moves by a fraction of its second difference (a 1 Hz
    swing loses 0.4 % of its amplitude at r = 4). The window shrinks to stay symmetric near the first
    and last frames, so a motion at constant velocity is kept exactly."""
    if not isinstance(motion, Motion):
        raise check.refuse("motion", "a Motion", motion)
    fps = check.number(fps, "fps", *FPS_RANGE)
    # Rates like AMASS's 120.00004577 are nominal: a frame within 0.1 % of the end still counts.
    count = np.floor(motion.duration * fps + 1e-3) + 1
    check_frames(count, motion.path, f"the motion resampled to {fps:g} fps")
    count = int(count)
    ratio = motion.fps / fps
    src = np.arange(count) * ratio
    last = motion.num_frames - 1
    lo = np.minimum(np.floor(src).astype(int), last)
    hi = np.minimum(lo + 1, last)
    frac = src - lo
    fields = {name: slerp_rotvecs(arr[lo], arr[hi], np.broadcast_to(frac[:, None], (count, arr.shape[1])))
              for name, arr in motion.parts().items()}
    if ratio > 1.0:
        frames, weights = _tent(src, ratio, last)
        fields = {name: _mean_rotations(fields[name], arr[frames], weights) for name, arr in motion.parts().items()}
        trans = np.einsum("ij,ijk->ik", weights, motion.trans[frames])
    else:
        trans = motion.trans[lo] * (1 - frac[:, None]) + motion.trans[hi] * frac[:, None]
    return motion.with_frames(trans=trans, fps=float(fps), **fields)


def _tent(src: np.ndarray, ratio: float, last: int) -> tuple[np.ndarray, np.ndarray]:
    """Source frames [N, M] and their normalised tent weights [N, M] around the source positions
    ``src`` [N]: 1 - |k - s| / w with the half-width w = min(``ratio``, s, ``last`` - s) (0: the
    position alone, whose neighbours' weights are then 0)."""
    reach = int(np.ceil(ratio))
    frames = np.floor(src).astype(int)[:, None] + np.arange(-reach, reach + 1)[None, :]  # column ``reach``: floor(s)
    width = np.minimum(ratio, np.minimum(src, last - src))[:, None]
    distance = np.abs(frames - src[:, None])
    weights = np.where(width > 0, np.maximum(0.0, 1.0 - distance / np.maximum(width, 1e-12)), 0.0)
    weights = np.where((frames < 0) | (frames > last), 0.0, weights)
    weights[weights.sum(1) == 0, reach] = 1.0  # w = 0: the position itself (a whole source frame there)
    return np.clip(frames, 0, last), weights / weights.sum(1, keepdims=True)


def _mean_rotations(centre: np.ndarray, rotations: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Axis-angles [N, J, 3]: the ``weights`` [N, M]-mean of ``rotations`` [N, M, J, 3] in the
    tangent space at ``centre`` [N, J, 3]: centre exp(sum_m w_m log(centre^-1 r_m))."""
    n, m, joints = rotations.shape[:3]
    at = Rotation.from_rotvec(np.broadcast_to(centre[:, None], rotations.shape).reshape(-1, 3))
    offsets = (at.inv() * Rotation.from_rotvec(rotations.reshape(-1, 3))).as_rotvec().reshape(n, m, joints, 3)
    mean = np.einsum("nm,nmjk->njk", weights, offsets)
    return (Rotation.from_rotvec(centre.reshape(-1, 3)) * Rotation.from_rotvec(mean.reshape(-1, 3))).as_rotvec().reshape(
        centre.shape)
