"""Edge and boundary queries on triangle meshes given as (vertices, faces) arrays."""
from __future__ import annotations

import numpy as np


def directed_edges(faces: np.ndarray) -> np.ndarray:
    """[3F, 2] half-edges (a -> b) in face order: edges 01, 12, 20 of every face."""
    return np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])


def unique_edges(faces: np.ndarray) -> np.ndarray:
    """[E, 2] every edge once, its ends in increasing order, the edges sorted."""
    return np.unique(np.sort(directed_edges(faces), axis=1), axis=0)


def half_edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Face-major half-edges: h = 3f + k runs from faces[f, k] to faces[f, (k + 1) % 3].
    Returns (start vertex [3F], end vertex [3F], key of the undirected edge [3F])."""
    start, end = faces.reshape(-1), np.roll(faces, -1, axis=1).reshape(-1)
    key = np.minimum(start, end).astype(np.int64) * (int(faces.max()) + 1) + np.maximum(start, end)
    return start, end, key


def interior_edge_halves(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two half-edges (h1, h2) of every edge shared by two faces, given the keys of half_edges."""
    order = np.argsort(key, kind="stable")
    same = np.where(key[order][1:] == key[order][:-1])[0]
    return order[same], order[same + 1]


def boundary_edges(faces: np.ndarray) -> np.ndarray:
    """Half-edges with no opposite half-edge: the mesh boundary, oriented with the faces."""
    half = directed_edges(faces)
    keys = {(int(a), int(b)) for a, b in half}
    return np.array([(a, b) for a, b in half if (int(b), int(a)) not in keys], np.int64).reshape(-1, 2)


def boundary_loops(faces: np.ndarray) -> list[np.ndarray]:
    """Ordered vertex loops of the boundary. Raises ValueError if the boundary is not a set of
    simple closed loops (a vertex with more than one outgoing boundary edge)."""
    edges = boundary_edges(faces)
    nxt: dict[int, int] = {}
    for a, b in edges:
        if int(a) in nxt:
            raise ValueError(f"boundary vertex {a} has two outgoing boundary edges")
        nxt[int(a)] = int(b)
    loops, seen = [], set()
    for start in nxt:
        if start in seen:
            continue
        loop, v = [], start
        while v not in seen:
            seen.add(v)
            loop.append(v)
            v = nxt[v]
        if v != start:
            raise ValueError("boundary is not a set of closed loops")
        loops.append(np.array(loop, np.int64))
    return loops


def edge_manifold(faces: np.ndarray) -> bool:
    """True when every undirected edge has one or two faces and half-edges are consistent."""
    half = directed_edges(faces)
    _, counts = np.unique(half, axis=0, return_counts=True)
    undirected = np.sort(half, axis=1)
    _, ucounts = np.unique(undirected, axis=0, return_counts=True)
    return bool((counts == 1).all() and (ucounts <= 2).all())


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """[F,3] (b - a) x (c - a) of each face (a, b, c): its normal, twice its area long."""
    a = vertices[faces[:, 0]]
    return np.cross(vertices[faces[:, 1]] - a, vertices[faces[:, 2]] - a)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals."""
    face_n = face_normals(vertices, faces)
    normals = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(normals, faces[:, k], face_n)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def smoothed_vertex_normals(vertices: np.ndarray, faces: np.ndarray, rings: int) -> np.ndarray:
    """Unit vertex normals averaged ``rings`` times over each vertex and its edge neighbours
    (n <- (n_i + sum_j n_j) / (1 + deg i), then normalised): across a hollow narrower than about
    ``rings`` edges they point out of it, where the raw normals point at each other."""
    edges = unique_edges(faces)
    degree = np.bincount(edges.reshape(-1), minlength=len(vertices))[:, None]
    normals = vertex_normals(vertices, faces)
    for _ in range(rings):
        total = normals.copy()
        np.add.at(total, edges[:, 0], normals[edges[:, 1]])
        np.add.at(total, edges[:, 1], normals[edges[:, 0]])
        normals = total / (1.0 + degree)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def loop_length(vertices: np.ndarray, loop: np.ndarray) -> float:
    """Length of a closed polyline."""
    pts = vertices[loop]
    return float(np.linalg.norm(pts - np.roll(pts, -1, axis=0), axis=1).sum())
