"""``darts.meshimport.panel_cut``: a mesh cut exactly along the borders of a distance field."""
from __future__ import annotations

import numpy as np

from darts.geometry.mesh import boundary_loops
from darts.meshimport.panel_cut import MARGIN, cut_along_panels


def _grid(n: int = 11) -> tuple[np.ndarray, np.ndarray]:
    """The unit square in the z = 0 plane, n x n vertices, two triangles a cell."""
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="xy")
    vertices = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], 1)
    corner = (np.arange(n - 1)[None] + n * np.arange(n - 1)[:, None]).ravel()
    faces = np.r_[np.stack([corner, corner + 1, corner + n + 1], 1), np.stack([corner, corner + n + 1, corner + n], 1)]
    return vertices, faces


def _areas(vertices, faces):
    return 0.5 * np.linalg.norm(np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]],
                                         vertices[faces[:, 2]] - vertices[faces[:, 0]]), axis=1)


def _quality(vertices, faces):
    """4 sqrt(3) area / sum of squared edges: 1 for an equilateral triangle, 0 for a sliver."""
    edges = vertices[faces[:, [1, 2, 0]]] - vertices[faces]
    return 4 * np.sqrt(3) * _areas(vertices, faces) / (edges ** 2).sum((1, 2))


def test_two_panels_are_cut_along_their_border_not_along_the_edges():
    """A slanted border (x + 0.3 y = 0.52) across a grid: every triangle lies on one side, the
    border's vertices on the line, the area and the opening kept, no sliver cut off."""
    vertices, faces = _grid()
    side = (vertices[:, 0] + 0.3 * vertices[:, 1] - 0.52) / np.hypot(1, 0.3)  # signed distance to the border
    distances = np.stack([np.maximum(side, 0), np.maximum(-side, 0)], 1)
    loop = boundary_loops(faces)[0]
    points, cut_faces, panels, loops = cut_along_panels(vertices, faces, distances, {"rim": loop})
    assert set(panels.tolist()) == {0, 1} and len(cut_faces) > len(faces)
    signed = (points[:, 0] + 0.3 * points[:, 1] - 0.52) / np.hypot(1, 0.3)
    assert np.all(signed[cut_faces[panels == 0]] <= 1e-9) and np.all(signed[cut_faces[panels == 1]] >= -1e-9)
    both = np.intersect1d(cut_faces[panels == 0], cut_faces[panels == 1])
    assert len(both) >= 10 and np.abs(signed[both]).max() < 1e-9  # the border's vertices lie on it
    assert np.isclose(_areas(points, cut_faces).sum(), 1.0)
    assert _quality(points, cut_faces).min() > 0.5 * _quality(vertices, faces).min() * MARGIN
    moved = np.linalg.norm(points[:len(vertices)] - vertices, axis=1)
    assert 0 < moved.max() < 0.2 * 0.1 * np.sqrt(2) + 1e-12  # a vertex next to the border moved onto it
    rim = loops["rim"]  # the opening passes through the border's two new points on it
    assert len(rim) > len(loop) and np.sum(np.abs(signed[rim]) < 1e-9) == 2
    assert set(boundary_loops(cut_faces)[0].tolist()) == set(rim.tolist())
    outline = points[rim]  # still the square's: a vertex on the opening moved only along it
    assert (np.isclose(outline[:, :2], 0) | np.isclose(outline[:, :2], 1)).any(1).all()


def test_three_panels_meet_at_one_point_and_a_mesh_on_the_borders_is_not_cut():
    """Three panels as the Voronoi cells of three sites (squared distances: the borders are straight
    and exact): a vertex on one border between two cells is equidistant from their sites, a
    single point joins all three, the sites' circumcentre (where the three borders meet; the mean of
    its triangle's three crossings was 0.23 of an edge off); a field whose borders already run along
    edges cuts nothing."""
    vertices, faces = _grid(13)
    sites = np.array([[0.2, 0.25, 0], [0.83, 0.3, 0], [0.47, 0.86, 0]])
    squared = ((vertices[:, None] - sites[None]) ** 2).sum(2)
    points, cut_faces, panels, _ = cut_along_panels(vertices, faces, squared)
    assert np.isclose(_areas(points, cut_faces).sum(), 1.0)
    owners = [set(panels[np.flatnonzero((cut_faces == v).any(1))].tolist()) for v in range(len(points))]
    assert sum(len(o) == 3 for o in owners) == 1
    junction = points[next(v for v, own in enumerate(owners) if len(own) == 3)]
    centre = np.linalg.solve(2 * (sites[1:, :2] - sites[0, :2]), (sites[1:] ** 2).sum(1) - (sites[0] ** 2).sum())
    assert np.linalg.norm(junction[:2] - centre) < 0.1 / 12  # a tenth of an edge (kept MARGIN inside its triangle)
    offsets = np.array([abs(np.linalg.norm(points[v] - sites[min(own)]) - np.linalg.norm(points[v] - sites[max(own)]))
                        for v, own in enumerate(owners) if len(own) == 2])
    assert len(offsets) >= 15 and np.mean(offsets < 1e-9) > 0.85  # exact, but where a crossing was kept MARGIN
    assert offsets.max() < MARGIN / 12  # from an edge's end (beside the junction, where no vertex may snap)

    half = np.stack([np.maximum(vertices[:, 0] - 0.5, 0), np.maximum(0.5 - vertices[:, 0], 0)], 1)  # x = 0.5: a grid line
    points, cut_faces, panels, _ = cut_along_panels(vertices, faces, half)
    assert len(cut_faces) == len(faces) and np.array_equal(points, vertices)
    assert np.all(vertices[cut_faces[panels == 0], 0] <= 0.5) and np.all(vertices[cut_faces[panels == 1], 0] >= 0.5)
