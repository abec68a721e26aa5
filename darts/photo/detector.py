"""Where the people in a photograph are: BlazePose's person detector (``models/pose_detection.tflite``)
and the square, rotated region each person's landmarks are read in.

The detector sees the picture letterboxed into 224 x 224 pixels (aspect kept, zero padding), values
in [-1, 1], and scores 2,254 SSD anchors (strides 8, 16, 32, 32, 32; two anchors a cell per layer,
unit size). Each anchor's regression is a box (x, y, w, h) and four keypoints, in pixels of the
224-pixel input relative to the anchor's centre: keypoint 0 is the middle of the hips, keypoint 1
a point whose distance from it is half the size of the whole body and whose direction is the
body's "up". Scores are logits (clipped to +-100). Overlapping detections (IoU > 0.3) are merged by
their scores (weighted non-maximum suppression). All coordinates here are image pixels (x right,
y down) of the original picture.

The landmark region of a detection is a square centred on keypoint 0, of side 2.5 x the distance
to keypoint 1, turned so that keypoint 1 is straight up in it (MediaPipe's pose_detection_to_roi).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import expit

INPUT = 224
STRIDES = (8, 16, 32, 32, 32)
MIN_SCORE = 0.5
NMS_IOU = 0.3
ROI_SCALE = 1.25  # of the 2 x (keypoint 0 - keypoint 1) box


@dataclass
class Region:
    """A square region of the picture: centre (x, y) pixels, side pixels, rotation radians (> 0:
    the region's "up" is turned clockwise on the picture)."""

    centre: np.ndarray
    side: float
    rotation: float

    def to_picture(self, points: np.ndarray) -> np.ndarray:
        """Picture pixels of points [N,2] given in the region's unit square ((0, 0) top left, (1, 1)
        bottom right)."""
        c, s = np.cos(self.rotation), np.sin(self.rotation)
        offset = (np.asarray(points, np.float64) - 0.5) * self.side
        return self.centre + offset @ np.array([[c, s], [-s, c]])

    def affine(self, size: int) -> tuple[float, ...]:
        """PIL's AFFINE data mapping a pixel of a ``size`` x ``size`` crop of the region to the picture."""
        c, s = np.cos(self.rotation), np.sin(self.rotation)
        k = self.side / size
        # picture = centre + R ((u + 0.5) k - side / 2, (v + 0.5) k - side / 2), R = [[c, -s], [s, c]]
        ox = self.centre[0] + (0.5 * k - self.side / 2) * (c - s)
        oy = self.centre[1] + (0.5 * k - self.side / 2) * (s + c)
        return (k * c, -k * s, ox - 0.5, k * s, k * c, oy - 0.5)


@dataclass
class Detection:
    score: float  # probability, 0..1
    box: np.ndarray  # [4] x_min, y_min, x_max, y_max, picture pixels
    keypoints: np.ndarray  # [4,2] picture pixels

    def region(self) -> Region:
        """The region the landmark model reads (module docstring)."""
        hips, top = self.keypoints[0], self.keypoints[1]
        rotation = np.pi / 2 - np.arctan2(-(top[1] - hips[1]), top[0] - hips[0])
        rotation = (rotation + np.pi) % (2 * np.pi) - np.pi
        return Region(hips.copy(), 2.0 * float(np.linalg.norm(top - hips)) * ROI_SCALE, float(rotation))


def anchors() -> np.ndarray:
    """SSD anchor centres [2254,2] in the unit square, in the model's output order."""
    centres = []
    layer = 0
    while layer < len(STRIDES):
        same = layer
        while same < len(STRIDES) and STRIDES[same] == STRIDES[layer]:
            same += 1
        per_cell = 2 * (same - layer)
        cells = int(np.ceil(INPUT / STRIDES[layer]))
        y, x = np.meshgrid((np.arange(cells) + 0.5) / cells, (np.arange(cells) + 0.5) / cells, indexing="ij")
        grid = np.stack([x.ravel(), y.ravel()], 1)
        centres.append(np.repeat(grid, per_cell, axis=0))
        layer = same
    return np.concatenate(centres)


def letterbox(width: int, height: int) -> tuple[float, float, float]:
    """(scale, x offset, y offset): picture pixel p sits at p * scale + offset in the 224-pixel input."""
    scale = INPUT / max(width, height)
    return scale, (INPUT - width * scale) / 2.0, (INPUT - height * scale) / 2.0


def _iou(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    low = np.maximum(box[:2], boxes[:, :2])
    high = np.minimum(box[2:], boxes[:, 2:])
    overlap = np.prod(np.clip(high - low, 0, None), axis=1)
    area = lambda b: np.prod(np.clip(b[..., 2:] - b[..., :2], 0, None), axis=-1)  # noqa: E731
    return overlap / np.maximum(area(box) + area(boxes) - overlap, 1e-12)


def decode(regression: np.ndarray, logits: np.ndarray, width: int, height: int,
           min_score: float = MIN_SCORE) -> list[Detection]:
    """Detections from the model's outputs ([2254,12], [2254]) on a ``width`` x ``height`` picture
    scoring at least ``min_score``, best first, after weighted non-maximum suppression."""
    score = expit(np.clip(logits, -100.0, 100.0))
    keep = score >= min_score
    if not keep.any():
        return []
    centre = anchors()[keep]
    raw = regression[keep] / INPUT
    score = score[keep]
    box_centre = centre + raw[:, :2]
    half = raw[:, 2:4] / 2.0
    boxes = np.concatenate([box_centre - half, box_centre + half], 1)
    points = centre[:, None, :] + raw[:, 4:12].reshape(-1, 4, 2)
    scale, dx, dy = letterbox(width, height)
    to_picture = lambda p: (p * INPUT - [dx, dy]) / scale  # noqa: E731
    boxes = np.concatenate([to_picture(boxes[:, :2]), to_picture(boxes[:, 2:])], 1)
    points = to_picture(points)
    found, remaining = [], np.argsort(-score)
    while len(remaining):
        best = remaining[0]
        overlap = _iou(boxes[best], boxes[remaining])
        group = remaining[overlap > NMS_IOU]
        weights = score[group] / score[group].sum()
        found.append(Detection(float(score[best]), weights @ boxes[group], np.einsum("g,gkd->kd", weights, points[group])))
        remaining = remaining[overlap <= NMS_IOU]
    return found
