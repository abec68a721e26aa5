"""Splitting a template into panels along its seams, and the seam pairs that re-join them.

Every vertex on a seam is duplicated once per side of the seam (a vertex where several seams meet,
once per panel corner around it). A seam pair is the two copies of one template vertex across one
seam: at rest they coincide (gap 0). Open seams (a sleeve's underarm slit) work the same way.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from darts.geometry.mesh import half_edges, interior_edge_halves


@dataclass
class PanelSplit:
    """vertices [V',3], faces [F,3] (same faces, new indices), panel [F], seam pairs [S,2], the seam
    index and arc position (0..1 along the seam) of each pair, and the template vertex of each new one."""

    vertices: np.ndarray
    faces: np.ndarray
    panel: np.ndarray
    pairs: np.ndarray
    pair_seam: np.ndarray
    pair_position: np.ndarray
    source: np.ndarray

    def map_loop(self, template_faces: np.ndarray, loop: np.ndarray) -> np.ndarray:
        """A template boundary loop in new indices, through both copies where it crosses a seam."""
        return _map_loop(self.faces, template_faces, loop)


def _arc_positions(vertices: np.ndarray, edges: np.ndarray) -> dict[int, float]:
    """Normalised arc length of each vertex along a seam polyline (a path, or a loop starting at its
    lowest vertex); several pieces are laid end to end."""
    neighbours: dict[int, list[int]] = {}
    for a, b in edges:
        neighbours.setdefault(int(a), []).append(int(b))
        neighbours.setdefault(int(b), []).append(int(a))
    position, total, seen = {}, 0.0, set()
    while len(seen) < len(neighbours):
        rest = [v for v in neighbours if v not in seen]
        ends = [v for v in rest if len(neighbours[v]) == 1]
        v = min(ends or rest, key=lambda u: (vertices[u, 1], u))
        previous = None
        while v is not None and v not in seen:
            if previous is not None:
                total += float(np.linalg.norm(vertices[v] - vertices[previous]))
            position[v], previous = total, v
            seen.add(v)
            v = next((u for u in neighbours[v] if u not in seen), None)
    return {v: p / max(total, 1e-12) for v, p in position.items()}


def split_panels(vertices: np.ndarray, faces: np.ndarray, seam_edges: list[np.ndarray]) -> PanelSplit:
    """Cut the mesh along ``seam_edges`` (one [E,2] array per seam, template indices)."""
    _, _, key = half_edges(faces)
    half = np.arange(len(key))
    face, start, end = half // 3, half, 3 * (half // 3) + (half % 3 + 1) % 3  # corners of each half-edge
    size = faces.max() + 1
    seam_keys = [np.minimum(e[:, 0], e[:, 1]).astype(np.int64) * size + np.maximum(e[:, 0], e[:, 1]) for e in seam_edges]
    is_seam = np.isin(key, np.concatenate(seam_keys)) if seam_keys else np.zeros(len(key), bool)
    h1, h2 = interior_edge_halves(key)
    glue = ~is_seam[h1]
    h1, h2 = h1[glue], h2[glue]
    # Opposite half-edges run in opposite directions: start of one meets the end of the other.
    rows = np.concatenate([start[h1], end[h1]])
    cols = np.concatenate([end[h2], start[h2]])
    corners = 3 * len(faces)
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(corners, corners))
    _, corner_vertex = connected_components(graph, directed=False)
    new_faces = corner_vertex.reshape(-1, 3)
    source = np.zeros(corner_vertex.max() + 1, np.int64)
    source[corner_vertex] = faces.reshape(-1)
    face_graph = coo_matrix((np.ones(len(h1)), (face[h1], face[h2])), shape=(len(faces),) * 2)
    _, panel = connected_components(face_graph, directed=False)

    pairs, pair_seam, pair_position = [], [], []
    for index, keys in enumerate(seam_keys):
        halves = np.where(np.isin(key, keys))[0]
        positions = _arc_positions(vertices, seam_edges[index])
        found = {}
        h_sorted = halves[np.argsort(key[halves], kind="stable")]
        for first, second in zip(h_sorted[0::2], h_sorted[1::2]):
            if key[first] != key[second]:
                raise ValueError("a seam edge lies on the mesh boundary")
            for c1, c2 in ((start[first], end[second]), (end[first], start[second])):
                a, b = sorted((int(corner_vertex[c1]), int(corner_vertex[c2])))
                if a != b:
                    found[(a, b)] = positions[int(source[a])]
        for (a, b), p in sorted(found.items()):
            pairs.append((a, b))
            pair_seam.append(index)
            pair_position.append(p)
    return PanelSplit(vertices[source], new_faces, panel.astype(np.int64), np.array(pairs, np.int64).reshape(-1, 2),
                      np.array(pair_seam, np.int64), np.array(pair_position, np.float64), source)


def _map_loop(new_faces: np.ndarray, template_faces: np.ndarray, loop: np.ndarray) -> np.ndarray:
    lookup = {}
    for tri, new in zip(template_faces, new_faces):
        for k in range(3):
            lookup[(int(tri[k]), int(tri[(k + 1) % 3]))] = (int(new[k]), int(new[(k + 1) % 3]))
    out: list[int] = []
    for a, b in zip(loop, np.roll(loop, -1)):
        u, w = lookup[(int(a), int(b))]
        out += [u, w]
    mapped = [v for i, v in enumerate(out) if v != out[i - 1]]
    return np.array(mapped, np.int64)
