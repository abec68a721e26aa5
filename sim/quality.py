"""What a user checks a simulated garment by, per frame: edge strain and how far a waistband slid.

Strain is measured on the solver's particles and edges (the DART's edges after welded seams are
merged and very short edges collapsed, ``sim.engine.model.cloth_model``): per edge s = max(l / l0 - 1, 0),
stretch only (a compressed edge is a fold, not a defect).

The waist slide of a skirt or pants (``WaistSlide``) is measured against the skin the waistband
settled on, not against a joint: at the first recorded frame each waist-line vertex is tied to its
closest point on the body (a body triangle and barycentric weights), which then moves with the skin.
Each frame, with a = the centroid of those skin points, w = the centroid of the waist line and n the
unit normal of the plane best fitting the skin points (the axis of the ring round the body; oriented
to world up at the first frame, then kept continuous), the slide is

    slide = (a - w) . n  -  (the same at the first recorded frame)      (metres)

positive where the waistband lies further down the body than it settled. (The height above the
pelvis joint, measured before, also counted the skin's own motion: in the squat the skin at the waist
drops 3.4 cm against the pelvis joint as the pelvis tilts, 1.4 cm sitting, 0.1 cm walking.)
"""
from __future__ import annotations

import numpy as np

from darts.dart.model import Dart
from sim.engine.model import WAIST_LINE, ClothModel


def edge_strain(model: ClothModel, particles: np.ndarray) -> np.ndarray:
    """Stretch of every model edge, max(l / l0 - 1, 0), for particle positions [P,3]."""
    e = model.edges
    length = np.linalg.norm(particles[e[:, 0]] - particles[e[:, 1]], axis=1)
    return np.maximum(length / model.edge_rest - 1.0, 0.0)


def strain_summary(strain: np.ndarray) -> dict[str, float]:
    """Mean, 99th percentile and max of one frame's edge strains (fractions)."""
    return {"mean": float(strain.mean()), "p99": float(np.percentile(strain, 99)), "max": float(strain.max())}


class WaistSlide:
    """The slide of the waist line ``loop`` [L] (vertex indices) of a garment whose vertices are
    ``vertices`` [V,3] on a body ``body_vertices`` [B,3] / ``body_faces`` [F,3] at its settled frame
    (module docstring; world frame, metres)."""

    def __init__(self, loop: np.ndarray, vertices: np.ndarray, body_vertices: np.ndarray, body_faces: np.ndarray):
        from darts.geometry.distance import SurfaceDistance

        self.loop = np.asarray(loop, np.int64)
        face, self.weights = SurfaceDistance(body_vertices, body_faces).closest_faces(vertices[self.loop])
        self.corners = np.asarray(body_faces)[face]
        self.axis = np.array([0.0, 0.0, 1.0])
        self.settled = 0.0
        self.settled = self(vertices, body_vertices)

    def __call__(self, vertices: np.ndarray, body_vertices: np.ndarray) -> float:
        """The slide (m) with the garment at ``vertices`` on the body at ``body_vertices``."""
        skin = np.einsum("lc,lcd->ld", self.weights, body_vertices[self.corners])
        centre = skin.mean(0)
        normal = np.linalg.svd(skin - centre)[2][2]
        self.axis = normal if normal @ self.axis >= 0 else -normal
        return float((centre - vertices[self.loop].mean(0)) @ self.axis) - self.settled


def waist_slide(dart: Dart, vertices: np.ndarray, body_vertices: np.ndarray, body_faces: np.ndarray) -> WaistSlide | None:
    """The ``WaistSlide`` of ``dart`` settled at ``vertices`` [V,3], or None without a waist line."""
    loop = dart.lines.get(WAIST_LINE)
    return None if loop is None else WaistSlide(loop, vertices, body_vertices, body_faces)
