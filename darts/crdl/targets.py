"""Target feature lines for the CRDL: procedural edits of a template's own lines, or loops read from
a ``lines.npz``, and their arc-length correspondence with the template's line vertices.

All points are in the template's frame (the body's canonical frame, Y up), metres. A target loop
has no vertex correspondence with the template: template line vertex k, at arc-length fraction s_k
of its loop, is matched to the point at fraction s_k (+ the best shift, in the best direction) of
the target loop.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from darts.errors import DartsInputError
from darts.geometry.loops import closest_on_loop
from darts.templates.categories import CATEGORIES

if TYPE_CHECKING:
    import torch

#: Edit name -> (what it changes, the lines it applies to). "length" moves a line along its loop's
#: axis, away from the garment (lengthens for > 0); "width" moves every point away from the loop's
#: centre in the loop's plane (widens for > 0).
EDITS = {
    "hem": ("length", ("hem", "left_hem", "right_hem")),
    "sleeve": ("length", ("left_cuff", "right_cuff")),
    "neckline": ("width", ("neckline",)),
    "waist": ("width", ("waist",)),
    "hem_width": ("width", ("hem", "left_hem", "right_hem")),
    "cuff_width": ("width", ("left_cuff", "right_cuff")),
}
MAX_EDIT = 0.5  # metres


def parse_edit(text: str) -> tuple[str, float]:
    """'NAME=+0.10' -> ('NAME', 0.10), NAME one of EDITS."""
    name, sep, value = text.partition("=")
    name = name.strip()
    if not sep or name not in EDITS:
        raise DartsInputError(None, f"--edit expects NAME=METRES with NAME one of {', '.join(EDITS)}, got '{text}'")
    try:
        amount = float(value)
    except ValueError:
        raise DartsInputError(None, f"--edit {text}: '{value}' is not a number of metres") from None
    if not np.isfinite(amount) or abs(amount) > MAX_EDIT:
        raise DartsInputError(None, f"--edit {text}: the amount must be finite and at most {MAX_EDIT} m in size")
    return name, amount


def loop_frame(points: np.ndarray, garment_centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(centre [3], unit axis [3]) of a closed loop: its mean, and the normal of its best-fit plane
    (least principal direction) pointing away from the garment's centre."""
    centre = points.mean(0)
    axis = np.linalg.svd(points - centre, full_matrices=False)[2][2]
    return centre, axis if np.dot(axis, centre - garment_centre) >= 0 else -axis


def loop_directions(points: np.ndarray, garment_centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(unit axis [3], unit radial directions [K,3]) of a closed loop: its axis (``loop_frame``) and
    each point's direction away from its centre within its plane."""
    centre, axis = loop_frame(points, garment_centre)
    radial = points - centre
    radial -= np.outer(radial @ axis, axis)
    return axis, radial / np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-9)


def edited_loop(points: np.ndarray, kind: str, amount: float, garment_centre: np.ndarray) -> np.ndarray:
    """The loop moved ``amount`` along its axis ("length") or away from its centre in its plane ("width")."""
    axis, radial = loop_directions(points, garment_centre)
    return points + amount * (axis if kind == "length" else radial)


def length_and_width_edited(points: np.ndarray, length: float, width: float, garment_centre: np.ndarray) -> np.ndarray:
    """The loop edited as ``edit_targets`` edits a hem or a cuff: a "length", then a "width" (metres)."""
    return edited_loop(edited_loop(points, "length", length, garment_centre), "width", width, garment_centre)


def fit_loop_edit(points: np.ndarray, target: np.ndarray, garment_centre: np.ndarray,
                  rounds: int = 30) -> tuple[float, float]:
    """(length, width), metres: the edit of the template loop ``points`` [K,3]
    (``length_and_width_edited``) that best takes it onto the closed polyline ``target`` [M,3] — the
    edit an opening of an edited garment came from. The edited loop is x_k + a n + b r_k (n the
    loop's axis, r_k the unit radial direction of x_k in its plane), linear in (a, b): alternately
    each edited point's closest point c_k on the target and the least-squares (a, b) of
    sum_k |x_k + a n + b r_k - c_k|^2 (an ICP with two unknowns, ``rounds`` times)."""
    points = np.asarray(points, np.float64)
    axis, radial = loop_directions(points, garment_centre)
    design = np.stack([np.broadcast_to(axis, radial.shape), radial], -1).reshape(-1, 2)
    length = width = 0.0
    for _ in range(rounds):
        closest = closest_on_loop(points + length * axis + width * radial, target)
        (length, width), *_ = np.linalg.lstsq(design, (closest - points).reshape(-1), rcond=None)
    return float(length), float(width)


def edit_targets(category: str, vertices: np.ndarray, lines: dict[str, np.ndarray],
                 edits: list[tuple[str, float]]) -> dict[str, np.ndarray]:
    """Target loops [K,3] for every line of the template (``vertices`` [V,3], ``lines`` vertex loops),
    edits applied in order; lines no edit names stay where they are."""
    targets = {name: vertices[loop].astype(np.float64) for name, loop in lines.items()}
    centre = vertices.mean(0)
    for name, amount in edits:
        kind, names = EDITS[name]
        hit = [n for n in names if n in targets]
        if not hit:
            raise DartsInputError(None, f"--edit {name}: a {category} has no {' or '.join(names)} line "
                                        f"(its lines: {', '.join(lines)})")
        if name == "sleeve" and not CATEGORIES[category].sleeved:
            raise DartsInputError(None, f"--edit sleeve: a {category} has no sleeves")
        for n in hit:
            targets[n] = edited_loop(targets[n], kind, amount, centre)
    return targets


def read_target_lines(path: str | os.PathLike, category: str, line_names: list[str]) -> dict[str, np.ndarray]:
    """Target loops from ``lines.npz``: one [K,3] array (K >= 3, metres, canonical frame) per line
    name, each a line of ``category``."""
    from darts.fileio import read_npz

    return target_lines(read_npz(path), category, line_names, path)


def target_lines(arrays: dict, category: str, line_names: list[str], source=None) -> dict[str, np.ndarray]:
    """``arrays`` (line name -> [K,3] points, K >= 3, metres, canonical frame) checked as target
    loops of ``category`` (float64); a DartsInputError naming ``source`` otherwise."""
    if not arrays:
        raise DartsInputError(source, "holds no lines")
    targets = {}
    for name, value in arrays.items():
        if name not in line_names:
            raise DartsInputError(source, f"line '{name}' is not a line of a {category} (its lines: {', '.join(line_names)})")
        points = np.asarray(value)
        if points.ndim != 2 or points.shape[1] != 3 or len(points) < 3:
            raise DartsInputError(source, f"line '{name}' must be [K,3] points with K >= 3, got shape {points.shape}")
        if not np.issubdtype(points.dtype, np.number) or not np.isfinite(points).all():
            raise DartsInputError(source, f"line '{name}' has non-finite or non-numeric values")
        targets[name] = points.astype(np.float64)
    return targets


def arc_fractions(points: np.ndarray) -> np.ndarray:
    """Arc-length fraction [K] in [0, 1) of each vertex of a closed loop, from its first vertex."""
    steps = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)[:-1]]) / max(steps.sum(), 1e-12)


def _sample_indices(target_fractions: np.ndarray, at: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For fractions ``at``: the target segment (k, k+1 mod M) containing each and the weight of k+1."""
    at = np.mod(at, 1.0)
    k = np.clip(np.searchsorted(target_fractions, at, side="right") - 1, 0, len(target_fractions) - 1)
    ends = np.append(target_fractions[1:], 1.0)
    t = (at - target_fractions[k]) / np.maximum(ends[k] - target_fractions[k], 1e-12)
    return k, (k + 1) % len(target_fractions), np.clip(t, 0.0, 1.0)


@dataclass
class Correspondence:
    """Template line vertex k <- (1 - t_k) target[first_k] + t_k target[second_k]."""

    first: np.ndarray
    second: np.ndarray
    weight: np.ndarray

    def points(self, target: torch.Tensor) -> torch.Tensor:
        """The matched target points [K,3] (differentiable in ``target`` [M,3])."""
        import torch

        t = torch.as_tensor(self.weight, dtype=target.dtype)[:, None]
        return (1 - t) * target[self.first] + t * target[self.second]


def correspond(template_points: np.ndarray, target: np.ndarray, shifts: int = 256) -> Correspondence:
    """Arc-length correspondence of a template loop [K,3] with a target loop [M,3]: both directions
    of the target and ``shifts`` start offsets are tried; the one closest in sum of squares wins."""
    fractions = arc_fractions(template_points)
    best, best_cost = None, np.inf
    for direction in (1, -1):
        order = np.arange(len(target))[::direction]
        ordered = target[order]
        target_fractions = arc_fractions(ordered)
        for shift in np.arange(shifts) / shifts:
            first, second, weight = _sample_indices(target_fractions, fractions + shift)
            matched = (1 - weight)[:, None] * ordered[first] + weight[:, None] * ordered[second]
            cost = np.square(matched - template_points).sum()
            if cost < best_cost:
                best, best_cost = Correspondence(order[first], order[second], weight), cost
    return best


def _around_centre(points: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The loop's points [K,2] in the plane of ``axes`` [2,3] about its centroid (the enclosed
    area's, by the shoelace formula: an unevenly sampled loop's vertex mean is off its centre) and
    their angles [K] (radians, in (-pi, pi]); None unless they turn once around, strictly one way
    (a loop star-shaped about it)."""
    flat = (points - points.mean(0)) @ axes.T
    following = np.roll(flat, -1, axis=0)
    cross = flat[:, 0] * following[:, 1] - following[:, 0] * flat[:, 1]
    if abs(cross.sum()) < 1e-12:
        return None
    flat = flat - ((flat + following) * cross[:, None]).sum(0) / (3.0 * cross.sum())
    angles = np.arctan2(flat[:, 1], flat[:, 0])
    steps = np.angle(np.exp(1j * (np.roll(angles, -1) - angles)))  # each step wrapped to (-pi, pi]
    if not (np.all(steps > 0) or np.all(steps < 0)) or abs(abs(steps.sum()) - 2 * np.pi) > 1e-6:
        return None
    return flat, angles


def correspond_around(template_points: np.ndarray, target: np.ndarray) -> Correspondence:
    """Correspondence of a template loop [K,3] with a target loop [M,3] by angle about each loop's
    centroid, in the template loop's plane (its two principal directions): template vertex k goes to
    the target's point at its own angle, between the two target vertices either side of it. An
    edit that scales a loop about its centre or moves it (a wider hem, a shorter sleeve) keeps every
    point's angle but not its share of the arc length: registered by arc length, a short skirt's
    side seams ended 7.7 mm along its hem from an edited original's, by angle 4.4 mm. Where either
    loop is not star-shaped about its centroid, arc length (``correspond``)."""
    axes = np.linalg.svd(template_points - template_points.mean(0), full_matrices=False)[2][:2]  # its plane
    template, target_around = _around_centre(template_points, axes), _around_centre(target, axes)
    if template is None or target_around is None:
        return correspond(template_points, target)
    (_, template_angles), (flat, target_angles) = template, target_around
    order = np.argsort(target_angles)  # star-shaped: by angle is along the loop
    start = target_angles[order[0]]
    first, second, _ = _sample_indices((target_angles[order] - start) / (2 * np.pi),
                                       (template_angles - start) / (2 * np.pi))
    first, second = order[first], order[second]
    # where the ray at each template angle crosses the target's segment: cross(d, a + w (b - a)) = 0
    ray = np.stack([np.cos(template_angles), np.sin(template_angles)], 1)
    at_first, at_second = (ray[:, 0] * flat[ends, 1] - ray[:, 1] * flat[ends, 0] for ends in (first, second))
    weight = np.clip(at_first / np.where(np.abs(at_first - at_second) > 1e-15, at_first - at_second, 1.0), 0.0, 1.0)
    return Correspondence(first, second, weight)
