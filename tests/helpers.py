"""Test data builders."""
from __future__ import annotations

import numpy as np

from darts.dart.model import Dart


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


def sheet_dart(vertices: np.ndarray, faces: np.ndarray) -> Dart:
    """A one-panel DART of a bare mesh (no lines, no seams), for solver tests."""
    empty = np.zeros((0, 2), np.int32)
    return Dart(category="test-sheet", vertices=vertices.astype(np.float32), faces=faces.astype(np.int32),
                panel=np.zeros(len(faces), np.int32), panel_names=["sheet"], lines={}, seams=[], pairs=empty,
                pair_seam=np.zeros(0, np.int32), pair_position=np.zeros(0, np.float32))
