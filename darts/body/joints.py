"""Joint names and parents of the SMPL family (SMPL 24, SMPL-H 52, SMPL-X 55)."""
from __future__ import annotations

import numpy as np

BODY_JOINT_NAMES = [
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar",
    "right_collar", "head", "left_shoulder", "right_shoulder", "left_elbow", "right_elbow",
    "left_wrist", "right_wrist",
]
SMPL_JOINT_NAMES = BODY_JOINT_NAMES + ["left_hand", "right_hand"]
SMPL_PARENTS = np.array([-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21])

_FINGERS = ["index", "middle", "pinky", "ring", "thumb"]


def _hand_names(side: str) -> list[str]:
    return [f"{side}_{finger}{k}" for finger in _FINGERS for k in (1, 2, 3)]


HAND_JOINT_NAMES = _hand_names("left") + _hand_names("right")
SMPLH_JOINT_NAMES = BODY_JOINT_NAMES + HAND_JOINT_NAMES
SMPLX_JOINT_NAMES = BODY_JOINT_NAMES + ["jaw", "left_eye", "right_eye"] + HAND_JOINT_NAMES

#: Number of joints -> (model kind, joint names).
KINDS = {24: ("smpl", SMPL_JOINT_NAMES), 52: ("smplh", SMPLH_JOINT_NAMES), 55: ("smplx", SMPLX_JOINT_NAMES)}


def kind_and_names(num_joints: int) -> tuple[str, list[str]]:
    """The model family and joint names for a joint count; unknown counts get generic names."""
    return KINDS.get(num_joints, ("custom", [f"joint{i}" for i in range(num_joints)]))


class BodySizes:
    """Counts and names of an SMPL-format body that holds ``v_template`` [V,3], ``shapedirs``
    [V,3,K] and ``parents`` [J] (numpy arrays or torch tensors alike)."""

    @property
    def num_vertices(self) -> int:
        return self.v_template.shape[0]

    @property
    def num_joints(self) -> int:
        return len(self.parents)

    @property
    def num_betas(self) -> int:
        return self.shapedirs.shape[-1]

    @property
    def kind(self) -> str:
        return kind_and_names(self.num_joints)[0]

    @property
    def joint_names(self) -> list[str]:
        return kind_and_names(self.num_joints)[1]
