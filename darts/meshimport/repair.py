"""Making an imported garment mesh one clean open surface, or saying why it cannot be.

Repaired (safe: the surface is unchanged): coincident vertices merged (seams of panel-wise exports,
STL's unshared corners), degenerate and repeated triangles and unused vertices dropped, pieces of
less than ``SMALL_PIECE`` of the area (labels, buttons, stray triangles) removed. Triangles are wound
consistently. Refused: edges shared by more than two triangles, several pieces of comparable size,
openings touching at a vertex, a surface with no boundary.
"""
from __future__ import annotations

import numpy as np

from darts.errors import DartsInputError
from darts.geometry.mesh import boundary_loops, directed_edges

#: Pieces with less than this fraction of the total area are removed rather than refused.
SMALL_PIECE = 0.02


def _triangle_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    corners = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)


def repair_garment_mesh(vertices: np.ndarray, faces: np.ndarray, source):
    """(vertices, faces, boundary loops, notes): the one open, edge-manifold surface of the mesh,
    or a DartsInputError naming ``source`` and what is wrong."""
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    notes = []
    count = len(mesh.vertices)
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    if len(mesh.vertices) < count:
        notes.append(f"merged {count - len(mesh.vertices)} coincident vertices")
    count = len(mesh.faces)
    mesh.update_faces(mesh.nondegenerate_faces(height=1e-12))
    mesh.update_faces(mesh.unique_faces())
    mesh.remove_unreferenced_vertices()
    if len(mesh.faces) < count:
        notes.append(f"dropped {count - len(mesh.faces)} degenerate or repeated triangles")
    if len(mesh.faces) == 0:
        raise DartsInputError(source, "the mesh has no triangle with an area")
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces, np.int64)

    edges = np.sort(directed_edges(faces), axis=1)
    _, uses = np.unique(edges, axis=0, return_counts=True)
    if (uses > 2).any():
        raise DartsInputError(source, f"{(uses > 2).sum()} edges are shared by more than two triangles "
                                      "(a non-manifold mesh)")
    labels = trimesh.graph.connected_component_labels(trimesh.graph.face_adjacency(faces), node_count=len(faces))
    area = np.bincount(labels, _triangle_areas(vertices, faces))
    share = area / area.sum()
    if (share >= SMALL_PIECE).sum() > 1:
        sizes = ", ".join(f"{s:.0%}" for s in np.sort(share)[::-1][:4])
        raise DartsInputError(source, f"the mesh has {(share >= SMALL_PIECE).sum()} separate pieces of comparable "
                                      f"size ({sizes} of the area): import one garment at a time")
    if len(share) > 1:
        keep = labels == int(np.argmax(share))
        notes.append(f"removed {len(share) - 1} small pieces ({1 - share.max():.1%} of the area)")
        mesh = trimesh.Trimesh(vertices, faces[keep], process=False)
        mesh.remove_unreferenced_vertices()
        vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces, np.int64)

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    trimesh.repair.fix_winding(mesh)  # boundary loops follow the winding: make it consistent
    faces = np.asarray(mesh.faces, np.int64)
    try:
        loops = boundary_loops(faces)
    except ValueError:
        raise DartsInputError(source, "two openings touch at a vertex (the boundary is not a set of "
                                      "separate loops)") from None
    if not loops:
        raise DartsInputError(source, "the mesh has no boundary (a closed surface): a garment needs openings")
    return vertices, faces, loops, notes
