"""The cloth model the solver steps, built from a DART (canonical frame, metres, kilograms).

- particles: DART vertices, with the two ends of every *welded* seam pair merged into one;
- mass: lumped areal density, m_i = density * sum of (area / 3) of the faces around particle i;
- stretch: one distance constraint per mesh edge, at its rest length;
- bending: one hinge (i, j shared edge; k, l opposite vertices) per interior edge, with its rest
  dihedral angle;
- seam springs: one per *active* pair of a stiff, loose, repulsive or partial seam, with that
  seam's stiffness (N/m) and rest length (0, or > 0 when repulsive).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.dart.model import Dart, merged_index
from darts.geometry.mesh import half_edges, interior_edge_halves


@dataclass
class ClothModel:
    """Arrays for the solver; every index is a particle index."""

    rest: np.ndarray  # [P,3]
    particle_of_vertex: np.ndarray  # [V]
    faces: np.ndarray  # [F,3]
    mass: np.ndarray  # [P]
    edges: np.ndarray  # [E,2]
    edge_rest: np.ndarray  # [E]
    hinges: np.ndarray  # [H,4]
    hinge_rest_angle: np.ndarray  # [H] radians, 0 = flat
    springs: np.ndarray  # [S,2]
    spring_rest: np.ndarray  # [S]
    spring_stiffness: np.ndarray  # [S] N/m
    spring_seam: np.ndarray  # [S] index into seam_names
    seam_names: list[str]
    material: dict


def dihedral_angles(points: np.ndarray, hinges: np.ndarray) -> np.ndarray:
    """Signed angle between the normals of triangles (i, j, k) and (j, i, l), 0 when flat."""
    i, j, k, l = (points[hinges[:, c]] for c in range(4))
    edge = j - i
    n1 = np.cross(edge, k - i)
    n2 = np.cross(l - i, edge)
    n1 /= np.maximum(np.linalg.norm(n1, axis=1, keepdims=True), 1e-20)
    n2 /= np.maximum(np.linalg.norm(n2, axis=1, keepdims=True), 1e-20)
    unit = edge / np.maximum(np.linalg.norm(edge, axis=1, keepdims=True), 1e-20)
    return np.arctan2(np.einsum("ij,ij->i", np.cross(n1, n2), unit), np.einsum("ij,ij->i", n1, n2))


def _hinges(faces: np.ndarray) -> np.ndarray:
    """(i, j, k, l) for each edge shared by two faces: (i, j) the edge, k and l the opposite corners."""
    a, b, key = half_edges(faces)
    opposite = np.roll(faces, -2, axis=1).reshape(-1)
    first, second = interior_edge_halves(key)
    return np.stack([a[first], b[first], opposite[first], opposite[second]], 1)


def cloth_model(dart: Dart) -> ClothModel:
    """The solver's model of ``dart`` (rest state in the canonical frame)."""
    welded_seams = [i for i, s in enumerate(dart.seams) if s.regime == "welded"]
    particle = merged_index(dart, dart.pairs[np.isin(dart.pair_seam, welded_seams)])
    count = particle.max() + 1
    rest = np.zeros((count, 3))
    rest[particle] = dart.vertices
    faces = particle[dart.faces].astype(np.int64)
    tri = rest[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    mass = np.zeros(count)
    np.add.at(mass, faces.reshape(-1), np.repeat(area / 3.0 * dart.material["density"], 3))
    edges = np.unique(np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1), axis=0)
    hinges = _hinges(faces)
    sprung = dart.pair_active & ~np.isin(dart.pair_seam, welded_seams)
    seam_of = dart.pair_seam[sprung]
    return ClothModel(
        rest=rest, particle_of_vertex=particle, faces=faces, mass=mass, edges=edges,
        edge_rest=np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1),
        hinges=hinges, hinge_rest_angle=dihedral_angles(rest, hinges),
        springs=particle[dart.pairs[sprung]].astype(np.int64),
        spring_rest=np.array([dart.seams[s].rest_length for s in seam_of]),
        spring_stiffness=np.array([dart.seams[s].stiffness for s in seam_of]),
        spring_seam=seam_of.astype(np.int64), seam_names=dart.seam_names, material=dict(dart.material),
    )
