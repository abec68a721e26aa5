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

from dataclasses import dataclass

import numpy as np
import torch

from darts.crdl.term import SilhouetteTerm


@dataclass
class Posing:
    """The affine map q = M p + c of each garment vertex (``linear`` [V,3,3], ``offset`` [V,3];
    module docstring)."""

    linear: torch.Tensor
    offset: torch.Tensor

    @classmethod
    def of(cls, body, pose: np.ndarray, betas, vertices: np.ndarray) -> Posing:
        """The posing of a garment at rest ``vertices`` [V,3] by ``body`` (a ``BodyModel``) at ``pose``
        [J,3] axis-angles (the root's first) and ``betas`` (None or empty: the body's rest shape)."""
        from darts.body import lbs
        from darts.geometry.distance import SurfaceDistance

        model = body.to(torch.float64)
        shape = None if betas is None or len(betas) == 0 else torch.as_tensor(np.asarray(betas, np.float64))[None]
        shaped, rest_joints = model.shaped(shape)
        triangle, bary = SurfaceDistance(shaped[0].numpy(), model.faces).closest_faces(np.asarray(vertices, np.float64))
        weights = np.einsum("vk,vkj->vj", bary, model.weights.numpy()[model.faces[triangle]])
        rotations = lbs.as_rotation_matrices(torch.as_tensor(np.asarray(pose, np.float64))[None], model.num_joints)
        transforms, _ = lbs.forward_kinematics(rotations, rest_joints, model.parents)
        linear, offset = lbs.blended_transforms(torch.as_tensor(weights), transforms, rest_joints)
        return cls(linear[0], offset[0])

    def __call__(self, vertices: torch.Tensor) -> torch.Tensor:
        """q = M p + c [V,3] of rest vertices p [V,3]."""
        return torch.einsum("vxy,vy->vx", self.linear.to(vertices.dtype), vertices) + self.offset.to(vertices.dtype)


class PosedTerm(SilhouetteTerm):
    """``inner`` (a silhouette term whose camera sees the posed body) on the garment posed by
    ``body`` (a ``BodyModel``) at ``pose`` [J,3] axis-angles (the root's first) and ``betas``."""

    def __init__(self, inner: SilhouetteTerm, body, pose: np.ndarray, betas=None, posing: Posing | None = None):
        self.inner, self.body, self.pose, self.betas, self.posing = inner, body, pose, betas, posing

    def bind(self, vertices: np.ndarray, faces: np.ndarray) -> PosedTerm:
        posing = Posing.of(self.body, self.pose, self.betas, vertices)
        inner = self.inner.bind(posing(torch.as_tensor(vertices, dtype=torch.float64)).numpy(), faces)
        return PosedTerm(inner, self.body, self.pose, self.betas, posing)

    def loss(self, vertices: torch.Tensor) -> torch.Tensor:
        return self.inner.loss(self.posing(vertices))
