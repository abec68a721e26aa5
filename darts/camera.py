"""A pinhole camera and its ``camera.json`` (the CRDL's silhouette term, the dataset, reconstruction).

``width``, ``height`` (pixels), ``fx``, ``fy``, ``cx``, ``cy`` (pixels), ``rotation`` [3,3] and
``translation`` [3] take canonical-frame points (the body's rest frame: Y up, metres) to camera
coordinates x_c = R x + t (OpenCV: x right, y down, looking along +z). Pixel (u, v) of a point is
(fx x_c / z_c + cx, fy y_c / z_c + cy): u runs along image columns, v along rows, and the centre of
pixel (column i, row j) is (i + 0.5, j + 0.5).
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass, replace

import numpy as np

from darts.errors import DartsInputError

KEYS = ("width", "height", "fx", "fy", "cx", "cy", "rotation", "translation")
IMAGE_SIZE = 224  # pixels, square: the dataset's pictures and the networks' input
DISTANCE = 2.6  # metres from the framed region's centre
MARGIN = 1.15  # the framed extent fills 1 / MARGIN of the image's width
#: category -> (centre [3], extent m): the box each category's garments occupy on the body, the
#: full range over the 996 draped garments of the dataset of seed 0 (every body shape, edit and
#: drape; docs/dataset.md): the largest of its width and height. A picture's camera looks at the
#: centre and frames the extent.
FRAMES = {
    "long-sleeve-top": ((0.0, 0.06, 0.02), 1.66), "short-sleeve-top": ((0.0, 0.06, 0.02), 0.84),
    "sleeveless-top": ((0.0, 0.06, 0.02), 0.84), "long-sleeve-dress": ((0.0, -0.22, 0.02), 1.66),
    "short-sleeve-dress": ((0.0, -0.24, 0.02), 1.40), "sleeveless-dress": ((0.0, -0.24, 0.02), 1.40),
    "long-pants": ((0.0, -0.735, 0.01), 1.14), "short-pants": ((0.0, -0.38, 0.01), 0.54),
    "long-skirt": ((0.0, -0.68, 0.03), 1.00), "short-skirt": ((0.0, -0.415, 0.03), 0.62),
}


def focal_for(extent: float, size: int = IMAGE_SIZE, distance: float = DISTANCE) -> float:
    """Focal length (pixels) that fits ``extent`` metres at ``distance`` into 1 / MARGIN of ``size``."""
    return size * distance / (extent * MARGIN)


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
    def from_json(cls, path: str | os.PathLike) -> Camera:
        """Read and check ``camera.json`` (see the module docstring)."""
        from darts.fileio import read_input

        text = read_input(path, "camera file")
        try:
            data = json.loads(text.decode("utf-8"))
        except (ValueError, UnicodeDecodeError) as exc:
            raise DartsInputError(path, f"not a JSON camera ({exc})") from None
        return cls.from_dict(data, path)

    @classmethod
    def from_dict(cls, data, source=None) -> Camera:
        """A camera from its JSON object, checked (``source`` names it in errors)."""
        missing = [key for key in KEYS if not isinstance(data, dict) or key not in data]
        if missing:
            raise DartsInputError(source, f"missing key(s) {', '.join(missing)}")
        try:
            rotation = np.asarray(data["rotation"], np.float64)
            translation = np.asarray(data["translation"], np.float64)
            numbers = [float(data[key]) for key in KEYS[:6]]
        except (TypeError, ValueError):
            raise DartsInputError(source, "camera values must be numbers") from None
        if rotation.shape != (3, 3) or translation.shape != (3,):
            raise DartsInputError(source,
                                  f"rotation must be [3,3] and translation [3], got {rotation.shape} and {translation.shape}")
        if not (np.isfinite(rotation).all() and np.isfinite(translation).all() and np.isfinite(numbers).all()):
            raise DartsInputError(source, "camera values must be finite")
        if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-4) or np.linalg.det(rotation) < 0:
            raise DartsInputError(source, "rotation is not a rotation matrix")
        width, height, fx, fy, cx, cy = numbers
        if not (1 <= width <= 16384 and 1 <= height <= 16384) or width != int(width) or height != int(height) \
                or fx <= 0 or fy <= 0:
            raise DartsInputError(source, "width and height must be integers in [1, 16384] and fx, fy > 0")
        return cls(int(width), int(height), fx, fy, cx, cy, rotation, translation)

    @classmethod
    def look_at(cls, eye, target, width: int, height: int, focal: float, up=(0.0, 1.0, 0.0)) -> Camera:
        """A camera at ``eye`` looking at ``target`` (canonical frame) with ``up`` pointing up in the
        image, focal length ``focal`` pixels and the principal point at the image centre."""
        eye, target, up = (np.asarray(a, np.float64) for a in (eye, target, up))
        forward = target - eye
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, up)
        right /= np.linalg.norm(right)
        down = np.cross(forward, right)
        rotation = np.stack([right, down, forward])  # rows: camera x, y, z in canonical coordinates
        return cls(int(width), int(height), float(focal), float(focal), width / 2.0, height / 2.0, rotation, -rotation @ eye)

    def resized(self, width: int, height: int) -> Camera:
        """The same view at ``width`` x ``height`` pixels (intrinsics scaled per axis)."""
        sx, sy = width / self.width, height / self.height
        return replace(self, width=width, height=height, fx=self.fx * sx, fy=self.fy * sy, cx=self.cx * sx,
                       cy=self.cy * sy)

    def as_dict(self) -> dict:
        return {"width": self.width, "height": self.height, "fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy,
                "rotation": np.asarray(self.rotation).tolist(), "translation": np.asarray(self.translation).tolist(),
                "convention": "x_c = R x + t, x in the body's canonical frame (Y up, metres); OpenCV camera axes; "
                              "pixel (u, v) = (fx x_c/z_c + cx, fy y_c/z_c + cy), pixel centres at +0.5"}

    @classmethod
    def default(cls, category: str, size: int = IMAGE_SIZE) -> Camera:
        """The camera a picture of ``category`` is assumed to come from: level, from the front (+Z),
        DISTANCE from the category's frame centre, the frame filling 1 / MARGIN of the image."""
        centre, extent = FRAMES[category]
        centre = np.asarray(centre)
        return cls.look_at(centre + [0.0, 0.0, DISTANCE], centre, size, size, focal_for(extent, size))

    @property
    def centre(self) -> np.ndarray:
        """The camera's position in the canonical frame."""
        return -np.asarray(self.rotation).T @ np.asarray(self.translation)

    def project(self, points):
        """(pixel coordinates [N,2], depth [N]) of canonical-frame points [N,3], numpy or torch
        (differentiable); a point behind the camera gets the pixel of depth 1 and its true depth."""
        if isinstance(points, np.ndarray):
            camera = points @ np.asarray(self.rotation).T + self.translation
            depth = camera[:, 2]
            safe = np.where(depth > 1e-6, depth, 1.0)
            return np.stack([self.fx * camera[:, 0] / safe + self.cx, self.fy * camera[:, 1] / safe + self.cy], 1), depth
        import torch

        rotation = torch.as_tensor(self.rotation, dtype=points.dtype)
        camera = points @ rotation.T + torch.as_tensor(self.translation, dtype=points.dtype)
        depth = camera[:, 2]
        safe = torch.where(depth > 1e-6, depth, torch.ones_like(depth))
        return torch.stack([self.fx * camera[:, 0] / safe + self.cx, self.fy * camera[:, 1] / safe + self.cy], 1), depth

    def rays(self, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(origin [3], unit directions [N,3]) in the canonical frame of rays through image points
        ``pixels`` [N,2] (u, v)."""
        local = np.stack([(pixels[:, 0] - self.cx) / self.fx, (pixels[:, 1] - self.cy) / self.fy, np.ones(len(pixels))], 1)
        directions = local @ np.asarray(self.rotation)  # R^T applied to each row
        return self.centre, directions / np.linalg.norm(directions, axis=1, keepdims=True)
