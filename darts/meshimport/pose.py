"""Templates with their arms lowered, for garments made in another pose than our T-pose.

Garment tools export tops and dresses with the arms hanging (an A-pose), where a template's sleeves
stand out level with the shoulders; fitted as they are, the sleeves are left out (Newton's
``unisex_shirt.usd``: the file 5.2 mm from the DART on average, p95 33 mm, and its category
guessed wrong). The template is posed instead by the body's own skinning (``darts.crdl.posed.Posing``:
each vertex takes the blend weights of its closest rest-body point) with both shoulder joints turned
down by an angle about the canonical front axis +Z (the left arm, along +X, by -a; the right by
+a), placed and registered in that pose against the body so posed, and the result is taken back to
the rest pose by the inverse of each vertex's blended transform: p = M^-1 (q - c), exact for the
same binding. Canonical frame, Y up, metres.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

#: Degrees the arms are lowered by in the poses tried for tops and dresses (their cuffs or armholes
#: follow the arms); the other families are tried at rest only.
ARM_ANGLES = (0.0, 30.0, 45.0, 60.0)
#: The families whose openings follow the arms.
ARM_FAMILIES = ("top", "dress")


@dataclass
class LoweredArms:
    """A template posed with its arms lowered by ``degrees``: ``template`` (the posed DART),
    ``body_vertices`` [B,3] (the body in that pose), and each template vertex's blended transform
    (``linear`` [V,3,3], ``offset`` [V,3]) for ``rest``."""

    degrees: float
    template: object
    body_vertices: np.ndarray
    linear: np.ndarray
    offset: np.ndarray

    def rest(self, vertices: np.ndarray, bound_to: np.ndarray | None = None) -> np.ndarray:
        """Posed points [N,3] back in the rest pose: the template's vertices (moved), or with
        ``bound_to`` [N] any points, each by the transform of the template vertex it names."""
        linear, offset = (self.linear, self.offset) if bound_to is None else (self.linear[bound_to], self.offset[bound_to])
        return np.linalg.solve(linear, (np.asarray(vertices, np.float64) - offset)[..., None])[..., 0]


def lower_arms(template, body, degrees: float) -> LoweredArms:
    """``template`` (a DART at rest on ``body``, a ``BodyModel``) with both arms lowered by ``degrees``."""
    import torch

    from darts.crdl.posed import Posing

    pose = np.zeros((body.num_joints, 3))
    angle = np.radians(degrees)
    pose[body.joint_names.index("left_shoulder")] = [0.0, 0.0, -angle]
    pose[body.joint_names.index("right_shoulder")] = [0.0, 0.0, angle]
    betas = template.body_betas if len(template.body_betas) else None
    rest = np.asarray(template.vertices, np.float64)
    posing = Posing.of(body, pose, betas, rest)
    linear, offset = posing.linear.numpy(), posing.offset.numpy()
    shape = None if betas is None else torch.as_tensor(np.asarray(betas), dtype=body.dtype)[None]
    posed_body = body(torch.as_tensor(pose[None], dtype=body.dtype), betas=shape).vertices[0].double().numpy()
    posed = np.einsum("vxy,vy->vx", linear, rest) + offset
    return LoweredArms(float(degrees), replace(template, vertices=posed.astype(np.float32)), posed_body, linear, offset)


def arm_angles(family: str) -> tuple[float, ...]:
    """The arm angles tried for a category of ``family``."""
    return ARM_ANGLES if family in ARM_FAMILIES else (0.0,)
