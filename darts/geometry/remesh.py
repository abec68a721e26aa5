"""Isotropic remeshing (Botsch & Kobbelt 2004, via gpytoolbox) that keeps boundaries and seams."""
from __future__ import annotations

import numpy as np

from darts.geometry.mesh import boundary_edges, edge_manifold


def remesh(vertices: np.ndarray, faces: np.ndarray, edge_length: float, feature_edges: np.ndarray | None = None,
           iterations: int = 10, fixed: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Remesh to edges of about ``edge_length`` metres, projected onto the input surface. Boundary
    edges (and ``feature_edges`` [E,2]) are resampled along themselves: the outline is kept; the
    ``fixed`` vertices [K] stay where they are (a crease kept exactly)."""
    import gpytoolbox

    if not edge_manifold(faces):  # the remesher aborts the process on such input
        raise RuntimeError("remesh: the input mesh is not edge-manifold and consistently oriented")
    features = boundary_edges(faces)
    if feature_edges is not None and len(feature_edges):
        features = np.concatenate([features, feature_edges])
    v, f = gpytoolbox.remesh_botsch(np.ascontiguousarray(vertices, np.float64), np.ascontiguousarray(faces, np.int32),
                                    i=iterations, h=float(edge_length), project=True,
                                    feature=np.ascontiguousarray(np.zeros(0) if fixed is None else fixed, np.int64),
                                    feature_edges=np.ascontiguousarray(features, np.int32))
    return np.asarray(v, np.float64), np.asarray(f, np.int64)
