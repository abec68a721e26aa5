"""The SMPL-format body model: template, shape and pose blend shapes, joint regressor, LBS weights.

``BodyModel.forward`` evaluates M(beta, theta) + trans for a batch of frames. Rest data are in the
canonical frame (Y up, metres); with an AMASS pose the root rotation carries them into Z-up world.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch

from darts.body import lbs
from darts.body.joints import BodySizes


@dataclass
class BodyOutput:
    """Posed body: vertices [B, V, 3] and joints [B, J, 3] in the frame the pose puts them in."""

    vertices: torch.Tensor
    joints: torch.Tensor


@dataclass
class BodyModel(BodySizes):
    """An SMPL-format body. Tensors: v_template [V,3], shapedirs [V,3,K], posedirs [V,3,9(J-1)] or
    None (all zero), J_regressor [J,V], weights [V,J]; faces [F,3] and parents [J] are numpy."""

    name: str
    v_template: torch.Tensor
    faces: np.ndarray
    shapedirs: torch.Tensor
    posedirs: torch.Tensor | None
    J_regressor: torch.Tensor
    weights: torch.Tensor
    parents: np.ndarray
    gender: str = "neutral"
    metadata: dict = field(default_factory=dict)

    @property
    def dtype(self) -> torch.dtype:
        return self.v_template.dtype

    @classmethod
    def from_arrays(cls, body, dtype: torch.dtype | None = None) -> BodyModel:
        """The model of validated ``BodyArrays`` (``darts.body.io``), tensors of ``dtype`` (float32 by default)."""
        dtype = torch.float32 if dtype is None else dtype
        as_tensor = lambda a: None if a is None else torch.as_tensor(a, dtype=dtype)  # noqa: E731
        return cls(body.name, as_tensor(body.v_template), body.faces, as_tensor(body.shapedirs),
                   as_tensor(body.posedirs), as_tensor(body.J_regressor), as_tensor(body.weights),
                   body.parents, body.gender, dict(body.metadata))

    def to(self, dtype: torch.dtype) -> BodyModel:
        """A copy whose tensors have ``dtype``."""
        cast = lambda t: None if t is None else t.to(dtype)  # noqa: E731
        return BodyModel(self.name, cast(self.v_template), self.faces, cast(self.shapedirs),
                         cast(self.posedirs), cast(self.J_regressor), cast(self.weights),
                         self.parents, self.gender, dict(self.metadata))

    def _betas(self, betas, batch: int) -> torch.Tensor:
        if betas is None:
            return torch.zeros(batch, 0, dtype=self.dtype)
        betas = torch.as_tensor(betas, dtype=self.dtype)
        if betas.ndim == 1:
            betas = betas[None]
        if betas.shape[-1] > self.num_betas:
            raise ValueError(f"{betas.shape[-1]} betas given, the model has {self.num_betas}")
        return betas

    def shaped(self, betas=None) -> tuple[torch.Tensor, torch.Tensor]:
        """Rest shape T + B_S(beta) [B,V,3] and its regressed joints J(beta) [B,J,3] (canonical frame)."""
        betas = self._betas(betas, 1)
        v_shaped = self.v_template[None] + lbs.blend_shapes(betas, self.shapedirs)
        joints = torch.einsum("jv,bvd->bjd", self.J_regressor, v_shaped)
        return v_shaped, joints

    def forward(self, pose=None, betas=None, trans=None) -> BodyOutput:
        """M(beta, theta) + trans. pose: [B,J,3] / [B,3J] axis-angles or [B,J,3,3]; betas [K'] or
        [B,K']; trans [B,3]. Missing pose is the rest pose; every argument broadcasts over B."""
        if pose is None:
            pose = torch.zeros(1, self.num_joints, 3, dtype=self.dtype)
        rotations = lbs.as_rotation_matrices(torch.as_tensor(pose, dtype=self.dtype), self.num_joints)
        batch = rotations.shape[0]
        v_shaped, rest_joints = self.shaped(betas)
        if v_shaped.shape[0] not in (1, batch):
            raise ValueError(f"betas batch {v_shaped.shape[0]} does not match pose batch {batch}")
        v_shaped = v_shaped.expand(batch, -1, -1)
        rest_joints = rest_joints.expand(batch, -1, -1)
        if self.posedirs is not None:
            offsets = self.posedirs.reshape(-1, self.posedirs.shape[-1]) @ lbs.pose_features(rotations).T
            v_shaped = v_shaped + offsets.T.reshape(batch, -1, 3)
        transforms, joints = lbs.forward_kinematics(rotations, rest_joints, self.parents)
        vertices = lbs.skinning(v_shaped, self.weights, transforms, rest_joints)
        if trans is not None:
            trans = torch.as_tensor(trans, dtype=self.dtype).reshape(-1, 1, 3)
            vertices, joints = vertices + trans, joints + trans
        return BodyOutput(vertices, joints)

    __call__ = forward
