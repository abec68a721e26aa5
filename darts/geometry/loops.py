"""Closed polylines (feature lines): arc-length resampling to a fixed number of points, in a fixed
start and direction, so that every line of every garment is K points sampled the same way.

Start: the point of the loop farthest along +Z (the body's front, canonical frame). Direction: the
loop turns counter-clockwise about its axis, the normal of its best-fit plane pointing away from
the garment's centre (``darts.crdl.targets.loop_frame``), i.e. sum_k (p_k - c) x (p_k+1 - c) . axis > 0.
"""
from __future__ import annotations

import numpy as np

#: Points per feature line wherever lines are compared or learnt (dataset, networks).
LINE_POINTS = 64


def loop_axis(points: np.ndarray, away_from: np.ndarray) -> np.ndarray:
    """Unit normal [3] of the loop's best-fit plane, pointing away from ``away_from``."""
    centre = points.mean(0)
    axis = np.linalg.svd(points - centre, full_matrices=False)[2][2]
    return axis if np.dot(axis, centre - away_from) >= 0 else -axis


def oriented(points: np.ndarray, away_from: np.ndarray) -> np.ndarray:
    """The loop [K,3] reversed if needed to turn counter-clockwise about ``loop_axis``."""
    centre = points.mean(0)
    turning = np.cross(points - centre, np.roll(points, -1, 0) - centre).sum(0)
    return points if np.dot(turning, loop_axis(points, away_from)) >= 0 else points[::-1]


def resample_loop(points: np.ndarray, count: int, away_from: np.ndarray) -> np.ndarray:
    """``count`` points [count,3] evenly spaced by arc length along the closed loop ``points`` [K,3],
    oriented (``oriented``) and starting at its front-most point (largest z)."""
    points = oriented(np.asarray(points, np.float64), np.asarray(away_from, np.float64))
    start = int(np.argmax(points[:, 2]))
    points = np.roll(points, -start, axis=0)
    closed = np.vstack([points, points[:1]])
    steps = np.linalg.norm(np.diff(closed, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    at = np.arange(count) * arc[-1] / count
    k = np.clip(np.searchsorted(arc, at, side="right") - 1, 0, len(steps) - 1)
    t = ((at - arc[k]) / np.maximum(steps[k], 1e-12))[:, None]
    return (1 - t) * closed[k] + t * closed[k + 1]


def closest_on_loop(points: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """[N,3]: the point of the closed polyline ``loop`` [K,3] nearest each of ``points`` [N,3] (the
    nearest of each segment's clamped projections)."""
    a, ab = loop, np.roll(loop, -1, 0) - loop
    t = np.clip(((points[:, None] - a[None]) * ab[None]).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-18), 0, 1)
    projected = a[None] + t[..., None] * ab[None]
    nearest = np.linalg.norm(points[:, None] - projected, axis=-1).argmin(1)
    return projected[np.arange(len(points)), nearest]


def distance_to_loop(points: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """[N] distance of each of ``points`` [N,3] to the closed polyline ``loop`` [K,3]."""
    return np.linalg.norm(points - closest_on_loop(points, loop), axis=1)


def feature_lines(dart, vertices: np.ndarray) -> dict[str, np.ndarray]:
    """Each feature line of ``dart`` at ``vertices`` [V,3] (its own, draped or posed), resampled to
    LINE_POINTS points (``resample_loop``, oriented away from the vertices' centre)."""
    vertices = np.asarray(vertices, np.float64)
    centre = vertices.mean(0)
    return {name: resample_loop(vertices[np.asarray(loop)], LINE_POINTS, centre) for name, loop in dart.lines.items()}
