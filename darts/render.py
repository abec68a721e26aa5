"""Flat-shaded pictures of meshes with matplotlib (painter's algorithm, orthographic views).

Draws on matplotlib Axes; callers make figures with ``matplotlib.figure.Figure`` so the package
never changes the user's pyplot backend.
"""
from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection

FRONT = (np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))  # canonical frame: look along -Z
SIDE = (np.array([0, 0, 1.0]), np.array([0, 1.0, 0]))  # look along -X, front +Z to the right
BACK = (np.array([-1.0, 0, 0]), np.array([0, 1.0, 0]))
#: A posed scene (AMASS world, Z up, the body facing -Y) seen from the front-left.
WORLD_FRONT_LEFT = (np.array([np.cos(0.6), np.sin(0.6), 0.0]), np.array([0, 0, 1.0]))


def draw_mesh(ax, vertices, faces, colors, right, up, two_sided: bool = False):
    """Project onto (right, up), sort triangles back to front, shade by n . view (Lambert).
    Back faces are culled unless ``two_sided`` (open garments show their inside)."""
    view = np.cross(right, up)
    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True) + 1e-12
    facing = normals @ view
    keep = np.ones(len(faces), bool) if two_sided else facing > 0
    order = np.argsort((tri[keep] @ view).mean(1))
    shade = (0.35 + 0.65 * np.abs(facing[keep][order]))[:, None]
    polys = np.stack([tri[keep][order] @ right, tri[keep][order] @ up], -1)
    ax.add_collection(PolyCollection(polys, facecolors=np.clip(colors[keep][order] * shade, 0, 1), edgecolors="none"))
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.axis("off")
