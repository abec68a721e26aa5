"""A deliberately plain, loop-based numpy implementation of the SMPL equations (Loper et al. 2015),
written independently of darts.body, used to check `darts body export` + `darts body pose`."""
from __future__ import annotations

import numpy as np


def rodrigues(r: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(r)
    if theta < 1e-12:
        return np.eye(3)
    k = r / theta
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * kx @ kx


class ReferenceSMPL:
    """Loads an official-layout SMPL .npz (v_template, shapedirs, posedirs, J_regressor, weights,
    kintree_table, f) and poses it one frame at a time."""

    def __init__(self, path):
        with np.load(path) as data:
            self.v_template = data["v_template"].astype(np.float64)
            self.shapedirs = data["shapedirs"].astype(np.float64)
            self.posedirs = data["posedirs"].astype(np.float64)
            self.J_regressor = data["J_regressor"].astype(np.float64)
            self.weights = data["weights"].astype(np.float64)
            self.parents = data["kintree_table"][0].astype(np.int64)
            self.faces = data["f"]

    def __call__(self, pose: np.ndarray, betas: np.ndarray, trans: np.ndarray) -> np.ndarray:
        num_joints = len(self.parents)
        v_shaped = self.v_template + self.shapedirs[:, :, : len(betas)] @ betas
        joints = self.J_regressor @ v_shaped
        rotations = [rodrigues(pose[j]) for j in range(num_joints)]
        pose_feature = np.concatenate([(rotations[j] - np.eye(3)).ravel() for j in range(1, num_joints)])
        v_posed = v_shaped + self.posedirs @ pose_feature
        world = []
        for j in range(num_joints):
            local = np.eye(4)
            local[:3, :3] = rotations[j]
            local[:3, 3] = joints[j] - (joints[self.parents[j]] if j > 0 else 0)
            world.append(local if j == 0 else world[self.parents[j]] @ local)
        skin = []
        for j in range(num_joints):
            a = world[j].copy()
            a[:3, 3] -= world[j][:3, :3] @ joints[j]
            skin.append(a)
        out = np.zeros_like(v_posed)
        for j in range(num_joints):
            homogeneous = np.c_[v_posed, np.ones(len(v_posed))] @ skin[j].T
            out += self.weights[:, j : j + 1] * homogeneous[:, :3]
        return out + trans
