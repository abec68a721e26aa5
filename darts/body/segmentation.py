"""Per-vertex body part segmentation derived from a body's rest shape and joints.

Works in the canonical frame (Y up, front +Z, left +X) of the rest (T-) pose, so the same rules
segment the bundled body and official SMPL / SMPL-H / SMPL-X files. Boundaries are planes chosen so
garments can be cut cleanly: each arm is cut by planes perpendicular to its bones (the shoulder cut
passes through the armpit), the legs by a line rising from the crotch to the side of the hip.
"""
from __future__ import annotations

import numpy as np

PART_NAMES = [
    "head", "neck", "upper_torso", "lower_torso", "hips",
    "left_upper_arm", "right_upper_arm", "left_forearm", "right_forearm", "left_hand", "right_hand",
    "left_thigh", "right_thigh", "left_calf", "right_calf", "left_foot", "right_foot",
]
PART_INDEX = {name: i for i, name in enumerate(PART_NAMES)}


def _joint(joints: np.ndarray, names: list[str], *candidates: str) -> np.ndarray:
    for name in candidates:
        if name in names:
            return joints[names.index(name)]
    raise ValueError(f"the body has none of the joints {candidates}")


def _beyond(vertices: np.ndarray, origin: np.ndarray, towards: np.ndarray) -> np.ndarray:
    """True where a vertex lies past the plane through ``origin`` facing ``towards - origin``."""
    axis = towards - origin
    return (vertices - origin) @ (axis / np.linalg.norm(axis)) > 0.0


def segment_body(vertices: np.ndarray, joints: np.ndarray, joint_names: list[str]) -> np.ndarray:
    """Part label per vertex (indices into PART_NAMES) for a body in its canonical rest pose.

    vertices [V, 3] and joints [J, 3] in the canonical frame (metres, Y up).
    """
    j = lambda *names: _joint(joints, joint_names, *names)  # noqa: E731
    x, y = vertices[:, 0], vertices[:, 1]
    labels = np.full(len(vertices), PART_INDEX["upper_torso"], np.int64)

    pelvis, neck, head = j("pelvis"), j("neck"), j("head")
    waist_y = j("spine1")[1]
    chest_y = 0.5 * (j("spine2")[1] + j("spine3")[1])
    labels[y < chest_y] = PART_INDEX["lower_torso"]
    labels[y < waist_y] = PART_INDEX["hips"]

    # Neck from a plane through the neck joint, tilted so the front (sternal notch) sits lower
    # than the back; the head from the plane just under the head joint.
    tilt = np.array([0.0, 1.0, 0.35]) / np.linalg.norm([0.0, 1.0, 0.35])
    near_axis = ((x - neck[0]) / 0.09) ** 2 + ((vertices[:, 2] - neck[2]) / 0.2) ** 2 < 1.0
    labels[((vertices - neck) @ tilt > 0.0) & near_axis] = PART_INDEX["neck"]
    labels[y > head[1] - 0.01] = PART_INDEX["head"]

    # Legs: below a line that rises from the crotch to the outside of each hip joint.
    hip_x = abs(j("left_hip")[0] - j("right_hip")[0]) / 2.0
    centre = np.abs(x - pelvis[0]) < 0.01
    crotch_y = y[centre & (y < pelvis[1])].min() if (centre & (y < pelvis[1])).any() else pelvis[1] - 0.1
    hip_y = 0.5 * (j("left_hip")[1] + j("right_hip")[1])
    slope = max(hip_y - crotch_y, 0.0) / (hip_x + 0.08)
    legs = y < crotch_y + slope * np.abs(x - pelvis[0])
    for side in ("left", "right"):
        sign = 1.0 if side == "left" else -1.0
        leg = legs & (sign * (x - pelvis[0]) > 0)
        labels[leg] = PART_INDEX[f"{side}_thigh"]
        labels[leg & (y < j(f"{side}_knee")[1])] = PART_INDEX[f"{side}_calf"]
        labels[leg & (y < j(f"{side}_ankle")[1])] = PART_INDEX[f"{side}_foot"]

        # Arms: planes perpendicular to each bone, applied from the shoulder outwards.
        shoulder, elbow, wrist = j(f"{side}_shoulder"), j(f"{side}_elbow"), j(f"{side}_wrist")
        hand = j(f"{side}_hand", f"{side}_middle1")
        arm = _beyond(vertices, shoulder, elbow) & (y > shoulder[1] - 0.2) & ~legs
        labels[arm] = PART_INDEX[f"{side}_upper_arm"]
        labels[arm & _beyond(vertices, elbow, wrist)] = PART_INDEX[f"{side}_forearm"]
        labels[arm & _beyond(vertices, wrist, hand)] = PART_INDEX[f"{side}_hand"]
    return labels


def body_segmentation(model) -> np.ndarray:
    """Part labels of a BodyModel: the ones shipped with it, else derived from its mean shape."""
    if "part_labels" in model.metadata:
        return np.asarray(model.metadata["part_labels"])
    vertices, joints = model.shaped()
    return segment_body(vertices[0].double().numpy(), joints[0].double().numpy(), model.joint_names)
