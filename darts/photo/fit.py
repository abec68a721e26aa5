"""The body in a photograph: pose, shape and camera of an SMPL-format body fitted to a person's
landmarks (``darts.photo.person``).

Unknowns: the body's joint rotations theta (axis-angle, the root's included), its first
``SHAPE_COUNT`` betas, and its translation t in the camera's frame; the focal length is assumed,
``FOCAL`` x the picture's long side (a normal lens: 53 degrees across the long side), the principal
point at the centre. A canonical-frame point x (Y up, front +Z) of the posed body M(theta, beta)
sits at F x + t in the camera's frame, F = diag(1, -1, -1) (OpenCV: x right, y down, looking along
+z; the body faces the camera at theta = 0). Minimised (Adam, in two stages: the root and t on the
shoulders and hips, then everything):

    sum_k v_k rho(|pi(F p_k + t) - l_k| / s)                     landmarks l_k, visibility v_k
  + W3 sum_k v_k |F (p_k - p_hips) - w_k|^2 / (0.1 m)^2          MediaPipe's metric landmarks w_k
  + WP |theta_body|^2 + WB |beta|^2                              priors

with p_k the body point of landmark k (a joint, or a vertex for the nose and ears), rho(r) =
r^2 / (1 + r^2) (Geman-McClure: a landmark far off costs at most 1), s = 5 % of the person's box
diagonal, and pi the pinhole projection. The fitted camera in the canonical frame of the unposed
body (root rotation R_0 about the pelvis j_0 taken into the camera) is x_c = F R_0 x + F (j_0 -
R_0 j_0) + t: the ``Camera`` a rest-posed garment is seen through.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from darts.camera import Camera
from darts.photo.person import LANDMARKS, Person

FOCAL = 1.0
SHAPE_COUNT = 8
FLIP = np.diag([1.0, -1.0, -1.0])
W3, WP, WB = 0.5, 0.02, 0.05
#: landmark -> body joint (SMPL names); the nose and ears are vertices (``_head_vertices``)
JOINT_OF = {
    "left_shoulder": "left_shoulder", "right_shoulder": "right_shoulder", "left_elbow": "left_elbow",
    "right_elbow": "right_elbow", "left_wrist": "left_wrist", "right_wrist": "right_wrist", "left_hip": "left_hip",
    "right_hip": "right_hip", "left_knee": "left_knee", "right_knee": "right_knee", "left_ankle": "left_ankle",
    "right_ankle": "right_ankle", "left_foot_index": "left_foot", "right_foot_index": "right_foot",
}
HEAD_LANDMARKS = ("nose", "left_ear", "right_ear")
#: joints whose rotation is fitted besides the root: spine, neck, head, collars, shoulders, elbows, hips, knees
POSED = ("spine1", "spine2", "spine3", "neck", "head", "left_collar", "right_collar", "left_shoulder", "right_shoulder",
         "left_elbow", "right_elbow", "left_hip", "right_hip", "left_knee", "right_knee")
STEPS = (150, 250)


@dataclass
class BodyFit:
    """A body fitted to a person: ``pose`` [J,3] axis-angles (the root's first), ``betas`` [K],
    ``translation`` [3] (camera frame, m), the ``camera`` of the rest-posed body (canonical frame,
    the picture's size), the posed ``vertices`` [V,3] in the canonical frame rotated as posed, and
    the median distance (pixels) of the visible landmarks from the body's projected points."""

    pose: np.ndarray
    betas: np.ndarray
    translation: np.ndarray
    camera: Camera
    posed_camera: Camera
    vertices: np.ndarray
    landmark_error_px: float
    landmarks_used: int

    def as_dict(self) -> dict:
        return {"betas": self.betas.round(4).tolist(), "pose_axis_angle": self.pose.round(4).tolist(),
                "translation_m": self.translation.round(4).tolist(), "landmark_error_px": round(self.landmark_error_px, 2),
                "landmarks_used": self.landmarks_used, "focal_px": self.camera.fx,
                "camera": self.camera.as_dict()}


def _head_vertices(rest: np.ndarray, head: np.ndarray) -> dict[str, int]:
    """Rest-shape vertices [V,3] of the nose (the most forward one near the head's middle plane) and
    the ears (the farthest to either side at the head joint's height), the head joint at ``head``."""
    near = np.linalg.norm(rest - head, axis=1) < 0.15
    middle = near & (np.abs(rest[:, 0]) < 0.015) & (rest[:, 1] < head[1] + 0.02)
    nose = int(np.flatnonzero(middle)[np.argmax(rest[middle, 2])])
    level = near & (np.abs(rest[:, 1] - head[1]) < 0.03)
    left = int(np.flatnonzero(level)[np.argmax(rest[level, 0])])
    right = int(np.flatnonzero(level)[np.argmin(rest[level, 0])])
    return {"nose": nose, "left_ear": left, "right_ear": right}


def fit_body(person: Person, body, width: int, height: int) -> BodyFit:
    """Fit ``body`` (a ``BodyModel``) to ``person`` found in a ``width`` x ``height`` picture (module
    docstring). Deterministic (no random draw); runs on one torch thread (its tensors are tiny:
    more threads only cost), restoring the caller's setting."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        return _fit(person, body, width, height)
    finally:
        torch.set_num_threads(threads)


def _fit(person: Person, body, width: int, height: int) -> BodyFit:
    from darts.body import lbs

    model = body.to(torch.float64)
    names = model.joint_names
    focal = FOCAL * max(width, height)
    centre = torch.tensor([width / 2.0, height / 2.0], dtype=torch.float64)
    flip = torch.tensor(FLIP)
    rest, rest_joints = (t[0].numpy() for t in model.shaped(None))
    heads = _head_vertices(rest, rest_joints[names.index("head")])
    joint_rows = [(LANDMARKS.index(k), names.index(j)) for k, j in JOINT_OF.items()]
    head_rows = [(LANDMARKS.index(k), heads[k]) for k in HEAD_LANDMARKS]
    marks = [m for m, _ in joint_rows] + [m for m, _ in head_rows]
    target = torch.tensor(person.landmarks[marks], dtype=torch.float64)
    weight = torch.tensor(person.visibility[marks], dtype=torch.float64)
    world = torch.tensor(person.world[marks], dtype=torch.float64)
    world = world - world[[m for m, (k, _) in enumerate(joint_rows) if names[_] in ("left_hip", "right_hip")]].mean(0)
    box = person.detection.box
    seen = person.landmarks[person.visibility > 0.5]
    extent = np.ptp(seen, axis=0) if len(seen) > 1 else box[2:] - box[:2]
    scale = 0.05 * float(np.hypot(*np.maximum(extent, 1.0)))

    count = SHAPE_COUNT if model.num_betas >= SHAPE_COUNT else model.num_betas
    betas = torch.zeros(count, dtype=torch.float64, requires_grad=True)
    pose = torch.zeros(model.num_joints, 3, dtype=torch.float64)
    root = torch.zeros(3, dtype=torch.float64, requires_grad=True)
    body_pose = torch.zeros(len(POSED), 3, dtype=torch.float64, requires_grad=True)
    posed_index = [names.index(n) for n in POSED]
    shoulders = [person.point("left_shoulder"), person.point("right_shoulder")]
    hips = [person.point("left_hip"), person.point("right_hip")]
    torso_px = np.linalg.norm(np.mean(shoulders, 0) - np.mean(hips, 0))
    depth = focal * 0.5 / max(torso_px, 1.0)  # a torso about 0.5 m long
    middle = (np.mean(shoulders, 0) + np.mean(hips, 0)) / 2
    start = np.array([(middle[0] - width / 2) * depth / focal, (middle[1] - height / 2) * depth / focal, depth])
    translation = torch.tensor(start, dtype=torch.float64, requires_grad=True)
    head_index = torch.tensor([v for _, v in head_rows])
    hip_rows = [k for k, (_, j) in enumerate(joint_rows) if names[j] in ("left_hip", "right_hip")]

    # Only the joints and three head vertices are needed while fitting: both are linear in beta.
    joint_template = model.J_regressor @ model.v_template
    joint_dirs = torch.einsum("jv,vdk->jdk", model.J_regressor, model.shapedirs[..., :count])
    head_template, head_dirs = model.v_template[head_index], model.shapedirs[head_index][..., :count]
    head_weights = model.weights[head_index]

    def points(full_pose, shape):
        rotations = lbs.as_rotation_matrices(full_pose[None], model.num_joints)
        rest_j = (joint_template + (joint_dirs @ shape if shape is not None else 0.0))[None]
        heads_rest = (head_template + (head_dirs @ shape if shape is not None else 0.0))[None]
        transforms, joints = lbs.forward_kinematics(rotations, rest_j, model.parents)
        heads_posed = lbs.skinning(heads_rest, head_weights, transforms, rest_j)
        return torch.cat([joints[0, [j for _, j in joint_rows]], heads_posed[0]]), joints[0]

    def objective(stage: int):
        full = pose.index_put((torch.tensor([0]),), root[None])
        if stage:
            full = full.index_put((torch.tensor(posed_index),), body_pose)
        p, _ = points(full, betas if stage else None)
        camera_points = p @ flip.T + translation
        pixels = focal * camera_points[:, :2] / camera_points[:, 2:].clamp(min=0.05) + centre
        r2 = ((pixels - target) ** 2).sum(1) / scale ** 2
        use = weight if stage else weight * torch.tensor([1.0 if LANDMARKS[m].endswith(("shoulder", "hip")) else 0.0
                                                            for m in marks], dtype=torch.float64)
        loss = (use * r2 / (1 + r2)).sum()
        if stage:
            relative = (p - p[hip_rows].mean(0)) @ flip.T
            loss = loss + W3 * (weight * ((relative - world) ** 2).sum(1)).sum() / 0.01
            loss = loss + WP * (body_pose ** 2).sum() + WB * (betas ** 2).sum()
        return loss

    for stage, steps in enumerate(STEPS):
        variables = [root, translation] + ([body_pose, betas] if stage else [])
        optimiser = torch.optim.Adam(variables, lr=0.02)
        for _ in range(steps):
            optimiser.zero_grad()
            loss = objective(stage)
            loss.backward()
            optimiser.step()
    with torch.no_grad():
        full = pose.index_put((torch.tensor([0]),), root[None]).index_put((torch.tensor(posed_index),), body_pose)
        p, _ = points(full, betas)
        camera_points = p @ flip.T + translation
        pixels = (focal * camera_points[:, :2] / camera_points[:, 2:] + centre).numpy()
        output = model(full[None], betas[None])
    visible = person.visibility[marks] > 0.5
    error = np.linalg.norm(pixels - person.landmarks[marks], axis=1)[visible]
    pose_np, t = full.detach().numpy(), translation.detach().numpy()
    root_rotation = lbs.as_rotation_matrices(full[None, :1].detach(), 1)[0, 0].numpy()
    pelvis = model.shaped(betas[None].detach())[1][0, 0].numpy()
    camera = Camera(width, height, focal, focal, width / 2.0, height / 2.0, FLIP @ root_rotation,
                    FLIP @ (pelvis - root_rotation @ pelvis) + t)
    posed_camera = Camera(width, height, focal, focal, width / 2.0, height / 2.0, FLIP.copy(), t.copy())
    return BodyFit(pose_np, betas.detach().numpy(), t, camera, posed_camera, output.vertices[0].numpy(),
                   float(np.median(error)) if len(error) else float("nan"), int(visible.sum()))
