"""A dataset picture: the draped garment on the rest-posed body, ray cast (``darts.raycast``) with
2 x 2 samples per pixel. Masks are per pixel: garment (or body) where at least half of the pixel's
samples see it first."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.raycast import cast, shade, surface_normals
from sim.dataset.appearance import Appearance, background, cloth_albedo

SAMPLES = 2
INSIDE = 0.6  # the inside of the cloth (seen through an opening) is this much darker


@dataclass
class Picture:
    image: np.ndarray  # [H,W,3] uint8
    garment_mask: np.ndarray  # [H,W] bool
    body_mask: np.ndarray  # [H,W] bool


def render(garment: tuple[np.ndarray, np.ndarray], body: tuple[np.ndarray, np.ndarray], look: Appearance,
           rng: np.random.Generator, unseen: bool) -> Picture:
    """Draw ``garment`` and ``body`` ((vertices [V,3], faces [F,3]), canonical frame) as ``look`` says."""
    camera = look.camera
    hits = cast(camera, [body, garment], SAMPLES)
    colour = np.zeros((len(hits.which), 3))
    view = camera.centre - hits.point
    view /= np.maximum(np.linalg.norm(view, axis=1, keepdims=True), 1e-12)
    light = np.asarray(look.light)
    for index, (vertices, faces) in enumerate((body, garment)):
        mine = hits.which == index
        if not mine.any():
            continue
        normals = surface_normals(np.asarray(vertices, np.float64), np.asarray(faces), hits.face[mine], hits.point[mine])
        if index == 0:
            albedo = np.broadcast_to(np.asarray(look.skin), (int(mine.sum()), 3))
            colour[mine] = shade(normals, view[mine], albedo, light, specular=0.04)
        else:
            albedo = cloth_albedo(hits.point[mine], look) * np.where(hits.front[mine], 1.0, INSIDE)[:, None]
            colour[mine] = shade(normals, view[mine], albedo, light)
    h, w, s2 = camera.height, camera.width, SAMPLES * SAMPLES
    which = hits.which.reshape(h, w, s2)
    back = background(look, rng, w, unseen).reshape(h, w, 1, 3)
    samples = np.where((which >= 0)[..., None], colour.reshape(h, w, s2, 3), back)
    image = samples.mean(2) + rng.normal(0.0, look.noise, (h, w, 3))
    return Picture((np.clip(image, 0, 1) * 255 + 0.5).astype(np.uint8),
                   (which == 1).sum(2) * 2 >= s2, (which == 0).sum(2) * 2 >= s2)
