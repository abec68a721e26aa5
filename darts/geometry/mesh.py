"""Edge and boundary queries on triangle meshes given as (vertices, faces) arrays."""
from __future__ import annotations

import numpy as np


def directed_edges(faces: np.ndarray) -> np.ndarray:
    """[3F, 2] half-edges (a -> b) in face order: edges 01, 12, 20 of every face."""
    return np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])


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


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals."""
    face_n = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]])
    normals = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(normals, faces[:, k], face_n)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def loop_length(vertices: np.ndarray, loop: np.ndarray) -> float:
    """Length of a closed polyline."""
    pts = vertices[loop]
    return float(np.linalg.norm(pts - np.roll(pts, -1, axis=0), axis=1).sum())
