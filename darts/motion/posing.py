"""Posing a body model by a motion: per-frame vertices and joints in the AMASS world frame (Z up)."""
from __future__ import annotations

import numpy as np
import torch
from tqdm import tqdm

from darts import arguments as check
from darts.body.model import BodyModel
from darts.motion.amass import Motion
from darts.motion.budget import check_posed_bytes


def motion_betas(model: BodyModel, motion: Motion, betas=None) -> np.ndarray:
    """Betas to pose ``model`` with: explicit ones, else the motion's for official models (truncated
    to the model's count), else zeros; the default body's shape space is not SMPL's."""
    if betas is not None:
        return check.betas(betas, model.num_betas, motion.num_frames)
    if motion.betas is not None and not model.name.startswith("darts-default"):
        return motion.betas[: model.num_betas]
    return np.zeros(0)


def pose_sequence(model: BodyModel, motion: Motion, betas=None, ground: bool = False,
                  chunk: int = 64, progress: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Vertices [T,V,3] and joints [T,J,3] (float32, metres, Z-up world): LBS(pose, betas) + trans.

    ``betas`` is one shape [K] or one per frame [T,K] (a body changing shape). With ``ground`` the
    whole sequence is shifted along Z so its lowest vertex touches z = 0."""
    if not isinstance(model, BodyModel):
        raise check.refuse("model", "a BodyModel (darts.load_body)", model)
    if not isinstance(motion, Motion):
        raise check.refuse("motion", "a Motion (darts.load_motion)", motion)
    ground, progress = check.switch(ground, "ground"), check.switch(progress, "progress")
    chunk = check.number(chunk, "chunk", 1, whole=True)
    check_posed_bytes(motion.num_frames, model.num_vertices + model.num_joints, motion.path)
    pose = motion.model_pose(model.num_joints)
    shape = torch.as_tensor(motion_betas(model, motion, betas), dtype=model.dtype)
    per_frame = shape.ndim == 2
    vertices = np.empty((motion.num_frames, model.num_vertices, 3), np.float32)
    joints = np.empty((motion.num_frames, model.num_joints, 3), np.float32)
    with torch.no_grad():
        for start in tqdm(range(0, motion.num_frames, chunk), desc="posing", unit="chunk",
                          disable=None if progress else True, leave=False):
            stop = min(start + chunk, motion.num_frames)
            out = model(pose[start:stop], betas=shape[start:stop] if per_frame else shape, trans=motion.trans[start:stop])
            vertices[start:stop] = out.vertices.numpy()
            joints[start:stop] = out.joints.numpy()
    if ground:
        lowest = vertices[..., 2].min()
        vertices[..., 2] -= lowest
        joints[..., 2] -= lowest
    return vertices, joints
