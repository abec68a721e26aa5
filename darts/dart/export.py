"""Writing a DART as a plain mesh (OBJ, PLY, GLB) with one colour per panel."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from darts.dart.model import Dart
from darts.errors import DartsInputError
from darts.fileio import atomic_path

MESH_FORMATS = (".obj", ".ply", ".glb")


def panel_colors(count: int) -> np.ndarray:
    """Distinct RGB colours in [0, 1], one per panel."""
    import matplotlib

    palette = matplotlib.colormaps["tab20"](np.arange(count) % 20)[:, :3]
    return palette


def export_mesh(dart: Dart, path: str | os.PathLike) -> None:
    """Write the DART's mesh with per-vertex panel colours (panels do not share vertices)."""
    path = Path(path)
    if path.suffix.lower() not in MESH_FORMATS:
        raise DartsInputError(path, f"unknown mesh format (one of {', '.join(MESH_FORMATS)})")
    colors = panel_colors(len(dart.panel_names))
    vertex_colors = np.full((len(dart.vertices), 4), 255, np.uint8)
    vertex_colors[dart.faces.reshape(-1), :3] = (255 * colors[np.repeat(dart.panel, 3)]).astype(np.uint8)
    import trimesh

    mesh = trimesh.Trimesh(dart.vertices, dart.faces, vertex_colors=vertex_colors, process=False)
    with atomic_path(path) as tmp:
        data = mesh.export(file_type=path.suffix.lower()[1:])
        Path(tmp).write_bytes(data if isinstance(data, bytes) else data.encode())
