"""Reading a garment mesh made elsewhere (OBJ, PLY, STL, GLB/GLTF with trimesh; USD with pxr) into
triangles in metres, Y up (the canonical frame's up), and the 4x4 that took the file's points there.

Units and up axis come from the file where it says (USD: ``metersPerUnit`` and ``upAxis``; glTF:
metres, Y up by its specification), else from the options, else they are guessed: OBJ, PLY and STL
carry no units, so the unit (m, cm or mm) that makes the garment between 0.2 m and 3 m across is
taken, and Y is taken as up (what Marvelous Designer, CLO and Blender's OBJ export write).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError
from darts.fileio import check_input_file

MESH_SUFFIXES = (".obj", ".ply", ".stl", ".glb", ".gltf", ".usd", ".usda", ".usdc", ".usdz")
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}
#: Sizes (largest extent, metres) a garment may have once in metres; a unit is guessed to land here.
PLAUSIBLE_SIZE = (0.2, 3.0)


@dataclass
class SourceMesh:
    """Triangles ``vertices`` [N,3] (metres, Y up) and ``faces`` [F,3]; ``to_canonical`` [4,4] maps
    the file's points (homogeneous, as stored) to ``vertices``; ``notes`` say what was assumed,
    ``units_note`` how the unit was decided."""

    vertices: np.ndarray
    faces: np.ndarray
    to_canonical: np.ndarray
    notes: list[str] = field(default_factory=list)
    units_note: str = ""


def triangulate(counts: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Fan triangulation of polygons given as ``counts`` [P] corners each and their flat corner
    ``indices``: polygon (v0, v1, ..., vk) becomes (v0, vi, vi+1) for i = 1..k-1."""
    counts = np.asarray(counts, np.int64)
    if (counts < 3).any():
        raise ValueError("a polygon has fewer than 3 corners")
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    fans = counts - 2
    first = np.repeat(starts, fans)
    offset = np.arange(fans.sum()) - np.repeat(np.cumsum(fans) - fans, fans) + 1
    return np.stack([indices[first], indices[first + offset], indices[first + offset + 1]], 1)


def _read_trimesh(path: Path) -> tuple[np.ndarray, np.ndarray, dict]:
    import trimesh

    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds for a file that is not a mesh  # noqa: BLE001
        raise DartsInputError(path, f"not a readable mesh ({type(exc).__name__}: {exc})") from None
    if not isinstance(loaded, trimesh.Trimesh):
        raise DartsInputError(path, "holds no triangle mesh")
    said = {}
    if path.suffix.lower() in (".glb", ".gltf"):
        said = {"units": "m", "up": "y", "units_why": "glTF is in metres", "up_why": "glTF is Y up"}
    return np.asarray(loaded.vertices, np.float64), np.asarray(loaded.faces, np.int64), said


def _read_usd(path: Path, prim_path: str | None) -> tuple[np.ndarray, np.ndarray, dict]:
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise DartsInputError(path, "not a readable USD stage")
    if prim_path is not None:
        prim = stage.GetPrimAtPath(prim_path)
        if not prim or not prim.IsA(UsdGeom.Mesh):
            raise DartsInputError(path, f"has no mesh at {prim_path}")
    else:
        prim = next((p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)), None)
        if prim is None:
            raise DartsInputError(path, "holds no UsdGeom.Mesh")
    mesh = UsdGeom.Mesh(prim)
    points = np.asarray(mesh.GetPointsAttr().Get() or [], np.float64).reshape(-1, 3)
    counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get() or [], np.int64)
    indices = np.asarray(mesh.GetFaceVertexIndicesAttr().Get() or [], np.int64)
    if counts.sum() != len(indices):
        raise DartsInputError(path, f"{prim.GetPath()}: faceVertexCounts do not add up to faceVertexIndices")
    # USD matrices act on row vectors (p M); transposed, on column vectors as everywhere here.
    world = np.asarray(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default()), np.float64).T
    try:
        faces = triangulate(counts, indices) if len(counts) else np.zeros((0, 3), np.int64)
    except ValueError as exc:
        raise DartsInputError(path, f"{prim.GetPath()}: {exc}") from None
    said = {"units": UsdGeom.GetStageMetersPerUnit(stage), "up": UsdGeom.GetStageUpAxis(stage).lower(),
            "units_why": "the stage's metersPerUnit", "up_why": "the stage's upAxis", "prim": str(prim.GetPath()),
            "world": world}
    return points, faces, said


def _up_rotation(up: str) -> np.ndarray:
    """The rotation taking ``up`` (y or z) to +Y: Z up goes to Y up by -90 degrees about X."""
    if up == "y":
        return np.eye(3)
    return np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])


def read_garment_mesh(path: str | os.PathLike, units: str | None = None, up: str | None = None,
                      prim: str | None = None) -> SourceMesh:
    """The triangles of the mesh file ``path`` in metres, Y up (see the module docstring for how
    units and up are decided; ``units``/``up`` override the file). ``prim`` picks a USD mesh."""
    path = check_input_file(path, "mesh file")
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise DartsInputError(path, f"unknown mesh format (one of {', '.join(MESH_SUFFIXES)})")
    if prim is not None and not suffix.startswith(".usd"):
        raise DartsInputError(path, "--prim applies to USD files only")
    points, faces, said = _read_usd(path, prim) if suffix.startswith(".usd") else _read_trimesh(path)
    if len(points) == 0 or len(faces) == 0:
        raise DartsInputError(path, "the mesh is empty (no triangles)")
    if not np.isfinite(points).all():
        raise DartsInputError(path, "the mesh has NaN or infinite coordinates")
    if faces.min() < 0 or faces.max() >= len(points):
        raise DartsInputError(path, "a face refers to a vertex the mesh does not have")
    notes = [f"read {path.suffix.lower()[1:].upper()}" + (f" mesh {said['prim']}" if "prim" in said else "")
             + f": {len(points)} points, {len(faces)} triangles"]
    up_axis = up or said.get("up") or "y"
    notes.append(f"up axis {up_axis.upper()}: " + ("--up" if up else said.get("up_why", "assumed (the file does not say)")))
    rotation = _up_rotation(up_axis)
    world = said.get("world", np.eye(4))
    extent = float(np.ptp(points @ world[:3, :3].T, axis=0).max())
    if units is not None:
        scale, why = UNITS[units], f"--units {units}"
    elif "units" in said:
        scale = float(UNITS[said["units"]] if isinstance(said["units"], str) else said["units"])
        why = said["units_why"]
    else:
        scale = next((s for s in sorted(UNITS.values(), reverse=True)
                      if PLAUSIBLE_SIZE[0] <= extent * s <= PLAUSIBLE_SIZE[1]), 1.0)
        why = f"guessed: {extent:.4g} units across is {extent * scale:.2f} m"
    units_note = f"1 unit = {scale:g} m ({why})"
    notes.append(units_note)
    to_canonical = np.eye(4)
    to_canonical[:3, :3] = scale * rotation
    to_canonical = to_canonical @ said.get("world", np.eye(4))  # a USD prim's own transform first
    vertices = points @ to_canonical[:3, :3].T + to_canonical[:3, 3]
    return SourceMesh(vertices, faces, to_canonical, notes, units_note)
