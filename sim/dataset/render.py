"""Dataset pictures: meshes ray cast (``darts.raycast``) with 2 x 2 samples per pixel, each mesh with
its own colour; masks are per pixel: a mesh's where at least half of the pixel's samples see it first.

``render`` is the rest-pose dataset's picture (the draped garment on the body); ``render_scene``
draws any list of meshes in front of a given background (the posed dataset's body, garment and
the other garment worn with it, ``sim.dataset.posed``).
"""
from __future__ import annotations

from collections.abc import Callable
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


@dataclass
class SceneMesh:
    """A mesh to draw: vertices [V,3], faces [F,3] (the camera's frame), its albedo at hit points
    (``albedo(points [N,3], front [N] bool) -> [N,3]``) and its specular strength."""

    vertices: np.ndarray
    faces: np.ndarray
    albedo: Callable[[np.ndarray, np.ndarray], np.ndarray]
    specular: float = 0.08


def cloth(look: Appearance, to_pattern: Callable[[np.ndarray], np.ndarray] | None = None):
    """The albedo of a cloth in ``look``'s colours and print (its inside darker); ``to_pattern`` maps
    hit points to where the print is evaluated (default: the points themselves)."""
    def albedo(points: np.ndarray, front: np.ndarray) -> np.ndarray:
        where = points if to_pattern is None else to_pattern(points)
        return cloth_albedo(where, look) * np.where(front, 1.0, INSIDE)[:, None]
    return albedo


def skin(colour) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    return lambda points, front: np.broadcast_to(np.asarray(colour, np.float64), (len(points), 3))


def render_scene(camera, meshes: list[SceneMesh], back: np.ndarray, light, noise: float,
                 rng: np.random.Generator) -> tuple[np.ndarray, list[np.ndarray]]:
    """(picture [H,W,3] uint8, mask [H,W] bool of each mesh) of ``meshes`` seen by ``camera`` in
    front of ``back`` [H,W,3] (values in [0, 1]), lit from ``light`` (unit direction towards it),
    with Gaussian pixel noise of standard deviation ``noise``."""
    hits = cast(camera, [(m.vertices, m.faces) for m in meshes], SAMPLES)
    colour = np.zeros((len(hits.which), 3))
    view = camera.centre - hits.point
    view /= np.maximum(np.linalg.norm(view, axis=1, keepdims=True), 1e-12)
    light = np.asarray(light, np.float64)
    for index, mesh in enumerate(meshes):
        mine = hits.which == index
        if not mine.any():
            continue
        normals = surface_normals(np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces), hits.face[mine],
                                  hits.point[mine])
        colour[mine] = shade(normals, view[mine], mesh.albedo(hits.point[mine], hits.front[mine]), light,
                             specular=mesh.specular)
    h, w, s2 = camera.height, camera.width, SAMPLES * SAMPLES
    which = hits.which.reshape(h, w, s2)
    samples = np.where((which >= 0)[..., None], colour.reshape(h, w, s2, 3), back.reshape(h, w, 1, 3))
    image = samples.mean(2) + rng.normal(0.0, noise, (h, w, 3))
    masks = [(which == index).sum(2) * 2 >= s2 for index in range(len(meshes))]
    return (np.clip(image, 0, 1) * 255 + 0.5).astype(np.uint8), masks


def render(garment: tuple[np.ndarray, np.ndarray], body: tuple[np.ndarray, np.ndarray], look: Appearance,
           rng: np.random.Generator, unseen: bool) -> Picture:
    """Draw ``garment`` and ``body`` ((vertices [V,3], faces [F,3]), canonical frame) as ``look`` says."""
    camera = look.camera
    meshes = [SceneMesh(*body, skin(look.skin), specular=0.04), SceneMesh(*garment, cloth(look))]
    back = background(look, rng, camera.width, unseen)
    image, (body_mask, garment_mask) = render_scene(camera, meshes, back, look.light, look.noise, rng)
    return Picture(image, garment_mask, body_mask)
