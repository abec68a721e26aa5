"""The surface the CRDL keeps the garment outside of (paper, Eq. 3 and Fig. 3).

It is the body in its canonical rest shape; for skirts and dresses also the remeshed convex hull of
the lower body that the DART carries, so that a skirt is pushed out of the space between the legs
and not into it. A point's signed distance is the smaller of the two (inside either is inside).
Points and normals are [N,3] in the canonical frame (Y up), metres.
"""
from __future__ import annotations

import numpy as np
import torch

from darts.geometry.distance import SurfaceDistance


class FitSurface:
    """Signed distance, closest point and outward normal to the body (union its lower-body hull)."""

    def __init__(self, body_vertices: np.ndarray, body_faces: np.ndarray,
                 hull: tuple[np.ndarray, np.ndarray] | None = None):
        self.body = SurfaceDistance(body_vertices, body_faces)
        self.hull = None if hull is None else SurfaceDistance(*hull)

    def query(self, points: np.ndarray, winding: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(signed distance [N], closest point [N,3], outward unit normal [N,3]); see
        ``SurfaceDistance.query`` for ``winding``."""
        signed, closest, normal = self.body.query(points, winding=winding)
        if self.hull is not None:
            hull_signed, hull_closest, hull_normal = self.hull.query(points, winding=winding)
            use = hull_signed < signed
            signed = np.where(use, hull_signed, signed)
            closest = np.where(use[:, None], hull_closest, closest)
            normal = np.where(use[:, None], hull_normal, normal)
        return signed, closest, normal

    def push_out(self, points: np.ndarray, clearance: float, passes: int = 3) -> np.ndarray:
        """``points`` [N,3] with those closer than ``clearance`` (or inside) moved to ``clearance``
        outside along the normal at their closest point (a few passes: a move can land near another part)."""
        points = np.array(points, np.float64)
        for _ in range(passes):
            signed, closest, normal = self.query(points)
            close = signed < clearance
            if not close.any():
                break
            points[close] = closest[close] + clearance * normal[close]
        return points

    def inside_fraction(self, points: np.ndarray) -> float:
        """Fraction of ``points`` inside the body itself (the hull is a guide, not an obstacle)."""
        return float((self.body.query(points)[0] < 0).mean())


def fit_deficit(points: torch.Tensor, closest: torch.Tensor, normal: torch.Tensor, margin: float) -> torch.Tensor:
    """max(0, margin - (p - q) . n) [N]: how far each point must move out along n to be ``margin``
    outside (q, n from ``FitSurface.query``, held fixed; Eq. 3's signed distance, linearised)."""
    return torch.relu(margin - row_dot(points - closest, normal))


def row_dot(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """a_i . b_i [N] for [N,3] rows, as a product with ones (torch's sum over an axis of 3 takes
    seven times as long)."""
    return (a * b) @ torch.ones(a.shape[1], dtype=a.dtype)
