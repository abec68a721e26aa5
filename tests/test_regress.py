"""The reconstruction networks: shapes, the identity at the start, gradients through every block,
a tiny network overfitting four samples, and the losses (Chamfer, circularity)."""
from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from darts.camera import Camera
from darts.regress.classifier import GarmentClassifier
from darts.regress.data import camera_batch
from darts.regress.encoder import ResNetEncoder
from darts.regress.lines import VARIANTS, FeatureLineRegressor, pool_features
from darts.regress.losses import chamfer, chamfer_per_line, circularity, edge_loss
from darts.regress.train import regression_loss

SIZE = 64


def _tiny_encoder() -> ResNetEncoder:
    return ResNetEncoder(widths=(8, 8, 16, 16), blocks=(1, 1, 1, 1))


def _circle(count: int, radius: float, centre=(0.0, 0.0, 0.0), phase: float = 0.0) -> np.ndarray:
    angle = phase + 2 * np.pi * np.arange(count) / count
    return np.stack([radius * np.cos(angle), radius * np.sin(angle), np.zeros(count)], 1) + centre


def _batch(count: int = 4, lines: int = 2, points: int = 16, seed: int = 0):
    """Pictures with a bright disc where each sample's target loops are, the cameras that see them,
    initial loops (circles at the origin) and targets (circles moved by up to 10 cm)."""
    rng = np.random.default_rng(seed)
    cameras = [Camera.look_at([0, 0, 2.0], [0, 0, 0], SIZE, SIZE, 60.0) for _ in range(count)]
    initial = np.stack([np.stack([_circle(points, 0.2, (0, 0.25 * k, 0)) for k in range(lines)])] * count)
    shift = rng.uniform(-0.1, 0.1, (count, lines, 1, 3)) * [1, 1, 0]
    truth = initial + shift
    images = np.zeros((count, 3, SIZE, SIZE), np.float32)
    v, u = np.mgrid[0:SIZE, 0:SIZE] + 0.5
    for b in range(count):
        for k in range(lines):
            (cu, cv), = cameras[b].project(truth[b, k].mean(0, keepdims=True))[0]
            images[b, k % 3] += np.exp(-((u - cu) ** 2 + (v - cv) ** 2) / 30.0)
    return (torch.tensor(images).clamp(0, 1), camera_batch(cameras), torch.tensor(initial, dtype=torch.float32),
            torch.tensor(truth, dtype=torch.float32), torch.ones(count, lines, dtype=torch.bool),
            torch.tensor([[5, 6]] * count))


def test_encoder_returns_four_maps_at_strides_4_to_32():
    maps = ResNetEncoder()(torch.rand(2, 3, 224, 224))
    assert [tuple(m.shape) for m in maps] == [(2, 16, 56, 56), (2, 32, 28, 28), (2, 64, 14, 14), (2, 128, 7, 7)]
    assert 0.6e6 < sum(p.numel() for p in ResNetEncoder().parameters()) < 0.8e6
    assert GarmentClassifier(encoder=_tiny_encoder())(torch.rand(3, 3, SIZE, SIZE)).shape == (3, 10)


def test_pooling_reads_the_map_at_the_projected_pixel():
    ramp = torch.arange(SIZE, dtype=torch.float32).repeat(SIZE, 1)[None, None]  # value = column index
    pixels = torch.tensor([[[10.5, 3.5], [40.5, 60.5], [0.5, 0.5]]])
    assert torch.allclose(pool_features([ramp], pixels, SIZE, SIZE)[0, :, 0], torch.tensor([10.0, 40.0, 0.0]), atol=1e-5)


@pytest.mark.parametrize("variant", VARIANTS)
def test_shapes_identity_start_and_gradients_through_every_block(variant):
    torch.manual_seed(0)
    images, cameras, initial, truth, mask, creases = _batch()
    model = FeatureLineRegressor(variant, blocks=2, hidden=32, layers=3, encoder=_tiny_encoder())
    outputs = model(images, cameras, initial, creases)
    assert len(outputs) == 2 + (variant != "p2m-gcn") and all(o.shape == initial.shape for o in outputs)
    if variant == "ours":  # every translation head starts at zero: the lines come out unchanged
        assert all(torch.equal(o, initial) for o in outputs)
    regression_loss(outputs, truth, mask).backward()
    if model.image_stm:  # at the identity only the zero heads see a gradient; one step later all do
        assert float(model.global_head.weight.grad.abs().sum()) > 0
        if variant == "ours":
            assert all(float(b.head.weight.grad.abs().sum()) > 0 for b in model.blocks)
        torch.optim.SGD(model.parameters(), lr=0.01).step()
        model.zero_grad()
        regression_loss(model(images, cameras, initial, creases), truth, mask).backward()
    parts = {"encoder": model.encoder, **{f"block {k}": b for k, b in enumerate(model.blocks)}}
    if model.image_stm:
        parts["image-guided STM"] = model.global_mlp
    for name, part in parts.items():
        grads = [p.grad for p in part.parameters() if p.requires_grad]
        assert grads and all(g is not None for g in grads) and sum(float(g.abs().sum()) for g in grads) > 0, name


@pytest.mark.slow
def test_a_tiny_regressor_overfits_four_samples():
    torch.manual_seed(0)
    images, cameras, initial, truth, mask, creases = _batch()
    model = FeatureLineRegressor("ours", blocks=2, hidden=32, layers=3, encoder=_tiny_encoder())
    optimizer = torch.optim.Adam(model.parameters(), lr=3e-3)
    with torch.no_grad():
        first = float(chamfer(model(images, cameras, initial, creases)[-1], truth, mask))
    for _ in range(150):
        loss = regression_loss(model(images, cameras, initial, creases), truth, mask)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
    with torch.no_grad():
        last = float(chamfer(model(images, cameras, initial, creases)[-1], truth, mask))
    assert last < first / 20, (first, last)  # squared Chamfer, cm^2: falls by more than 20x


def test_chamfer_is_zero_on_itself_and_the_distance_to_a_shifted_loop():
    loop = torch.tensor(_circle(64, 0.3), dtype=torch.float32)[None, None]
    mask = torch.ones(1, 1, dtype=torch.bool)
    assert float(chamfer(loop, loop, mask)) < 1e-6
    moved = loop + torch.tensor([0.0, 0.0, 0.02])  # 2 cm along the loop's normal
    assert float(chamfer_per_line(moved, loop, squared=False)) == pytest.approx(2.0, rel=1e-3)
    assert float(chamfer(moved, loop, mask)) == pytest.approx(4.0, rel=1e-3)  # squared, cm^2


def test_circularity_is_zero_on_an_evenly_spaced_loop_and_positive_otherwise():
    mask = torch.ones(1, 1, dtype=torch.bool)
    as_tensor = lambda a: torch.tensor(a, dtype=torch.float32)[None, None]  # noqa: E731
    assert float(circularity(as_tensor(_circle(64, 0.3)), mask)) < 1e-8
    assert float(circularity(as_tensor(_circle(8, 0.3) * [1, 0.5, 1]), mask)) > 1e-3  # an ellipse: uneven spacing
    uneven = _circle(64, 0.3)[np.r_[0:32:2, 32:64]]  # half the loop sampled half as densely
    assert float(circularity(as_tensor(uneven), mask)) > 0.05
    zigzag = _circle(64, 0.3) * (1 + 0.2 * (np.arange(64) % 2))[:, None]
    assert float(circularity(as_tensor(zigzag), mask)) > 0.05
    folded = _circle(64, 0.3)
    folded[[10, 11]] = folded[[11, 10]]  # two points swapped: the loop doubles back
    assert float(circularity(as_tensor(folded), mask)) > 0.01
    padding = torch.zeros(1, 1, dtype=torch.bool)  # masked lines do not count
    assert float(circularity(as_tensor(zigzag), padding)) == 0.0
    chord = 100 * 2 * 0.3 * math.sin(math.pi / 64)
    assert float(edge_loss(as_tensor(_circle(64, 0.3)), mask)) == pytest.approx(chord**2, rel=1e-3)
