"""Procedural AMASS-format motions (walk, run, wave, jumping jacks, twist, squat).

Each motion starts in the rest (T-) pose and blends into its movement over the first ``BLEND``
seconds, so cloth can be draped first. Joint rotations are written in SMPL's canonical frame
(Y up, front +Z, left +X): about X, negative flexes a hip forward and positive bends a knee or the
spine forward; about Z, a positive angle raises the left arm. The root carries the body into the
Z-up world (facing -Y). Feet are put on the floor (z = 0) by posing the body, and locked against
sliding: the stance foot for gaits, the mean of both ankles otherwise.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch
from scipy.spatial.transform import Rotation

from darts.body.joints import BODY_JOINT_NAMES
from darts.body.model import BodyModel
from darts.motion.amass import Motion

BLEND = 0.6  # seconds to blend out of the rest pose
Y_UP_TO_Z_UP = Rotation.from_euler("x", 90, degrees=True)
LEFT_ANKLE, RIGHT_ANKLE = BODY_JOINT_NAMES.index("left_ankle"), BODY_JOINT_NAMES.index("right_ankle")


def smoothstep(t0: float, t1: float, t: np.ndarray) -> np.ndarray:
    """0 before t0, 1 after t1, 3s^2 - 2s^3 between."""
    s = np.clip((t - t0) / (t1 - t0), 0.0, 1.0)
    return s * s * (3 - 2 * s)


def _about(axis: int, angles) -> Rotation:
    """Rotations by ``angles`` (radians, scalar or [T]) about a canonical axis (0 = X, 1 = Y, 2 = Z)."""
    angles = np.atleast_1d(np.asarray(angles, np.float64))
    rotvecs = np.zeros((len(angles), 3))
    rotvecs[:, axis] = angles
    return Rotation.from_rotvec(rotvecs)


def rx(angles) -> Rotation:
    return _about(0, angles)


def ry(angles) -> Rotation:
    return _about(1, angles)


def rz(angles) -> Rotation:
    return _about(2, angles)


def arms_down(t, lower: float = 1.25, swing_left=0.0, swing_right=0.0, elbow: float = 0.25) -> dict:
    """Arms lowered by ``lower`` rad from the T-pose, swung about X (positive = backwards), elbows
    bent forwards by ``elbow``."""
    return {
        "left_shoulder": rx(swing_left + 0 * t) * rz(-lower),
        "right_shoulder": rx(swing_right + 0 * t) * rz(lower),
        "left_elbow": ry(-elbow + 0 * t), "right_elbow": ry(elbow + 0 * t),
    }


def legs(t, hip_l, hip_r, knee_l, knee_r, ankle_l=0.0, ankle_r=0.0) -> dict:
    z = 0 * t
    return {"left_hip": rx(hip_l + z), "right_hip": rx(hip_r + z), "left_knee": rx(knee_l + z),
            "right_knee": rx(knee_r + z), "left_ankle": rx(ankle_l + z), "right_ankle": rx(ankle_r + z)}


@dataclass(frozen=True)
class Gait:
    """A walking or running cycle (angles in radians): each hip swings about ``hip_bias`` by
    ``hip_swing``; each knee bends ``knee_bend`` plus ``knee_lift`` * max(cos, 0)^``knee_sharpness``
    while its leg swings through; arms hang ``arm_lower`` below the T-pose and swing against the legs."""

    period: float
    hip_bias: float
    hip_swing: float
    knee_bend: float
    knee_lift: float
    knee_sharpness: float
    ankle: float
    arm_lower: float
    arm_swing: float
    elbow: float
    pelvis_yaw: float


WALK = Gait(1.1, 0.12, 0.32, 0.08, 0.95, 2.0, 0.12, 1.25, 0.3, 0.3, 0.06)
RUN = Gait(0.72, 0.25, 0.55, 0.3, 1.5, 1.5, 0.15, 1.2, 0.6, 1.4, 0.1)


def gait(t, g: Gait):
    """Pose, root rotation and cycle phase (radians) of a gait at times t."""
    phase = 2 * np.pi * t / g.period
    s, c = np.sin(phase), np.cos(phase)
    pose = legs(t, -(g.hip_bias + g.hip_swing * s), -(g.hip_bias - g.hip_swing * s),
                g.knee_bend + g.knee_lift * np.maximum(c, 0) ** g.knee_sharpness,
                g.knee_bend + g.knee_lift * np.maximum(-c, 0) ** g.knee_sharpness, g.ankle * s, -g.ankle * s)
    pose.update(arms_down(t, g.arm_lower, g.arm_swing * s, -g.arm_swing * s, g.elbow))
    return pose, ry(g.pelvis_yaw * s), phase


def walk(t):
    pose, root, phase = gait(t, WALK)
    pose["spine2"] = ry(-0.06 * np.sin(phase))
    return pose, root, 0 * t


def run(t):
    pose, root, phase = gait(t, RUN)
    pose["spine1"] = rx(0.12 + 0 * t)
    flight = 0.05 * np.maximum(0.0, -np.cos(2 * phase)) ** 2
    return pose, root, flight


def wave(t):
    raise_right = smoothstep(0.8, 1.6, t)
    waving = 0.4 * np.sin(2 * np.pi * 1.4 * (t - 1.6)) * smoothstep(1.6, 2.0, t)
    pose = {
        "left_shoulder": rz(-1.25 * smoothstep(0.0, 1.0, t)),
        "left_elbow": ry(-0.2 + 0 * t),
        "right_shoulder": rz(-0.55 * raise_right),
        "right_elbow": rz(-(1.2 * raise_right) + waving),
        "spine2": rz(-0.05 * raise_right),
    }
    return pose, ry(0 * t), 0 * t


def jumping_jacks(t):
    cycle = np.where(t > 1.0, t - 1.0, 0.0)
    open_ = 0.5 * (1 - np.cos(2 * np.pi * cycle / 1.0))
    arms = -1.25 + 2.55 * open_
    pose = {"left_shoulder": rz(arms), "right_shoulder": rz(-arms), "left_elbow": ry(-0.15 + 0 * t),
            "right_elbow": ry(0.15 + 0 * t), "left_hip": rz(0.22 * open_), "right_hip": rz(-0.22 * open_),
            "left_ankle": rz(-0.15 * open_), "right_ankle": rz(0.15 * open_)}
    lift = 0.08 * np.sin(2 * np.pi * cycle / 1.0) ** 2
    return pose, ry(0 * t), lift


def twist(t):
    swing = 0.28 * np.sin(2 * np.pi * (t - 0.6) / 1.6) * smoothstep(0.6, 1.0, t)
    pose = arms_down(t, 1.0, 0.0, 0.0, 0.6)
    pose.update({"spine1": ry(swing), "spine2": ry(swing), "spine3": ry(swing)})
    turn = 0.5 * np.pi * smoothstep(1.0, 2.0, t) * (1 - smoothstep(2.6, 3.6, t))
    return pose, ry(turn), 0 * t


def squat(t):
    depth = np.where(t > 0.8, 0.5 * (1 - np.cos(2 * np.pi * (t - 0.8) / 1.6)), 0.0)
    pelvis_pitch = 0.5 * depth
    pose = legs(t, -2.1 * depth, -2.1 * depth, 2.1 * depth, 2.1 * depth, -0.5 * depth, -0.5 * depth)
    pose["spine1"] = rx(0.1 * depth)
    pose.update({"left_shoulder": rx(-1.5 * depth) * rz(-1.3 + 0 * t),
                 "right_shoulder": rx(-1.5 * depth) * rz(1.3 + 0 * t)})
    return pose, rx(pelvis_pitch), 0 * t


def sit(t):
    """Down onto a chair's height (thighs horizontal, knees at a right angle, the back upright),
    held, and up again: 0.8-1.8 s down, 2.8-3.8 s up."""
    depth = smoothstep(0.8, 1.8, t) * (1 - smoothstep(2.8, 3.8, t))
    pose = legs(t, -1.57 * depth, -1.57 * depth, 1.57 * depth, 1.57 * depth)
    pose["spine1"] = rx(0.15 * depth * (1 - depth) * 4)  # leaning forward on the way down and up
    pose.update(arms_down(t, 1.2, -0.35 * depth, -0.35 * depth, 0.5))
    return pose, ry(0 * t), 0 * t


def kneel(t):
    """Down onto both knees (thighs upright, shins on the floor behind), held, and up: the hips fold
    on the way down and up as a person's do."""
    depth = smoothstep(0.8, 2.0, t) * (1 - smoothstep(2.8, 4.0, t))
    fold = 4 * depth * (1 - depth)  # 0 standing and kneeling, 1 halfway
    pose = legs(t, -1.0 * fold, -1.0 * fold, 1.57 * depth + 0.6 * fold, 1.57 * depth + 0.6 * fold,
                0.6 * depth, 0.6 * depth)
    pose["spine1"] = rx(0.25 * fold)
    pose.update(arms_down(t, 1.2, -0.3 * fold, -0.3 * fold, 0.3))
    return pose, ry(0 * t), 0 * t


def walk_arms_down(t):
    """The walk with the arms held straight down at the sides, not swinging: the sleeves pressed
    against the torso from the armpits down."""
    pose, root, phase = gait(t, WALK)
    pose.update(arms_down(t, 1.45, 0.0, 0.0, 0.05))
    return pose, root, 0 * t


def arms_crossed(t):
    """Standing, the arms folded across the chest, each hand past the body's middle (the left forearm
    over the right, both against the chest), swaying a little."""
    fold = smoothstep(0.6, 1.6, t)
    sway = 0.08 * np.sin(2 * np.pi * (t - 1.6) / 2.0) * smoothstep(1.6, 2.0, t)
    pose = {"left_shoulder": ry(-1.4 * fold) * rz(-1.1 * fold), "right_shoulder": ry(1.5 * fold) * rz(1.1 * fold),
            "left_elbow": ry(-2.09 * fold), "right_elbow": ry(2.09 * fold), "spine2": ry(sway)}
    return pose, ry(0 * t), 0 * t


@dataclass(frozen=True)
class MotionSpec:
    """A procedural motion: its length, its pose builder and how its feet are locked."""

    duration: float
    build: Callable
    lock: str  # "stance" (the lower ankle stays put) or "both" (the ankles' mean stays put)
    smooth: float = 0.0  # seconds over which to average the horizontal velocity


MOTIONS = {
    "walk": MotionSpec(4.0, walk, "stance"),
    "run": MotionSpec(3.0, run, "stance", smooth=0.72),
    "wave": MotionSpec(4.0, wave, "both"),
    "jumping_jacks": MotionSpec(4.0, jumping_jacks, "both"),
    "twist": MotionSpec(4.0, twist, "both"),
    "squat": MotionSpec(4.0, squat, "both"),
    "sit": MotionSpec(4.5, sit, "both"),
    "kneel": MotionSpec(4.5, kneel, "both"),
    "arms_down": MotionSpec(4.0, walk_arms_down, "stance"),
    "arms_crossed": MotionSpec(4.0, arms_crossed, "both"),
}


def _body_pose(pose: dict, root: Rotation, t: np.ndarray) -> np.ndarray:
    """[T,22,3] axis-angles; every local rotation is scaled in from the rest pose over BLEND s."""
    blend = smoothstep(0.0, BLEND, t)[:, None]
    body = np.zeros((len(t), len(BODY_JOINT_NAMES), 3))
    for name, rotation in pose.items():
        body[:, BODY_JOINT_NAMES.index(name)] = rotation.as_rotvec() * blend
    body[:, 0] = (Y_UP_TO_Z_UP * Rotation.from_rotvec(root.as_rotvec() * blend)).as_rotvec()
    return body


def _floor_and_lock(model: BodyModel, body: np.ndarray, lift: np.ndarray, spec: MotionSpec, fps: float) -> np.ndarray:
    """Root translation [T,3] putting the lowest vertex at z = lift and keeping the feet in place."""
    pose = np.concatenate([body, np.zeros((len(body), model.num_joints - body.shape[1], 3))], axis=1)
    out = model(pose)
    vertices, joints = out.vertices.detach().numpy(), out.joints.detach().numpy()
    ankles = joints[:, [LEFT_ANKLE, RIGHT_ANKLE], :2]
    if spec.lock == "stance":
        stance = np.argmin(joints[:, [LEFT_ANKLE, RIGHT_ANKLE], 2], axis=1)
        rows = np.arange(1, len(body))
        step = ankles[rows, stance[1:]] - ankles[rows - 1, stance[1:]]
        xy = -np.concatenate([[[0.0, 0.0]], np.cumsum(step, axis=0)])
    else:
        xy = -(ankles.mean(1) - ankles[0].mean(0))
    if spec.smooth:
        width = max(int(round(spec.smooth * fps)), 1)
        velocity = np.diff(xy, axis=0)
        kernel = np.ones(width) / width
        velocity = np.stack([np.convolve(velocity[:, k], kernel, mode="same") for k in range(2)], 1)
        xy = np.concatenate([[[0.0, 0.0]], np.cumsum(velocity, axis=0)])
    z = -vertices[..., 2].min(1) + lift
    return np.concatenate([xy, z[:, None]], axis=1)


def build_motion(name: str, model: BodyModel, fps: float = 60.0) -> Motion:
    """The procedural motion ``name`` (a key of MOTIONS) at ``fps``, placed on the floor for ``model``."""
    spec = MOTIONS[name]
    t = np.arange(int(round(spec.duration * fps)) + 1) / fps
    pose, root, lift = spec.build(t)
    body = _body_pose(pose, root, t)
    trans = _floor_and_lock(model.to(torch.float64), body, np.asarray(lift) * smoothstep(0.0, BLEND, t), spec, fps)
    return Motion(body_pose=body, trans=trans, fps=float(fps), betas=np.zeros(16), gender="neutral",
                  source_format="amass-smplh", path=None)
