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


def write_classic_amass_120fps(source_path, path) -> None:
    """A classic AMASS SMPL-H file at 120.00004577 fps (dmpls, bytes gender) made from a motion."""
    from darts.fileio import save_npz
    from darts.motion.amass import load_motion
    from darts.motion.resample import resample

    fine = resample(load_motion(source_path), 120.00004577)
    save_npz(path, poses=np.concatenate([fine.body_pose, fine.hand_pose], 1).reshape(fine.num_frames, -1),
             trans=fine.trans, betas=np.zeros(16), gender=np.array(b"male"), dmpls=np.zeros((fine.num_frames, 8)),
             mocap_framerate=np.array(120.00004577))
