"""AMASS-format motions: loading and validating the classic SMPL-H (``poses [T,156]``), plain SMPL
(``[T,72]``), SMPL-X (``[T,165]``) and SMPL-X "N" (``root_orient``/``pose_body``/...) releases, and
writing the classic SMPL-H layout.

Rotations are axis-angle vectors (radians). The root orientation and ``trans`` are in the AMASS
world frame (Z up, metres); other joints are local rotations in SMPL's canonical joint frames.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from darts import arguments as check
from darts.errors import DartsInputError
from darts.fileio import check_output, read_npz, require_keys, require_real, save_npz

NUM_BODY_JOINTS = 22  # the root plus 21 body joints, common to SMPL, SMPL-H and SMPL-X
NUM_HAND_JOINTS = 30  # 15 per hand, left then right (MANO order)
_FRAME_RATE_KEYS = ("mocap_framerate", "mocap_frame_rate", "frame_rate", "fps")
#: frame rates a motion may have (frames per second): from a slow keyframed clip to high-speed capture
FPS_RANGE = (1.0, 1000.0)


@dataclass
class Motion:
    """A motion: per-frame joint rotations [T, n, 3] (axis-angle), root translation [T, 3]."""

    body_pose: np.ndarray
    trans: np.ndarray
    fps: float
    hand_pose: np.ndarray | None = None
    smpl_hand_pose: np.ndarray | None = None
    jaw_pose: np.ndarray | None = None
    eye_pose: np.ndarray | None = None
    betas: np.ndarray | None = None
    gender: str = "neutral"
    source_format: str = "amass-smplh"
    path: str | None = None

    @property
    def num_frames(self) -> int:
        return len(self.trans)

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return (self.num_frames - 1) / self.fps

    def parts(self) -> dict[str, np.ndarray]:
        """The rotation arrays present, by name, each [T, n, 3]."""
        names = ("body_pose", "hand_pose", "smpl_hand_pose", "jaw_pose", "eye_pose")
        return {name: getattr(self, name) for name in names if getattr(self, name) is not None}

    def with_frames(self, **arrays) -> Motion:
        """A copy with some per-frame arrays replaced (same fields as the constructor)."""
        return replace(self, **arrays)

    def model_pose(self, num_joints: int) -> np.ndarray:
        """Axis-angles [T, J, 3] for a model with ``num_joints`` (24 SMPL, 52 SMPL-H, 55 SMPL-X);
        joints the motion does not drive stay at rest."""
        t = self.num_frames
        zeros = lambda n: np.zeros((t, n, 3))  # noqa: E731
        pick = lambda arr, n: zeros(n) if arr is None else arr  # noqa: E731
        if num_joints == 24:
            extra = [pick(self.smpl_hand_pose, 2)]
        elif num_joints == 52:
            extra = [pick(self.hand_pose, NUM_HAND_JOINTS)]
        elif num_joints == 55:
            extra = [pick(self.jaw_pose, 1), pick(self.eye_pose, 2), pick(self.hand_pose, NUM_HAND_JOINTS)]
        else:
            raise DartsInputError(self.path, f"no AMASS joint mapping for a body with {num_joints} joints (24, 52 or 55)")
        return np.concatenate([self.body_pose] + extra, axis=1)


def _frames(arrays: dict, key: str, width: int, frames: int | None, path) -> np.ndarray:
    value = require_real(key, arrays[key], path)
    if value.ndim != 2 or value.shape[1] != width:
        raise DartsInputError(path, f"'{key}' has shape {value.shape}, expected [T, {width}]")
    if frames is not None and len(value) != frames:
        raise DartsInputError(path, f"'{key}' has {len(value)} frames, 'trans' has {frames}")
    return value.astype(np.float64)


def _rotations(arrays: dict, key: str, joints: int, frames: int, path) -> np.ndarray:
    """A [T, 3 * joints] axis-angle array as [T, joints, 3]."""
    return _frames(arrays, key, 3 * joints, frames, path).reshape(frames, joints, 3)


def _frame_rate(arrays: dict, path) -> float:
    for key in _FRAME_RATE_KEYS:
        if key in arrays:
            value = np.asarray(arrays[key])
            if value.size != 1 or value.dtype.kind not in "fiu":
                raise DartsInputError(path, f"'{key}' must be one number, found {value.dtype} values of shape {value.shape}")
            fps = float(value.reshape(()))
            if not np.isfinite(fps) or fps <= 0:
                raise DartsInputError(path, f"frame rate '{key}' must be positive, found {fps}")
            if not FPS_RANGE[0] <= fps <= FPS_RANGE[1]:
                raise DartsInputError(path, f"frame rate '{key}' is {fps:g} frames/s, not a motion's "
                                            f"({FPS_RANGE[0]:g} to {FPS_RANGE[1]:g})")
            return fps
    raise DartsInputError(path, f"missing frame rate (one of {', '.join(_FRAME_RATE_KEYS)})")


def _gender(arrays: dict) -> str:
    value = arrays.get("gender")
    if value is None:
        return "neutral"
    value = np.asarray(value).reshape(-1)[0] if np.asarray(value).size else "neutral"
    if isinstance(value, bytes | np.bytes_):
        value = value.decode("utf-8", "replace")
    return str(value).strip() or "neutral"


def load_motion(path: str | os.PathLike) -> Motion:
    """Load and validate an AMASS-format ``.npz``; any problem raises DartsInputError naming the file."""
    path = Path(check.path_or(path, "path"))
    arrays = read_npz(path)
    require_keys(arrays, ["trans"], path, "an AMASS motion file")
    trans = _frames(arrays, "trans", 3, None, path)
    frames = len(trans)
    if frames == 0:
        raise DartsInputError(path, "the motion has zero frames")
    fps = _frame_rate(arrays, path)
    common = dict(trans=trans, fps=fps, gender=_gender(arrays), path=str(path))
    if "betas" in arrays:
        common["betas"] = require_real("betas", arrays["betas"], path).astype(np.float64).reshape(-1)
    if "poses" in arrays:
        width = np.asarray(arrays["poses"]).shape[-1] if np.asarray(arrays["poses"]).ndim == 2 else -1
        layouts = {72: "amass-smpl", 156: "amass-smplh", 165: "amass-smplx"}
        if width not in layouts:
            raise DartsInputError(path,
                                  f"'poses' has shape {np.asarray(arrays['poses']).shape}, "
                                  "expected [T, 72], [T, 156] or [T, 165]")
        poses = _rotations(arrays, "poses", width // 3, frames, path)
        body = poses[:, :NUM_BODY_JOINTS]
        if width == 72:
            return Motion(body, smpl_hand_pose=poses[:, 22:], source_format=layouts[width], **common)
        if width == 156:
            return Motion(body, hand_pose=poses[:, 22:], source_format=layouts[width], **common)
        return Motion(body, jaw_pose=poses[:, 22:23], eye_pose=poses[:, 23:25], hand_pose=poses[:, 25:],
                      source_format=layouts[width], **common)
    if "root_orient" in arrays and "pose_body" in arrays:
        root = _rotations(arrays, "root_orient", 1, frames, path)
        body = np.concatenate([root, _rotations(arrays, "pose_body", 21, frames, path)], axis=1)
        optional = {}
        for key, name, joints in (("pose_hand", "hand_pose", 30), ("pose_jaw", "jaw_pose", 1), ("pose_eye", "eye_pose", 2)):
            if key in arrays:
                optional[name] = _rotations(arrays, key, joints, frames, path)
        return Motion(body, source_format="amass-smplx-n", **optional, **common)
    raise DartsInputError(path, "not an AMASS motion: needs 'poses' or 'root_orient' + 'pose_body'")


def save_motion(motion: Motion, path: str | os.PathLike) -> None:
    """Write ``motion`` in the classic SMPL-H AMASS layout (poses [T,156], trans, betas [16],
    gender, mocap_framerate, dmpls [T,8])."""
    if not isinstance(motion, Motion):
        raise check.refuse("motion", "a Motion", motion)
    path = check_output(check.path_or(path, "path"), (".npz",))
    t = motion.num_frames
    hands = motion.hand_pose if motion.hand_pose is not None else np.zeros((t, NUM_HAND_JOINTS, 3))
    betas = np.zeros(16) if motion.betas is None else np.resize(motion.betas, 16)
    save_npz(
        path, compressed=False,
        poses=np.concatenate([motion.body_pose, hands], axis=1).reshape(t, -1),
        trans=motion.trans, betas=betas, gender=np.array(motion.gender),
        mocap_framerate=np.array(float(motion.fps)), dmpls=np.zeros((t, 8)),
    )
