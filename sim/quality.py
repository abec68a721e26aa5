"""What a user checks a simulated garment by, per frame: edge strain and how far a waistband slid.

Strain is measured on the solver's particles and edges (the DART's edges after welded seams are
merged and very short edges collapsed, ``sim.engine.model.cloth_model``): per edge s = max(l / l0 - 1, 0),
stretch only (a compressed edge is a fold, not a defect). The waist slide of a skirt or pants is the
height of its waist loop's centroid above the pelvis joint (world Z up, metres), compared with its
height at the first recorded frame (the settled place): a positive slide is the waist below where it
settled.
"""
from __future__ import annotations

import numpy as np

from darts.dart.model import Dart
from sim.engine.model import ClothModel

#: The feature line whose slide is measured, for garments held up at the waist.
WAIST_LINE = "waist"


def edge_strain(model: ClothModel, particles: np.ndarray) -> np.ndarray:
    """Stretch of every model edge, max(l / l0 - 1, 0), for particle positions [P,3]."""
    e = model.edges
    length = np.linalg.norm(particles[e[:, 0]] - particles[e[:, 1]], axis=1)
    return np.maximum(length / model.edge_rest - 1.0, 0.0)


def strain_summary(strain: np.ndarray) -> dict[str, float]:
    """Mean, 99th percentile and max of one frame's edge strains (fractions)."""
    return {"mean": float(strain.mean()), "p99": float(np.percentile(strain, 99)), "max": float(strain.max())}


def waist_height(dart: Dart, vertices: np.ndarray, pelvis: np.ndarray) -> float | None:
    """Height (m) of the waist loop's centroid above the pelvis joint, or None for a garment
    without a waist line."""
    loop = dart.lines.get(WAIST_LINE)
    if loop is None or pelvis is None:
        return None
    return float(vertices[loop, 2].mean() - pelvis[2])
