"""The animated body a garment is simulated on, in the AMASS world frame (Z up, metres).

Timeline: during ``settle`` seconds the body goes from its rest pose (placed by the first frame's
root rotation and translation) to the motion's first frame, every joint slerped from identity;
then the recorded frames follow. ``positions(t)`` interpolates linearly between frames, which is
what the solver samples at every substep.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from darts.body.lbs import axis_angle_to_matrix
from darts.body.model import BodyModel
from darts.body.segmentation import body_segmentation
from darts.errors import DartsInputError
from darts.motion.amass import Motion
from darts.motion.budget import check_frames
from darts.motion.posing import motion_betas, pose_sequence
from darts.motion.resampling import resample
from sim.engine.settings import DEFAULT_BODY_GAP


@dataclass
class BodyTrack:
    """Body vertices per frame [T,V,3] at ``fps``; the first ``settle_frames`` are the settle blend."""

    vertices: np.ndarray
    faces: np.ndarray
    fps: float
    settle_frames: int
    rest_rotation: np.ndarray  # root rotation (3x3) of the rest placement
    rest_origin: np.ndarray  # pelvis joint of the rest shape (canonical frame)
    rest_translation: np.ndarray  # world position of that pelvis joint at t = 0
    parts: np.ndarray | None = None  # [V] each body vertex's part (darts.body.segmentation.PART_NAMES)

    @property
    def duration(self) -> float:
        return (len(self.vertices) - 1) / self.fps

    def positions(self, time: float) -> np.ndarray:
        """Body vertices at ``time`` seconds (clamped to the track), linear between frames."""
        x = float(np.clip(time * self.fps, 0.0, len(self.vertices) - 1))
        lo = min(int(np.floor(x)), len(self.vertices) - 1)
        hi = min(lo + 1, len(self.vertices) - 1)
        w = x - lo
        return (1.0 - w) * self.vertices[lo] + w * self.vertices[hi]

    def place_rest(self, canonical: np.ndarray) -> np.ndarray:
        """Canonical rest-pose points (a DART's vertices) moved exactly as the body is at t = 0."""
        return (np.asarray(canonical, np.float64) - self.rest_origin) @ self.rest_rotation.T + self.rest_translation


def _shape_blend(start: np.ndarray, target: np.ndarray, count: int, frames: int) -> np.ndarray:
    """Betas [frames, K]: from ``start`` to ``target`` over the first ``count`` frames along a
    smoothstep s(w) = 3w^2 - 2w^3 (no jump in the body's speed at either end), then ``target``."""
    width = max(len(start), len(target))
    start, target = np.pad(start, (0, width - len(start))), np.pad(target, (0, width - len(target)))
    w = np.clip(np.arange(frames) / max(count, 1), 0.0, 1.0)
    s = (3 * w**2 - 2 * w**3)[:, None]
    return (1 - s) * start + s * target


def build_body_track(body: BodyModel, motion: Motion, fps: float, settle: float, betas=None,
                     progress: bool = False, start_betas=None, gap: float = DEFAULT_BODY_GAP) -> BodyTrack:
    """Pose ``body`` by ``motion`` resampled to ``fps``, preceded by ``settle`` seconds of blend;
    with ``gap`` > 0 (m; by default ``SimSettings``' own, so a track built without naming it is the
    one darts-sim simulates against), every frame's parts that overlap or come closer are pressed
    that far apart (``sim.body_separation``; ``SimSettings.body_gap``); 0: the body as skinned.

    ``start_betas``: the shape the body starts in (a garment's own shape) when it is not ``betas``
    (the shape to simulate on); the body then also changes shape during the settle blend, so a
    garment made for one body is carried onto another."""
    if settle < 0:
        raise DartsInputError(None, f"settle must be >= 0 s, got {settle}")
    motion = resample(motion, fps) if abs(motion.fps - fps) > 1e-9 else motion
    check_frames(round(settle * fps) + motion.num_frames, None, f"the settle of {settle:g} s and the motion at {fps:g} fps")
    count = int(round(settle * fps))
    target = motion_betas(body, motion, betas)
    start = target if start_betas is None else np.asarray(start_betas, np.float64)
    reshaping = len(target) + len(start) > 0 and not np.array_equal(np.pad(start, (0, max(0, len(target) - len(start)))),
                                                                    np.pad(target, (0, max(0, len(start) - len(target)))))
    if reshaping and count == 0:
        raise DartsInputError(None, "a body shape other than the garment's (--betas) needs a settle period to change "
                                    "shape in: give --settle > 0")
    if count:
        weights = (np.arange(count) / count)[:, None, None]
        blend = {name: arr[:1] * weights for name, arr in motion.parts().items()}
        blend["body_pose"][:, 0] = motion.body_pose[0, 0]  # the root keeps its first-frame rotation
        blended = motion.with_frames(trans=np.repeat(motion.trans[:1], count, 0), **blend)
        joined = {name: np.concatenate([getattr(blended, name), arr]) for name, arr in motion.parts().items()}
        motion = motion.with_frames(trans=np.concatenate([blended.trans, motion.trans]), **joined)
    shapes = _shape_blend(start, target, count, motion.num_frames) if reshaping else target
    vertices, _ = pose_sequence(body, motion, betas=shapes, progress=progress)
    _, rest_joints = body.shaped(torch.as_tensor(start, dtype=body.dtype))
    origin = rest_joints[0, 0].double().numpy()
    # In the rest pose every joint moves with the root: x -> R (x - J_0) + J_0 + trans.
    rotation = axis_angle_to_matrix(torch.as_tensor(motion.body_pose[0, 0], dtype=torch.float64)).numpy()
    parts = body_segmentation(body)
    if gap > 0:
        from sim.body_separation import separate_parts

        vertices = separate_parts(vertices, body.faces, parts, gap)
    return BodyTrack(vertices, body.faces, float(fps), count, rotation, origin, origin + motion.trans[0], parts)
