"""The CRDL's outline term: the garment's projection matched against the mask's distance field and
outline, at the cost of a bilinear lookup and a nearest-neighbour query per solver step, whatever
the picture's size (the soft rasteriser of ``darts.crdl.silhouette`` costs a pixel loop per face).

The term works at one resolution whatever the picture's: the mask resampled (bilinear, then
thresholded at half) and the camera's intrinsics scaled so that the mask's bounding box is
``WORKING_SIZE`` pixels on its long side. With u_v the pixel of vertex v through that camera
(``darts.camera.Camera.project``), D the distance
(pixels) from a pixel to the nearest mask pixel (0 inside; the mask's holes filled, where the body
is in front of the garment), b the points of the mask's outline (pixel centres, at most
``OUTLINE_POINTS`` of them, evenly spaced along the pixel list) and s = sqrt(mask area) the mask's
size in pixels:

    L(p) = ( mean_v rho(D(u_v)) + mean_b rho(min_v |u_v - b|) ) / s,   rho(d) = sqrt(d^2 + 1) - 1

The first half keeps the garment inside the mask, the second stretches it over the whole of it
(every outline point has a vertex near it). rho is the Charbonnier penalty (pixels: quadratic below
one pixel, linear above); 0.01 is a mean miss of about 1 % of the garment's size.
"""
from __future__ import annotations

import numpy as np
import torch

from darts.camera import Camera
from darts.crdl.term import SilhouetteTerm

#: outline points kept (evenly along the outline's pixel list)
OUTLINE_POINTS = 2000
#: pixels on the long side of the mask's bounding box where the term is evaluated (the dataset's
#: 224-pixel pictures show a garment 100-200 pixels tall)
WORKING_SIZE = 160


def _working(mask: np.ndarray, camera: Camera) -> tuple[np.ndarray, Camera]:
    """``mask`` [H,W] and ``camera`` at the working resolution (module docstring)."""
    from PIL import Image

    rows, cols = np.nonzero(mask)
    k = WORKING_SIZE / max(rows.max() - rows.min() + 1, cols.max() - cols.min() + 1)
    width, height = max(1, round(mask.shape[1] * k)), max(1, round(mask.shape[0] * k))
    grey = Image.fromarray(mask.astype(np.uint8) * 255).resize((width, height), Image.BILINEAR)
    return np.asarray(grey) > 127, camera.resized(width, height)


def _charbonnier(distance: torch.Tensor) -> torch.Tensor:
    return torch.sqrt(distance.square() + 1.0) - 1.0


class Outline(SilhouetteTerm):
    """L(p) of the module docstring for a garment ``mask`` [H,W] bool seen by ``camera``."""

    def __init__(self, mask: np.ndarray, camera: Camera):
        from scipy import ndimage

        self.mask, self.camera = _working(np.asarray(mask, bool), camera)
        filled = ndimage.binary_fill_holes(self.mask)
        self.size = float(np.sqrt(self.mask.sum()))
        self._distance = torch.as_tensor(ndimage.distance_transform_edt(~filled), dtype=torch.float64)[None, None]
        edge = filled & ~ndimage.binary_erosion(filled, border_value=0)
        rows, cols = np.nonzero(edge)
        keep = np.linspace(0, len(rows) - 1, min(len(rows), OUTLINE_POINTS)).round().astype(np.int64)
        self.outline = np.stack([cols[keep], rows[keep]], 1).astype(np.float64) + 0.5

    def bind(self, vertices: np.ndarray, faces: np.ndarray) -> Outline:
        """The same term: it reads the vertices only, not the mesh's ``faces``."""
        return self

    def _outside(self, pixels: torch.Tensor) -> torch.Tensor:
        """D(u) [N] (pixels), bilinear; beyond the picture, D at its border plus the way to it."""
        height, width = self.mask.shape
        limit = torch.tensor([width, height], dtype=pixels.dtype)
        inside = pixels.clamp(min=torch.zeros(2, dtype=pixels.dtype), max=limit)
        grid = (2 * inside / limit - 1)[None, None]
        sampled = torch.nn.functional.grid_sample(self._distance.to(pixels.dtype), grid, mode="bilinear",
                                                  padding_mode="border", align_corners=False)[0, 0, 0]
        return sampled + (pixels - inside).norm(dim=1)

    def loss(self, vertices: torch.Tensor) -> torch.Tensor:
        from scipy.spatial import cKDTree

        pixels, _ = self.camera.project(vertices)
        nearest = torch.as_tensor(cKDTree(pixels.detach().numpy()).query(self.outline)[1])
        cover = (pixels[nearest] - torch.as_tensor(self.outline, dtype=pixels.dtype)).norm(dim=1)
        return (_charbonnier(self._outside(pixels)).mean() + _charbonnier(cover).mean()) / self.size
