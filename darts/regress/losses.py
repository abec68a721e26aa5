"""The losses of the feature-line regressor (paper, Eq. 1) and the Chamfer distance it is judged by.

Lines are [B,L,K,3] in metres; a mask [B,L] marks real lines (the rest is padding). Losses are
computed in centimetres, so their values read in cm^2 (Chamfer, edges) or are pure numbers.

- ``chamfer``: per line, the mean over predicted points of the squared distance to the nearest
  ground-truth point plus the mean over ground-truth points of the squared distance to the nearest
  predicted point, halved (both directions averaged; squared, as Pixel2Mesh's).
- ``chamfer_distance``: the same with unsquared distances (the number reported, in cm).
- ``edge_loss`` (L_ed, Pixel2Mesh's edge regulariser): the mean squared length of a loop's edges.
- ``circularity`` (L_circ, which the paper leaves undefined; ours): a line must stay one closed,
  evenly spaced loop. With e_k = p_{k+1} - p_k (indices mod K, so the loop is closed by
  construction) and ebar the mean edge length,
      L_circ = mean_k (|e_k| / ebar - 1)^2 + mean_k relu(cos 45 deg - e_k . e_{k+1} / (|e_k| |e_{k+1}|))^2,
  uniform spacing plus a bound on how sharply the loop turns at a point (no point doubling back,
  no zig-zag). It is zero on every evenly spaced closed loop turning less than 45 degrees per
  point (a circle of 8 or more points, any smooth loop resampled densely) and positive otherwise.
"""
from __future__ import annotations

import math

import torch

CM = 100.0
MAX_TURN_COS = math.cos(math.radians(45.0))


def _masked_mean(values: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    mask = mask.to(values.dtype)
    return (values * mask).sum() / mask.sum().clamp_min(1.0)


def nearest(a: torch.Tensor, b: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Squared distances (cm^2) from every point of a [B,L,K,3] to its nearest in b [B,L,M,3], and
    from every point of b to its nearest in a: ([B,L,K], [B,L,M])."""
    d = torch.cdist(a * CM, b * CM, compute_mode="donot_use_mm_for_euclid_dist").square()
    return d.min(3).values, d.min(2).values


def chamfer_per_line(pred: torch.Tensor, gt: torch.Tensor, squared: bool = True) -> torch.Tensor:
    """[B,L]: half the sum of the two directions' mean (squared, cm^2, or unsquared, cm) nearest distances."""
    forward, backward = nearest(pred, gt)
    if not squared:
        forward, backward = forward.clamp_min(1e-12).sqrt(), backward.clamp_min(1e-12).sqrt()
    return 0.5 * (forward.mean(2) + backward.mean(2))


def chamfer(pred: torch.Tensor, gt: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """L_c: squared Chamfer (cm^2) averaged over the real lines."""
    return _masked_mean(chamfer_per_line(pred, gt), mask)


def edge_loss(points: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """L_ed: mean squared edge length (cm^2) of the loops."""
    edges = (torch.roll(points, -1, 2) - points) * CM
    return _masked_mean(edges.square().sum(-1).mean(2), mask)


def circularity(points: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """L_circ (module docstring), averaged over the real lines."""
    edges = torch.roll(points, -1, 2) - points
    length = edges.norm(dim=-1).clamp_min(1e-9)
    spacing = (length / length.mean(2, keepdim=True) - 1).square().mean(2)
    unit = edges / length[..., None]
    turn = torch.relu(MAX_TURN_COS - (unit * torch.roll(unit, -1, 2)).sum(-1)).square().mean(2)
    return _masked_mean(spacing + turn, mask)
