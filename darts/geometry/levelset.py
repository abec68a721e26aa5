"""Inserting the zero level set of a per-vertex scalar field into a triangle mesh.

The field is linear on each triangle, so its zero set is a polyline crossing triangles. Vertices
close to it (within ``snap`` of an edge's length) are moved onto it along that edge; the remaining
crossing edges are split at the zero, and crossed triangles are re-triangulated. Afterwards the
zero set runs exactly along mesh edges, so a garment can be cut or seamed along it.
"""
from __future__ import annotations

import numpy as np


def _edge_keys(a: np.ndarray, b: np.ndarray, count: int) -> np.ndarray:
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    return lo.astype(np.int64) * count + hi


def insert_level_set(vertices: np.ndarray, faces: np.ndarray, values: np.ndarray, snap: float = 0.25,
                     locked: np.ndarray | None = None):
    """Return (vertices, faces, values) where every sign change of ``values`` lies on mesh edges.

    New vertices get value 0; snapped vertices are moved and set to 0. Vertices flagged in
    ``locked`` (on an earlier cut or the boundary) are never moved. Face orientation is kept.
    """
    vertices, values = vertices.astype(np.float64).copy(), values.astype(np.float64).copy()
    count = len(vertices)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    a, b = edges[:, 0], edges[:, 1]
    crossing = values[a] * values[b] < 0
    # Snap: move the nearer end of a crossing edge onto the zero when it is close; a vertex near
    # several crossings goes to the closest one.
    ca, cb = a[crossing], b[crossing]
    t = values[ca] / (values[ca] - values[cb])
    points = vertices[ca] + t[:, None] * (vertices[cb] - vertices[ca])
    near_a, near_b = t < snap, t > 1 - snap
    if locked is not None:
        near_a &= ~locked[ca]
        near_b &= ~locked[cb]
    movers = np.concatenate([ca[near_a], cb[near_b]])
    targets = np.concatenate([points[near_a], points[near_b]])
    order = np.argsort(np.concatenate([t[near_a], 1 - t[near_b]]), kind="stable")
    moved, first = np.unique(movers[order], return_index=True)
    vertices[moved] = targets[order][first]
    values[moved] = 0.0
    crossing = values[a] * values[b] < 0
    keys = _edge_keys(a[crossing], b[crossing], count)
    unique_keys, first = np.unique(keys, return_index=True)
    ea, eb = a[crossing][first], b[crossing][first]
    t = values[ea] / (values[ea] - values[eb])
    new_vertices = vertices[ea] + t[:, None] * (vertices[eb] - vertices[ea])
    new_index = count + np.arange(len(unique_keys))

    def mid(u, w):
        return new_index[np.searchsorted(unique_keys, _edge_keys(u, w, count))]

    sign = np.sign(values)[faces]
    out = []
    crosses = np.stack([sign[:, 0] * sign[:, 1] < 0, sign[:, 1] * sign[:, 2] < 0, sign[:, 2] * sign[:, 0] < 0], 1)
    n_cross = crosses.sum(1)
    out.append(faces[n_cross == 0])
    # Two crossed edges: rotate so the lone vertex o is first -> (o, m_oa, m_ob), (m_oa, a, b), (m_oa, b, m_ob).
    two = np.where(n_cross == 2)[0]
    lone = np.where(~crosses[two, 1], 0, np.where(~crosses[two, 2], 1, 2))  # vertex opposite the uncrossed edge
    rot = np.stack([faces[two, lone], faces[two, (lone + 1) % 3], faces[two, (lone + 2) % 3]], 1)
    o, p, q = rot.T
    m_op, m_oq = mid(o, p), mid(o, q)
    out += [np.stack([o, m_op, m_oq], 1), np.stack([m_op, p, q], 1), np.stack([m_op, q, m_oq], 1)]
    # One crossed edge (the third vertex is on the zero): split through that vertex.
    one = np.where(n_cross == 1)[0]
    edge_at = np.argmax(crosses[one], axis=1)
    rot = np.stack([faces[one, (edge_at + 2) % 3], faces[one, edge_at], faces[one, (edge_at + 1) % 3]], 1)
    z, p, q = rot.T
    m = mid(p, q)
    out += [np.stack([z, p, m], 1), np.stack([z, m, q], 1)]
    return (np.concatenate([vertices, new_vertices]), np.concatenate(out).astype(np.int64),
            np.concatenate([values, np.zeros(len(new_vertices))]))


def keep_side(vertices: np.ndarray, faces: np.ndarray, values: np.ndarray):
    """Cut along the zero set and keep the part where ``values <= 0``; unused vertices removed.
    Returns (vertices, faces, index of each kept vertex in the cut mesh)."""
    vertices, faces, values = insert_level_set(vertices, faces, values)
    keep = faces[(values[faces] <= 0).all(1) & (values[faces] < 0).any(1)]
    return compact(vertices, keep)


def compact(vertices: np.ndarray, faces: np.ndarray):
    """Drop unreferenced vertices. Returns (vertices, faces, old index of each kept vertex)."""
    used = np.unique(faces)
    remap = np.full(len(vertices), -1, np.int64)
    remap[used] = np.arange(len(used))
    return vertices[used], remap[faces], used
