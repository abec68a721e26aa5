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
  + WP |theta_body|^2 + WB |beta|^2                              priors

with p_k the body point of landmark k: its joint plus its offset in the joint's frame, J_j + R_j o_k
(``landmarks.json``, calibrated on renders of the body: ``scripts/calibrate_landmarks.py``), rho(r) =
r^2 / (1 + r^2) (Geman-McClure: a landmark far off costs at most 1), s = 5 % of the person's box
diagonal, and pi the pinhole projection. (A term pulling the body's landmarks, about the hips,
towards MediaPipe's metric ones made it worse on 12 renders of posed, shaped bodies with known
truth: joints 1.77 against 1.50 pixels off at weight 0.5, betas 0.96 against 0.74 off: its
skeleton is not this body's.) The fitted camera in the canonical frame of the unposed
body (root rotation R_0 about the pelvis j_0 taken into the camera) is x_c = F R_0 x + F (j_0 -
R_0 j_0) + t: the ``Camera`` a rest-posed garment is seen through.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import torch

from darts.camera import Camera
from darts.photo.person import LANDMARKS, Person

FOCAL = 1.0
SHAPE_COUNT = 8
FLIP = np.diag([1.0, -1.0, -1.0])
WP, WB = 0.02, 0.05
#: joints whose rotation is fitted besides the root: spine, neck, head, collars, shoulders, elbows, hips, knees
POSED = ("spine1", "spine2", "spine3", "neck", "head", "left_collar", "right_collar", "left_shoulder", "right_shoulder",
         "left_elbow", "right_elbow", "left_hip", "right_hip", "left_knee", "right_knee")
STEPS = (150, 250)
#: each landmark's joint and offset (m, the joint's frame), calibrated: ``scripts/calibrate_landmarks.py``
LANDMARK_TABLE = Path(__file__).parent / "landmarks.json"


@lru_cache(maxsize=1)
def landmark_table() -> tuple[list[str], np.ndarray]:
    """(each landmark's joint name, offsets [33,3] m in the joint's frame), in ``LANDMARKS`` order."""
    table = json.loads(LANDMARK_TABLE.read_text())["landmarks"]
    return [table[name]["joint"] for name in LANDMARKS], np.array([table[name]["offset_m"] for name in LANDMARKS])


class Adam:
    """Adam (Kingma & Ba 2015) as ``torch.optim.Adam`` computes it (betas 0.9, 0.999, eps 1e-8): per
    variable m <- b1 m + (1 - b1) g, v <- b2 v + (1 - b2) g^2, p <- p - lr / (1 - b1^t) m /
    (sqrt(v) / sqrt(1 - b2^t) + eps). Written out because constructing torch's optimiser imports
    its compiler (torch._dynamo): 1.5 s of a photograph's 10."""

    def __init__(self, variables: list[torch.Tensor], lr: float, betas: tuple[float, float] = (0.9, 0.999),
                 eps: float = 1e-8):
        self.variables, self.lr, self.betas, self.eps, self.t = variables, lr, betas, eps, 0
        self.m = [torch.zeros_like(v) for v in variables]
        self.v = [torch.zeros_like(v) for v in variables]

    @torch.no_grad()
    def step(self) -> None:
        self.t += 1
        b1, b2 = self.betas
        correction1, correction2 = 1 - b1 ** self.t, 1 - b2 ** self.t
        for variable, m, v in zip(self.variables, self.m, self.v):
            g = variable.grad
            m.lerp_(g, 1 - b1)
            v.mul_(b2).addcmul_(g, g, value=1 - b2)
            variable.addcdiv_(m, (v.sqrt() / correction2 ** 0.5).add_(self.eps), value=-self.lr / correction1)


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
                "camera": self.camera.as_dict(), "posed_camera": self.posed_camera.as_dict()}


def fit_body(person: Person, body, width: int, height: int) -> BodyFit:
    """Fit ``body`` (a ``BodyModel``) to ``person`` found in a ``width`` x ``height`` picture (module
    docstring). Deterministic (no random draw); runs on one torch thread (its tensors are tiny:
    more threads only cost), restoring the caller's setting."""
    from darts.threads import one_torch_thread

    with one_torch_thread():
        return _fit(person, body, width, height)


def _fit(person: Person, body, width: int, height: int) -> BodyFit:
    from darts.body import lbs

    model = body.to(torch.float64)
    names = model.joint_names
    focal = FOCAL * max(width, height)
    centre = torch.tensor([width / 2.0, height / 2.0], dtype=torch.float64)
    flip = torch.tensor(FLIP)
    joint_names, offsets = landmark_table()
    joint_index = torch.tensor([names.index(j) for j in joint_names])
    offsets = torch.tensor(offsets, dtype=torch.float64)
    target = torch.tensor(person.landmarks, dtype=torch.float64)
    weight = torch.tensor(person.visibility, dtype=torch.float64)
    torso = torch.tensor([1.0 if name.endswith(("shoulder", "hip")) else 0.0 for name in LANDMARKS], dtype=torch.float64)
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
    hip_points = [person.point("left_hip"), person.point("right_hip")]
    torso_px = np.linalg.norm(np.mean(shoulders, 0) - np.mean(hip_points, 0))
    depth = focal * 0.5 / max(torso_px, 1.0)  # a torso about 0.5 m long
    middle = (np.mean(shoulders, 0) + np.mean(hip_points, 0)) / 2
    start = np.array([(middle[0] - width / 2) * depth / focal, (middle[1] - height / 2) * depth / focal, depth])
    translation = torch.tensor(start, dtype=torch.float64, requires_grad=True)
    # Only the joints are needed while fitting: linear in beta.
    joint_template = model.J_regressor @ model.v_template
    joint_dirs = torch.einsum("jv,vdk->jdk", model.J_regressor, model.shapedirs[..., :count])

    def points(full_pose, shape):
        """Each landmark's body point J_j + R_j o_k [33,3] (posed frame)."""
        rotations = lbs.as_rotation_matrices(full_pose[None], model.num_joints)
        rest_j = (joint_template + (joint_dirs @ shape if shape is not None else 0.0))[None]
        transforms, joints = lbs.forward_kinematics(rotations, rest_j, model.parents)
        frames = transforms[0, joint_index, :3, :3]
        return joints[0, joint_index] + torch.einsum("kxy,ky->kx", frames, offsets)

    def full_pose(stage: int) -> torch.Tensor:
        """Every joint's axis-angle [J,3]: the root's, and in the second stage the posed joints'."""
        full = pose.index_put((torch.tensor([0]),), root[None])
        return full.index_put((torch.tensor(posed_index),), body_pose) if stage else full

    def objective(stage: int):
        p = points(full_pose(stage), betas if stage else None)
        camera_points = p @ flip.T + translation
        pixels = focal * camera_points[:, :2] / camera_points[:, 2:].clamp(min=0.05) + centre
        r2 = ((pixels - target) ** 2).sum(1) / scale ** 2
        loss = ((weight if stage else weight * torso) * r2 / (1 + r2)).sum()
        if stage:
            loss = loss + WP * (body_pose ** 2).sum() + WB * (betas ** 2).sum()
        return loss

    for stage, steps in enumerate(STEPS):
        variables = [root, translation] + ([body_pose, betas] if stage else [])
        optimiser = Adam(variables, lr=0.02)
        for _ in range(steps):
            for variable in variables:
                variable.grad = None
            loss = objective(stage)
            loss.backward()
            optimiser.step()
    with torch.no_grad():
        full = full_pose(1)
        p = points(full, betas)
        camera_points = p @ flip.T + translation
        pixels = (focal * camera_points[:, :2] / camera_points[:, 2:] + centre).numpy()
        output = model(full[None], betas[None])
    visible = person.visibility > 0.5
    error = np.linalg.norm(pixels - person.landmarks, axis=1)[visible]
    pose_np, t = full.detach().numpy(), translation.detach().numpy()
    root_rotation = lbs.as_rotation_matrices(full[None, :1].detach(), 1)[0, 0].numpy()
    pelvis = model.shaped(betas[None].detach())[1][0, 0].numpy()
    camera = Camera(width, height, focal, focal, width / 2.0, height / 2.0, FLIP @ root_rotation,
                    FLIP @ (pelvis - root_rotation @ pelvis) + t)
    posed_camera = Camera(width, height, focal, focal, width / 2.0, height / 2.0, FLIP.copy(), t.copy())
    return BodyFit(pose_np, betas.detach().numpy(), t, camera, posed_camera, output.vertices[0].numpy(),
                   float(np.median(error)) if len(error) else float("nan"), int(visible.sum()))
