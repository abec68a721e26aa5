"""Removing slivers: short edges collapsed and single-face corners repaired, curves kept as curves."""
from __future__ import annotations

import numpy as np

from darts.geometry.levelset import insert_level_set
from darts.geometry.mesh import boundary_loops, edge_manifold, unique_edges
from darts.geometry.slivers import remove_slivers


def _grid(n: int = 12, size: float = 0.12):
    """An n x n grid of squares (1 cm for the defaults), each split in two, in the z = 0 plane."""
    y, x = np.meshgrid(np.linspace(0, size, n + 1), np.linspace(0, size, n + 1), indexing="ij")
    vertices = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], 1)
    faces = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = i * (n + 1) + j, i * (n + 1) + j + 1, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1
            faces += [(a, b, d), (a, d, c)]
    return vertices, np.array(faces, np.int64)


def _seamed_grid():
    """The grid with two seams inserted as level sets the way templates get theirs: x = 0.0405
    (passing 0.5 mm from a column of vertices: the snap moves them) and then y = 0.0603, which may
    not move the first seam's or the boundary's vertices, so it leaves sub-millimetre edges where
    it crosses them. Returns vertices, faces and the seams' edges."""
    vertices, faces = _grid()
    locked = np.zeros(len(vertices), bool)
    locked[np.concatenate(boundary_loops(faces))] = True
    lines = (("vertical", 0, 0.0405), ("horizontal", 1, 0.0603))
    for _name, axis, value in lines:
        vertices, faces, values = insert_level_set(vertices, faces, vertices[:, axis] - value, locked=locked)
        locked = np.concatenate([locked, np.zeros(len(vertices) - len(locked), bool)]) | (values == 0)
    edges = unique_edges(faces)
    on = {name: np.abs(vertices[:, axis] - value) < 1e-12 for name, axis, value in lines}
    return vertices, faces, {name: edges[on[name][edges].all(1)] for name in on}


def _lengths(vertices, faces):
    edges = unique_edges(faces)
    return np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1)


def _ends(edges):
    """Vertices that end a polyline (one edge)."""
    count = np.bincount(edges.reshape(-1))
    return set(np.where(count == 1)[0])


def test_seam_insertion_leaves_slivers_that_are_collapsed_along_the_curves():
    vertices, faces, seams = _seamed_grid()
    before = _lengths(vertices, faces)
    assert before.min() < 0.001  # the horizontal seam's crossings: slivers under 1 mm (1 cm squares)
    out_vertices, out_faces, out_seams, report = remove_slivers(vertices, faces, seams, 0.0035)
    after = _lengths(out_vertices, out_faces)
    assert after.min() >= 0.0035 and report.short_left == 0 and report.collapsed > 0
    assert edge_manifold(out_faces) and len(boundary_loops(out_faces)) == 1
    # Each seam is still one polyline from boundary to boundary on its line (x = 0.0405, y = 0.0603),
    # with the same length (1 mm at most shorter, where a crossing slid along it).
    for name, axis, value in (("vertical", 0, 0.0405), ("horizontal", 1, 0.0603)):
        edges = out_seams[name]
        points = out_vertices[np.unique(edges)]
        assert np.abs(points[:, axis] - value).max() < 1e-12, name
        assert len(_ends(edges)) == 2 and len(np.unique(edges)) == len(edges) + 1, name
        length = np.linalg.norm(out_vertices[edges[:, 0]] - out_vertices[edges[:, 1]], axis=1).sum()
        assert abs(length - 0.12) < 1e-9, name
    # The outline is where it was: every boundary vertex on the square's edges.
    outline = out_vertices[np.concatenate(boundary_loops(out_faces))]
    assert (np.minimum(np.abs(outline[:, :2]), np.abs(outline[:, :2] - 0.12)).min(1) < 1e-12).all()
    # Face winding kept: every normal still +z.
    normals = np.cross(out_vertices[out_faces[:, 1]] - out_vertices[out_faces[:, 0]],
                       out_vertices[out_faces[:, 2]] - out_vertices[out_faces[:, 0]])
    assert (normals[:, 2] > 0).all()


def test_a_corner_sector_with_one_face_gets_a_second():
    """A seam along the grid's diagonal of one corner square leaves the corner vertex's sector
    between the seam and the boundary with one triangle; the repair splits the opposite edge."""
    vertices, faces = _grid(4, 0.04)
    corner, diagonal_end = 0, 6  # faces (0, 1, 6) and (0, 6, 5): the seam 0-6 cuts the corner square
    seams = {"diagonal": np.array([[corner, diagonal_end], [diagonal_end, 12], [12, 18], [18, 24]])}
    out_vertices, out_faces, out_seams, report = remove_slivers(vertices, faces, seams, 0.003)
    assert report.split + report.flipped >= 2 and report.lone_corners_left == 0
    # Cut along the seam, the corner's two copies each have three neighbours or more.
    around = [f for f in out_faces.tolist() if corner in f]
    assert len(around) >= 4  # two faces on each side of the seam
    assert _lengths(out_vertices, out_faces).min() >= 0.003
    assert edge_manifold(out_faces)
