"""The garment in a photograph: its mask and its category, from the picture cropped around the person.

Input: a square crop around the person (the box of its mask, ``darts.photo.person``, widened by
``MARGIN`` on each side) resized to ``SIZE`` x ``SIZE``: RGB in [0, 1] and the person's mask
probability, 4 channels. ``GarmentNet`` is a small U-Net (Ronneberger et al. 2015): four levels of
two 3 x 3 convolutions (batch norm, ReLU), w-2w-4w-8w channels (w = 12 shipped: 0.28 M parameters), max pooling down and bilinear
upsampling with skip connections up, a 1 x 1 convolution to the garment mask's logit per pixel;
and, from the average of the deepest features, a linear layer to the ten categories' logits.
Trained on the posed dataset (``scripts/train_garment_net.py``); the weights ship in
``weights/garment_net.pt`` with their record.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import torch
from torch import nn

from darts.photo.crop import Crop

SIZE = 96
MARGIN = 0.1
WEIGHTS = Path(__file__).parent / "weights" / "garment_net.pt"


def _block(inputs: int, outputs: int) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(inputs, outputs, 3, padding=1, bias=False), nn.BatchNorm2d(outputs), nn.ReLU(inplace=True),
                         nn.Conv2d(outputs, outputs, 3, padding=1, bias=False), nn.BatchNorm2d(outputs), nn.ReLU(inplace=True))


class GarmentNet(nn.Module):
    """(mask logits [B,1,S,S], category logits [B,categories]) of crops [B,4,S,S] (module docstring)."""

    def __init__(self, categories: int = 10, width: int = 16):
        super().__init__()
        channels = [width, 2 * width, 4 * width, 8 * width]
        self.down = nn.ModuleList([_block(4, channels[0])] + [_block(a, b) for a, b in zip(channels, channels[1:])])
        self.up = nn.ModuleList([_block(b + a, a) for a, b in zip(channels[:-1], channels[1:])])
        self.mask = nn.Conv2d(channels[0], 1, 1)
        self.category = nn.Linear(channels[-1], categories)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        skips = []
        for level, block in enumerate(self.down):
            x = block(x if level == 0 else nn.functional.max_pool2d(x, 2))
            skips.append(x)
        category = self.category(x.mean((2, 3)))
        for block, skip in zip(reversed(self.up), reversed(skips[:-1])):
            x = nn.functional.interpolate(x, size=skip.shape[-2:], mode="bilinear", align_corners=False)
            x = block(torch.cat([skip, x], 1))
        return self.mask(x), category


def network_input(crop: Crop, image: np.ndarray, person_mask: np.ndarray) -> torch.Tensor:
    """[4,SIZE,SIZE]: the ``crop`` of ``image`` [H,W,3] uint8 (RGB in [0, 1]) and of ``person_mask``
    [H,W] (0..1)."""
    rgb = crop.resample(np.asarray(image, np.uint8), SIZE)
    mask = crop.resample(np.asarray(person_mask, np.float32), SIZE)
    channels = np.concatenate([np.asarray(rgb, np.float32) / 255.0, np.asarray(mask, np.float32)[..., None]], 2)
    return torch.from_numpy(channels).permute(2, 0, 1).contiguous()


def person_crop(person_mask: np.ndarray) -> Crop | None:
    """The crop around the person's mask [H,W] (> 0.5), or None if it is empty."""
    return Crop.around(np.asarray(person_mask) > 0.5, MARGIN)


@lru_cache(maxsize=1)
def shipped_net() -> tuple[GarmentNet, dict]:
    """The shipped network (eval mode) and its record (``darts.checkpoint``, kind "garment")."""
    from darts.checkpoint import load_model
    from darts.errors import DartsInputError

    if not WEIGHTS.is_file():
        raise DartsInputError(WEIGHTS, "the shipped weights are missing (train them: scripts/train_garment_net.py)")
    return load_model(WEIGHTS, "garment", GarmentNet)


@torch.no_grad()
def segment_garment(image: np.ndarray, person_mask: np.ndarray) -> tuple[np.ndarray, list[tuple[str, float]]] | None:
    """(the garment's mask [H,W] bool, every category with its probability, most likely first) of the
    person whose mask is ``person_mask`` [H,W] in ``image`` [H,W,3] uint8; None without a person."""
    crop = person_crop(person_mask)
    if crop is None:
        return None
    net, record = shipped_net()
    mask_logits, category_logits = net(network_input(crop, image, person_mask)[None])
    probability = torch.sigmoid(mask_logits[0, 0]).numpy()
    mask = crop.to_picture(probability, image.shape[1], image.shape[0]) > 0.5
    categories = torch.softmax(category_logits[0], 0).numpy()
    order = np.argsort(-categories)
    return mask, [(record["categories"][i], float(categories[i])) for i in order]
