"""The silhouette term of the CRDL: the garment's soft silhouette seen by a pinhole camera against a
garment mask (a SoftRas-style differentiable rasteriser, Liu et al. 2019, written in torch).

The camera is ``darts.camera.Camera`` (``camera.json``); row v of the mask image is image row v.
"""
from __future__ import annotations

import os

import numpy as np
import torch

from darts.camera import Camera
from darts.crdl.term import SilhouetteTerm
from darts.errors import DartsInputError

SIGMA = 1.0  # pixels: the width of a triangle's soft edge


def read_mask(path: str | os.PathLike, width: int, height: int, of: str = "the camera") -> np.ndarray:
    """A garment mask image as bool [height, width] (garment where the grey level is above half);
    a DartsInputError when it is not ``width`` x ``height`` (the size of ``of``) or empty."""
    from darts.fileio import read_image

    grey = read_image(path, "L").astype(np.float64) / 255.0
    if grey.shape != (height, width):
        raise DartsInputError(path, f"the mask is {grey.shape[1]}x{grey.shape[0]} pixels but {of} is {width}x{height}")
    mask = grey > 0.5
    if not mask.any():
        raise DartsInputError(path, "the mask is empty (no pixel above half grey)")
    return mask


def _pixel_pairs(triangles: np.ndarray, width: int, height: int, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """(face [P], pixel [P]) for every pixel whose centre lies within ``reach`` of a face's box."""
    lo = np.clip(np.floor(triangles.min(1) - reach), 0, [width - 1, height - 1]).astype(np.int64)
    hi = np.clip(np.ceil(triangles.max(1) + reach), 0, [width - 1, height - 1]).astype(np.int64)
    span = hi - lo + 1
    count = span[:, 0] * span[:, 1]
    face = np.repeat(np.arange(len(triangles)), count)
    offset = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    x = lo[face, 0] + offset % span[face, 0]
    y = lo[face, 1] + offset // span[face, 0]
    return face, y * width + x


def _segment_distance(point: torch.Tensor, a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Distance [P] from points [P,2] to segments a-b [P,2]."""
    ab = b - a
    t = ((point - a) * ab).sum(1) / (ab * ab).sum(1).clamp_min(1e-12)
    return (point - a - t.clamp(0, 1)[:, None] * ab).norm(dim=1)


def soft_silhouette(pixels: torch.Tensor, depth: torch.Tensor, faces: np.ndarray, width: int, height: int,
                    sigma: float = SIGMA) -> torch.Tensor:
    """Coverage [height, width] in [0, 1]: 1 - prod_f (1 - sigmoid(d_f(x) / sigma)), d_f the signed
    distance (pixels, > 0 inside) from the pixel centre x to projected face f (faces in front only)."""
    front = faces[(depth.detach().numpy()[faces] > 1e-6).all(1)]
    triangles = pixels[torch.as_tensor(front)]  # [F,3,2]
    face, pixel = _pixel_pairs(triangles.detach().numpy(), width, height, 3 * sigma)
    centre = torch.stack([torch.as_tensor(pixel % width), torch.as_tensor(pixel // width)], 1).to(pixels.dtype) + 0.5
    a, b, c = triangles[face, 0], triangles[face, 1], triangles[face, 2]
    edge = torch.stack([_segment_distance(centre, a, b), _segment_distance(centre, b, c), _segment_distance(centre, c, a)], 1)
    area = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0]

    def side(p, q):
        return ((q - p)[:, 0] * (centre - p)[:, 1] - (q - p)[:, 1] * (centre - p)[:, 0]) * torch.sign(area)

    inside = (side(a, b) >= 0) & (side(b, c) >= 0) & (side(c, a) >= 0)
    signed = torch.where(inside, 1.0, -1.0).to(pixels.dtype) * edge.min(1).values
    probability = torch.sigmoid(signed / sigma).clamp(max=1 - 1e-6)
    missed = torch.zeros(width * height, dtype=pixels.dtype).index_add(0, torch.as_tensor(pixel), torch.log1p(-probability))
    return (1 - torch.exp(missed)).reshape(height, width)


class Silhouette(SilhouetteTerm):
    """L_sil(p) = 1 - soft IoU of the garment's soft silhouette (faces [F,3]) with the mask."""

    def __init__(self, mask: np.ndarray, camera: Camera, faces: np.ndarray | None = None):
        self.mask = torch.as_tensor(mask, dtype=torch.float64)
        self.camera = camera
        self.faces = faces

    @classmethod
    def from_files(cls, mask_path, camera_path) -> Silhouette:
        camera = Camera.from_json(camera_path)
        return cls(read_mask(mask_path, camera.width, camera.height), camera)

    def bind(self, vertices: np.ndarray, faces: np.ndarray) -> Silhouette:
        """The same term for the mesh with ``faces`` (the welded garment's)."""
        return Silhouette(self.mask.numpy(), self.camera, np.asarray(faces, np.int64))

    def render(self, vertices: torch.Tensor) -> torch.Tensor:
        pixels, depth = self.camera.project(vertices)
        return soft_silhouette(pixels, depth, self.faces, self.camera.width, self.camera.height)

    def loss(self, vertices: torch.Tensor) -> torch.Tensor:
        image = self.render(vertices)
        overlap = (image * self.mask).sum()
        return 1 - overlap / (image.sum() + self.mask.sum() - overlap).clamp_min(1e-9)


def silhouette_term(name: str, mask: np.ndarray, camera: Camera):
    """The silhouette term ``name`` (``darts.crdl.SILHOUETTE_WEIGHTS``) of a garment ``mask`` [H,W]
    bool seen by ``camera``."""
    from darts.crdl import check_silhouette

    check_silhouette(name)
    if name == "outline":
        from darts.crdl.outline import Outline

        return Outline(mask, camera)
    return Silhouette(mask, camera)

