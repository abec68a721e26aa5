"""Dataset samples (``darts dataset make``, docs/dataset.md) as tensors for the networks, and the
initial feature lines F_g of every category.

A category's lines are in ``Category.line_names`` order (tops and dresses: neckline, left cuff,
right cuff, hem; pants: waist, left hem, right hem; skirts: waist, hem), padded to MAX_LINES with
a mask. F_g is the shipped DART of the category (the default body, its rest shape) with each line
resampled like the dataset's (``darts.geometry.loops.resample_loop``, LINE_POINTS points).
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import torch

from darts.camera import Camera
from darts.errors import DartsInputError
from darts.geometry.loops import LINE_POINTS
from darts.regress.lines import CREASE_OF_LINE, CREASES, MAX_LINES, CameraBatch
from darts.templates.categories import CATEGORIES

CATEGORY_IDS = list(CATEGORIES)


@cache
def initial_lines(category: str) -> np.ndarray:
    """F_g of ``category``: [L, LINE_POINTS, 3] (canonical frame, metres)."""
    from darts.dart.io import load_dart
    from darts.geometry.loops import resample_loop
    from darts.shipped import resolve_garment

    dart = load_dart(resolve_garment(category))
    vertices = np.asarray(dart.vertices, np.float64)
    centre = vertices.mean(0)
    return np.stack([resample_loop(vertices[np.asarray(dart.lines[name])], LINE_POINTS, centre)
                     for name in CATEGORIES[category].line_names])


def padded(category: str, lines: dict[str, np.ndarray] | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lines [MAX_LINES,K,3], mask [MAX_LINES], crease index [MAX_LINES]) of ``category`` from a
    {name: [K,3]} dict or an [L,K,3] array in line order."""
    names = CATEGORIES[category].line_names
    stacked = np.stack([lines[name] for name in names]) if isinstance(lines, dict) else np.asarray(lines)
    out = np.zeros((MAX_LINES,) + stacked.shape[1:], np.float32)
    out[: len(names)] = stacked
    mask = np.arange(MAX_LINES) < len(names)
    creases = np.array([CREASES.index(CREASE_OF_LINE[n]) for n in names] + [0] * (MAX_LINES - len(names)))
    return out, mask, creases


def camera_batch(cameras: list[Camera]) -> CameraBatch:
    """The cameras of one batch (all of one image size) as tensors."""
    return CameraBatch(torch.tensor(np.stack([c.rotation for c in cameras]), dtype=torch.float32),
                       torch.tensor(np.stack([c.translation for c in cameras]), dtype=torch.float32),
                       torch.tensor([[c.fx, c.fy] for c in cameras], dtype=torch.float32),
                       torch.tensor([[c.cx, c.cy] for c in cameras], dtype=torch.float32),
                       cameras[0].width, cameras[0].height)


@dataclass
class Samples:
    """Every sample of one split: ids [N], images uint8 [N,3,H,W], garment masks and foreground
    (garment or body) masks bool [N,H,W], category indices [N] (CATEGORY_IDS), cameras,
    ground-truth and initial lines [N,4,K,3], mask and crease indices [N,4]."""

    ids: list[str]
    folders: list[Path]
    images: torch.Tensor
    masks: torch.Tensor
    foreground: torch.Tensor
    categories: torch.Tensor
    cameras: CameraBatch
    lines: torch.Tensor
    initial: torch.Tensor
    line_mask: torch.Tensor
    creases: torch.Tensor

    def __len__(self) -> int:
        return len(self.ids)

    def index(self, rows) -> Samples:
        rows = torch.as_tensor(rows)
        pick = lambda t: t[rows]  # noqa: E731
        return Samples([self.ids[i] for i in rows.tolist()], [self.folders[i] for i in rows.tolist()], pick(self.images),
                       pick(self.masks), pick(self.foreground), pick(self.categories), self.cameras.index(rows), pick(self.lines),
                       pick(self.initial), pick(self.line_mask), pick(self.creases))


def load_split(root: str | Path, split: str, limit: int | None = None) -> Samples:
    """The samples of ``root/split`` (sorted by id; the first ``limit`` if given)."""
    from darts.fileio import read_image, read_npz

    folders = sorted(p for p in (Path(root) / split).glob("*") if (p / "image.png").is_file())[:limit]
    if not folders:
        raise DartsInputError(Path(root) / split, "holds no samples (make them with darts dataset make)")
    images, masks, foreground, categories, cameras, lines, initial, line_masks, creases = ([] for _ in range(9))
    for folder in folders:
        category = json.loads((folder / "meta.json").read_text())["category"]
        images.append(read_image(folder / "image.png").transpose(2, 0, 1))
        masks.append(read_image(folder / "mask.png", "L") > 127)
        foreground.append(masks[-1] | (read_image(folder / "body_mask.png", "L") > 127))
        categories.append(CATEGORY_IDS.index(category))
        cameras.append(Camera.from_json(folder / "camera.json"))
        truth, mask, crease = padded(category, read_npz(folder / "lines.npz"))
        lines.append(truth)
        initial.append(padded(category, initial_lines(category))[0])
        line_masks.append(mask)
        creases.append(crease)
    return Samples([f.name for f in folders], folders, torch.from_numpy(np.stack(images)), torch.from_numpy(np.stack(masks)),
                   torch.from_numpy(np.stack(foreground)), torch.tensor(categories), camera_batch(cameras),
                   torch.from_numpy(np.stack(lines)),
                   torch.from_numpy(np.stack(initial)), torch.from_numpy(np.stack(line_masks)), torch.tensor(np.stack(creases)))
