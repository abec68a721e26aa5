"""Pictures of a posed body with known truth: for calibrating the landmark model against the body
(``scripts/calibrate_landmarks.py``) and for tests. Canonical frame rotated as posed (Y up, metres)."""
from __future__ import annotations

import numpy as np

SKIN = (0.85, 0.65, 0.5)
CLOTH = (0.2, 0.3, 0.7)
BACKGROUND = (0.55, 0.6, 0.65)
LIGHT = (0.3, 0.6, 0.74)


def posed_body(body, pose: np.ndarray, betas=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertices [V,3], joints [J,3], joint rotations [J,3,3] in the posed frame) of ``body`` at
    ``pose`` [J,3] axis-angles and ``betas``."""
    import torch

    from darts.body import lbs

    model = body.to(torch.float64)
    shape = None if betas is None else torch.as_tensor(np.asarray(betas, np.float64))[None]
    out = model(torch.as_tensor(np.asarray(pose, np.float64))[None], shape)
    rotations = lbs.as_rotation_matrices(torch.as_tensor(np.asarray(pose, np.float64))[None], model.num_joints)
    transforms, _ = lbs.forward_kinematics(rotations, model.shaped(shape)[1], model.parents)
    return out.vertices[0].numpy(), out.joints[0].numpy(), transforms[0, :, :3, :3].numpy()


def render_person(camera, vertices: np.ndarray, faces: np.ndarray, worn=(), samples: int = 2) -> np.ndarray:
    """A shaded picture [H,W,3] uint8 of a body (``vertices``, ``faces``) wearing the meshes ``worn``
    [(vertices, faces)] (in ``CLOTH``), seen by ``camera`` against a plain background."""
    from darts.raycast import cast, shade, surface_normals

    meshes = [(vertices, faces), *worn]
    hits = cast(camera, meshes, samples)
    colour = np.full((len(hits.which), 3), BACKGROUND)
    for index, (points, mesh_faces) in enumerate(meshes):
        mine = hits.which == index
        normals = surface_normals(np.asarray(points, np.float64), np.asarray(mesh_faces), hits.face[mine], hits.point[mine])
        view = camera.centre - hits.point[mine]
        view /= np.linalg.norm(view, axis=1, keepdims=True)
        albedo = np.broadcast_to(SKIN if index == 0 else CLOTH, (int(mine.sum()), 3))
        colour[mine] = shade(normals, view, albedo, np.asarray(LIGHT))
    picture = colour.reshape(camera.height, camera.width, samples * samples, 3).mean(2)
    return (np.clip(picture, 0, 1) * 255).astype(np.uint8)
