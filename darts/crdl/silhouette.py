"""The silhouette term of the CRDL: the garment's soft silhouette seen by a pinhole camera against a
garment mask (a SoftRas-style differentiable rasteriser, Liu et al. 2019, written in torch).

Camera (``camera.json``): ``width``, ``height`` (pixels), ``fx``, ``fy``, ``cx``, ``cy`` (pixels),
``rotation`` [3,3] and ``translation`` [3] taking canonical-frame points (Y up, metres) to camera
coordinates x_c = R x + t (OpenCV: x right, y down, looking along +z). Pixel (u, v) of a point is
(fx x_c / z_c + cx, fy y_c / z_c + cy); row v of the mask image is image row v.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np
import torch

from darts.errors import DartsInputError

SIGMA = 1.0  # pixels: the width of a triangle's soft edge


@dataclass
class Camera:
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    rotation: np.ndarray
    translation: np.ndarray

    @classmethod
    def from_json(cls, path: str | os.PathLike) -> "Camera":
        """Read and check ``camera.json`` (see the module docstring)."""
        try:
            data = json.loads(open(path).read())
        except FileNotFoundError:
            raise DartsInputError(path, "no such file") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise DartsInputError(path, f"not a JSON camera ({exc})") from None
        keys = ("width", "height", "fx", "fy", "cx", "cy", "rotation", "translation")
        missing = [key for key in keys if not isinstance(data, dict) or key not in data]
        if missing:
            raise DartsInputError(path, f"missing key(s) {', '.join(missing)}")
        try:
            rotation = np.asarray(data["rotation"], np.float64)
            translation = np.asarray(data["translation"], np.float64)
            numbers = [float(data[key]) for key in keys[:6]]
        except (TypeError, ValueError):
            raise DartsInputError(path, "camera values must be numbers") from None
        if rotation.shape != (3, 3) or translation.shape != (3,):
            raise DartsInputError(path, f"rotation must be [3,3] and translation [3], got {rotation.shape} and {translation.shape}")
        if not (np.isfinite(rotation).all() and np.isfinite(translation).all() and np.isfinite(numbers).all()):
            raise DartsInputError(path, "camera values must be finite")
        if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-4) or np.linalg.det(rotation) < 0:
            raise DartsInputError(path, "rotation is not a rotation matrix")
        width, height, fx, fy, cx, cy = numbers
        if width < 1 or height < 1 or width != int(width) or height != int(height) or fx <= 0 or fy <= 0:
            raise DartsInputError(path, "width and height must be positive integers and fx, fy > 0")
        return cls(int(width), int(height), fx, fy, cx, cy, rotation, translation)

    def project(self, points: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(pixel coordinates [N,2], depth [N]) of canonical-frame points [N,3]."""
        camera = points @ torch.as_tensor(self.rotation, dtype=points.dtype).T + torch.as_tensor(self.translation, dtype=points.dtype)
        depth = camera[:, 2]
        safe = torch.where(depth > 1e-6, depth, torch.ones_like(depth))
        u = self.fx * camera[:, 0] / safe + self.cx
        v = self.fy * camera[:, 1] / safe + self.cy
        return torch.stack([u, v], 1), depth


def read_mask(path: str | os.PathLike, camera: Camera) -> np.ndarray:
    """A garment mask image as bool [height, width] (garment where the grey level is above half)."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            grey = np.asarray(image.convert("L"), np.float64) / 255.0
    except FileNotFoundError:
        raise DartsInputError(path, "no such file") from None
    except (UnidentifiedImageError, OSError) as exc:
        raise DartsInputError(path, f"not an image ({exc})") from None
    if grey.shape != (camera.height, camera.width):
        raise DartsInputError(path, f"the mask is {grey.shape[1]}x{grey.shape[0]} pixels but the camera is "
                                    f"{camera.width}x{camera.height}")
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


class Silhouette:
    """L_sil(p) = 1 - soft IoU of the garment's soft silhouette (faces [F,3]) with the mask."""

    def __init__(self, mask: np.ndarray, camera: Camera, faces: np.ndarray | None = None):
        self.mask = torch.as_tensor(mask, dtype=torch.float64)
        self.camera = camera
        self.faces = faces

    @classmethod
    def from_files(cls, mask_path, camera_path) -> "Silhouette":
        camera = Camera.from_json(camera_path)
        return cls(read_mask(mask_path, camera), camera)

    def bind(self, faces: np.ndarray) -> "Silhouette":
        """The same term for the mesh with ``faces`` (the welded garment's)."""
        return Silhouette(self.mask.numpy(), self.camera, np.asarray(faces, np.int64))

    def render(self, vertices: torch.Tensor) -> torch.Tensor:
        pixels, depth = self.camera.project(vertices)
        return soft_silhouette(pixels, depth, self.faces, self.camera.width, self.camera.height)

    def loss(self, vertices: torch.Tensor) -> torch.Tensor:
        image = self.render(vertices)
        overlap = (image * self.mask).sum()
        return 1 - overlap / (image.sum() + self.mask.sum() - overlap).clamp_min(1e-9)

    def value_and_gradient(self, vertices: torch.Tensor) -> tuple[float, torch.Tensor]:
        """L_sil and dL_sil/dp [V,3] at ``vertices`` (for the local-global solver's proximal step)."""
        with torch.enable_grad():
            p = vertices.detach().clone().requires_grad_(True)
            loss = self.loss(p)
            (grad,) = torch.autograd.grad(loss, p)
        return float(loss.detach()), grad
