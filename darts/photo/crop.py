"""A square region of a picture: found around a mask, resampled to a network's input size and drawn
back (PIL's affine transform, bilinear), and the camera that sees it.

A crop (x, y, side) resampled to S x S pixels maps a picture pixel (u, v) to ((u - x) S / side,
(v - y) S / side).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Crop:
    """A square region of the picture: top-left corner (x, y) and side, pixels."""

    x: float
    y: float
    side: float

    @classmethod
    def around(cls, mask: np.ndarray, margin: float) -> Crop | None:
        """The square around the pixels of ``mask`` [H,W] bool: their box widened by ``margin`` of its
        longer side on each side, centred on it; None for an empty mask."""
        rows, cols = np.nonzero(mask)
        if len(rows) == 0:
            return None
        x0, x1, y0, y1 = cols.min(), cols.max() + 1, rows.min(), rows.max() + 1
        side = max(x1 - x0, y1 - y0) * (1 + 2 * margin)
        return cls((x0 + x1) / 2 - side / 2, (y0 + y1) / 2 - side / 2, float(side))

    def resample(self, picture: np.ndarray, size: int, fill=None) -> np.ndarray:
        """The region of ``picture`` at ``size`` x ``size`` pixels: uint8 [H,W] or [H,W,3] stays
        uint8, float [H,W] stays float32; ``fill`` off the picture (PIL's default, 0, if None)."""
        from PIL import Image

        k = self.side / size
        data = (k, 0.0, self.x, 0.0, k, self.y)
        array = np.asarray(picture)
        image = (Image.fromarray(np.asarray(array, np.float32), mode="F") if array.dtype.kind == "f"
                 else Image.fromarray(np.asarray(array, np.uint8)))
        return np.asarray(image.transform((size, size), Image.AFFINE, data, Image.BILINEAR, fillcolor=fill))

    def to_picture(self, values: np.ndarray, width: int, height: int) -> np.ndarray:
        """A square float map [S,S] of the crop drawn back onto the picture [height,width] (0 outside)."""
        from PIL import Image

        k = len(values) / self.side
        data = (k, 0.0, -self.x * k, 0.0, k, -self.y * k)
        back = Image.fromarray(np.asarray(values, np.float32), mode="F").transform((width, height), Image.AFFINE, data,
                                                                                   Image.BILINEAR, fillcolor=0.0)
        return np.asarray(back, np.float32)

    def camera(self, camera, size: int):
        """The ``darts.camera.Camera`` of the crop resampled to ``size`` pixels (module docstring)."""
        from darts.camera import Camera

        scale = size / self.side
        return Camera(size, size, camera.fx * scale, camera.fy * scale, (camera.cx - self.x) * scale,
                      (camera.cy - self.y) * scale, np.asarray(camera.rotation), np.asarray(camera.translation))
