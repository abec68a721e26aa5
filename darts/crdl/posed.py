"""A silhouette term seen on a posed body: the garment, deformed in the rest pose (the CRDL's
variables, canonical frame), is posed by the body's skinning before the term measures it.

Each garment vertex takes the skinning of the body where it sits at rest: the LBS weights
interpolated at its closest rest-body point (barycentrics on that triangle). With G_j the posed
transforms of the body's joints (``darts.body.lbs.forward_kinematics`` at ``pose``, ``betas``) and
A_j = G_j [I | -J_j], the vertex p_i is seen at

    q_i = sum_j w_ij A_j [p_i; 1] = M_i p_i + c_i,

an affine map fixed for the solve (the weights are found once, at the rest vertices ``bind`` is
given). The inner term (outline or soft) then compares the q_i with the mask through the camera of
the posed body (``darts.photo.fit.BodyFit.posed_camera``, or a dataset sample's).
"""
from __future__ import annotations

import numpy as np
import torch

from darts.crdl.term import SilhouetteTerm


class PosedTerm(SilhouetteTerm):
    """``inner`` (a silhouette term whose camera sees the posed body) on the garment posed by
    ``body`` (a ``BodyModel``) at ``pose`` [J,3] axis-angles (the root's first) and ``betas``."""

    def __init__(self, inner: SilhouetteTerm, body, pose: np.ndarray, betas=None):
        self.inner, self.body = inner, body
        self.pose = np.asarray(pose, np.float64)
        self.betas = None if betas is None or len(betas) == 0 else np.asarray(betas, np.float64)
        self.linear = self.offset = None

    def bind(self, vertices: np.ndarray, faces: np.ndarray) -> "PosedTerm":
        from darts.body import lbs
        from darts.geometry.distance import SurfaceDistance

        model = self.body.to(torch.float64)
        shaped, rest_joints = model.shaped(None if self.betas is None else self.betas[None])
        rest = shaped[0].numpy()
        triangle, bary = SurfaceDistance(rest, model.faces).closest_faces(np.asarray(vertices, np.float64))
        corners = model.faces[triangle]
        weights = np.einsum("vk,vkj->vj", bary, model.weights.numpy()[corners])
        rotations = lbs.as_rotation_matrices(torch.as_tensor(self.pose)[None], model.num_joints)
        transforms, _ = lbs.forward_kinematics(rotations, rest_joints, model.parents)
        rot = transforms[0, :, :3, :3]
        trans = transforms[0, :, :3, 3] - (rot @ rest_joints[0, :, :, None])[..., 0]
        weights = torch.as_tensor(weights)
        bound = PosedTerm(self.inner, self.body, self.pose, self.betas)
        bound.linear = torch.einsum("vj,jxy->vxy", weights, rot)
        bound.offset = torch.einsum("vj,jx->vx", weights, trans)
        bound.inner = self.inner.bind(bound.posed(torch.as_tensor(vertices, dtype=torch.float64)).numpy(), faces)
        return bound

    def posed(self, vertices: torch.Tensor) -> torch.Tensor:
        """q = M p + c [V,3] of rest vertices p [V,3] (module docstring)."""
        return torch.einsum("vxy,vy->vx", self.linear.to(vertices.dtype), vertices) + self.offset.to(vertices.dtype)

    def loss(self, vertices: torch.Tensor) -> torch.Tensor:
        return self.inner.loss(self.posed(vertices))
