"""The SMPL equations (Loper et al. 2015) in torch: blend shapes, joint regression, forward
kinematics and linear blend skinning. Batched over frames and differentiable.

All arrays are in the body's canonical frame (Y up) until the root rotation of a pose, which in
AMASS carries the body into the Z-up world frame. Shapes: V vertices, J joints, B frames.
"""
from __future__ import annotations

import numpy as np
import torch


def axis_angle_to_matrix(axis_angle: torch.Tensor) -> torch.Tensor:
    """Rodrigues: R = I + (sin t / t) K + ((1 - cos t) / t^2) K^2 with K = [a]x and t = |a|.

    ``axis_angle`` [..., 3] -> [..., 3, 3]. Uses the Taylor series near t = 0, so the gradient is
    finite at the identity.
    """
    theta2 = (axis_angle * axis_angle).sum(-1, keepdim=True)[..., None]
    theta = theta2.clamp_min(1e-24).sqrt()
    small = theta2 < 1e-8
    a = torch.where(small, 1.0 - theta2 / 6.0, torch.sin(theta) / theta)
    b = torch.where(small, 0.5 - theta2 / 24.0, (1.0 - torch.cos(theta)) / theta2.clamp_min(1e-24))
    x, y, z = axis_angle.unbind(-1)
    zero = torch.zeros_like(x)
    k = torch.stack([zero, -z, y, z, zero, -x, -y, x, zero], -1).reshape(*axis_angle.shape[:-1], 3, 3)
    eye = torch.eye(3, dtype=axis_angle.dtype, device=axis_angle.device)
    return eye + a * k + b * (k @ k)


def blend_shapes(betas: torch.Tensor, shapedirs: torch.Tensor) -> torch.Tensor:
    """Shape offsets sum_k beta_k S_k: betas [B, K'] (K' <= K), shapedirs [V, 3, K] -> [B, V, 3]."""
    return torch.einsum("bk,vdk->bvd", betas, shapedirs[..., : betas.shape[-1]])


def pose_features(rotations: torch.Tensor) -> torch.Tensor:
    """SMPL's pose-corrective input: vec(R_j - I) for every joint but the root. [B, J, 3, 3] -> [B, 9(J-1)]."""
    eye = torch.eye(3, dtype=rotations.dtype, device=rotations.device)
    return (rotations[:, 1:] - eye).reshape(rotations.shape[0], -1)


def forward_kinematics(
    rotations: torch.Tensor, rest_joints: torch.Tensor, parents: np.ndarray
) -> tuple[torch.Tensor, torch.Tensor]:
    """World transforms along the tree: G_0 = [R_0 | J_0], G_i = G_p(i) [R_i | J_i - J_p(i)].

    rotations [B, J, 3, 3], rest_joints [B, J, 3] -> (G [B, J, 4, 4], posed joints [B, J, 3]).
    ``parents`` must list every parent before its children.
    """
    batch, count = rotations.shape[:2]
    offsets = rest_joints.clone()
    offsets[:, 1:] = rest_joints[:, 1:] - rest_joints[:, parents[1:]]
    local = torch.zeros(batch, count, 4, 4, dtype=rotations.dtype, device=rotations.device)
    local[..., :3, :3] = rotations
    local[..., :3, 3] = offsets
    local[..., 3, 3] = 1.0
    world = [local[:, 0]]
    for i in range(1, count):
        world.append(world[parents[i]] @ local[:, i])
    transforms = torch.stack(world, 1)
    return transforms, transforms[..., :3, 3]


def blended_transforms(weights: torch.Tensor, transforms: torch.Tensor,
                       rest_joints: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Each vertex's affine rest-to-posed map (M [B, V, 3, 3], c [B, V, 3]): sum_j w_j A_j with
    A_j = G_j [I | -J_j]. weights [V, J], transforms [B, J, 4, 4], rest_joints [B, J, 3]."""
    rot = transforms[..., :3, :3]
    trans = transforms[..., :3, 3] - (rot @ rest_joints[..., None])[..., 0]
    return torch.einsum("vj,bjxy->bvxy", weights, rot), torch.einsum("vj,bjx->bvx", weights, trans)


def skinning(vertices: torch.Tensor, weights: torch.Tensor, transforms: torch.Tensor, rest_joints: torch.Tensor) -> torch.Tensor:
    """LBS: v' = sum_j w_j G_j [v - J_j; 1] = M v + c (``blended_transforms``). vertices [B, V, 3],
    weights [V, J], transforms [B, J, 4, 4]."""
    blended_rot, blended_trans = blended_transforms(weights, transforms, rest_joints)
    return (blended_rot @ vertices[..., None])[..., 0] + blended_trans


def as_rotation_matrices(pose: torch.Tensor, num_joints: int) -> torch.Tensor:
    """Accept a pose as axis-angles [B, J, 3] / [B, 3J] or matrices [B, J, 3, 3]; return matrices."""
    if pose.ndim == 4 and pose.shape[-2:] == (3, 3):
        rotations = pose
    elif pose.ndim == 2 and pose.shape[1] == 3 * num_joints:
        rotations = axis_angle_to_matrix(pose.reshape(pose.shape[0], num_joints, 3))
    elif pose.ndim == 3 and pose.shape[-1] == 3:
        rotations = axis_angle_to_matrix(pose)
    else:
        raise ValueError(f"pose must be [B,{num_joints},3], [B,{3 * num_joints}] or [B,{num_joints},3,3], "
                         f"got {tuple(pose.shape)}")
    if rotations.shape[1] != num_joints:
        raise ValueError(f"pose has {rotations.shape[1]} joints, the model has {num_joints}")
    return rotations
