"""Animated meshes to USD (.usda text or .usdc binary), streamed frame by frame.

The stage is Z up with one metre per unit (the AMASS world frame of the simulation), its time codes
are frames at ``fps``, and ``/World`` is the default prim. Each mesh has time-sampled points and
extents, per-face ``displayColor`` and no subdivision; seam curves are optional linear
BasisCurves. The file is written beside its target and renamed into place when closed.
"""
from __future__ import annotations

import os
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError
from darts.fileio import atomic_path
from exporters.streaming import StreamingWriter

USD_SUFFIXES = (".usd", ".usda", ".usdc")


@dataclass
class _Track:
    points_attr: object
    extent_attr: object
    vertex_count: int


def _safe_name(name: str) -> str:
    cleaned = "".join(c if c.isalnum() or c == "_" else "_" for c in name)
    return cleaned if cleaned and not cleaned[0].isdigit() else f"_{cleaned}"


class UsdAnimationWriter(StreamingWriter):
    """Write animated meshes: ``add_mesh`` each once, ``write_frame`` per frame, then ``close``.

    Use as a context manager; if the block raises, nothing is left at ``path``.
    """

    def __init__(self, path: str | os.PathLike, fps: float, start_frame: int = 0):
        from pxr import Sdf, Usd, UsdGeom, Vt

        self.path = Path(path)
        if self.path.suffix.lower() not in USD_SUFFIXES:
            raise DartsInputError(self.path, f"not a USD file name (one of {', '.join(USD_SUFFIXES)})")
        if not np.isfinite(fps) or fps <= 0:
            raise DartsInputError(None, f"fps must be positive, got {fps}")
        self._geom, self._sdf, self._vt = UsdGeom, Sdf, Vt
        self._stack = ExitStack()
        self._tmp = self._stack.enter_context(atomic_path(self.path, keep_suffix=True, janitor=True))
        os.unlink(self._tmp)  # USD creates the layer itself
        self.stage = Usd.Stage.CreateNew(str(self._tmp))
        UsdGeom.SetStageUpAxis(self.stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(self.stage, 1.0)
        self.stage.SetTimeCodesPerSecond(float(fps))
        self.stage.SetFramesPerSecond(float(fps))
        world = UsdGeom.Xform.Define(self.stage, "/World")
        self.stage.SetDefaultPrim(world.GetPrim())
        self.start_frame = start_frame
        self.frames_written = 0
        self._tracks: dict[str, _Track] = {}
        self._curves: dict[str, tuple[object, np.ndarray]] = {}

    def add_mesh(self, name: str, faces: np.ndarray, vertex_count: int, face_colors: np.ndarray | None = None) -> None:
        """A triangle mesh ``/World/<name>``; ``face_colors`` [F,3] in [0, 1]."""
        mesh = self._geom.Mesh.Define(self.stage, f"/World/{_safe_name(name)}")
        faces = np.asarray(faces, np.int32)
        mesh.CreateFaceVertexCountsAttr(np.full(len(faces), 3, np.int32).tolist())
        mesh.CreateFaceVertexIndicesAttr(faces.reshape(-1).tolist())
        mesh.CreateSubdivisionSchemeAttr(self._geom.Tokens.none)
        mesh.CreateOrientationAttr(self._geom.Tokens.rightHanded)
        if face_colors is not None:
            primvar = mesh.CreateDisplayColorPrimvar(self._geom.Tokens.uniform)
            primvar.Set([tuple(map(float, c)) for c in np.asarray(face_colors)])
        self._tracks[name] = _Track(mesh.CreatePointsAttr(), mesh.CreateExtentAttr(), vertex_count)

    def add_curves(self, name: str, segments: np.ndarray, width: float = 0.002) -> None:
        """Linear curve segments between vertex pairs ``segments`` [S,2] of the mesh ``name``
        (seam springs, say), moving with it."""
        curves = self._geom.BasisCurves.Define(self.stage, f"/World/{_safe_name(name)}_seams")
        curves.CreateTypeAttr(self._geom.Tokens.linear)
        curves.CreateCurveVertexCountsAttr(np.full(len(segments), 2, np.int32).tolist())
        curves.CreateWidthsAttr([float(width)])
        curves.SetWidthsInterpolation(self._geom.Tokens.constant)
        self._curves[name] = (curves, np.asarray(segments, np.int64))

    def write_frame(self, points: dict[str, np.ndarray]) -> None:
        """Points [V,3] (metres, Z up) of every mesh at the next frame."""
        time = float(self.start_frame + self.frames_written)
        for name, track in self._tracks.items():
            p = np.asarray(points[name], np.float32)
            if p.shape != (track.vertex_count, 3) or not np.isfinite(p).all():
                raise ValueError(f"frame {self.frames_written}: '{name}' points must be finite [{track.vertex_count}, 3]")
            track.points_attr.Set(self._vt.Vec3fArray.FromNumpy(p), time)
            track.extent_attr.Set(self._vt.Vec3fArray.FromNumpy(np.stack([p.min(0), p.max(0)])), time)
            if name in self._curves:
                curves, segments = self._curves[name]
                ends = p[segments].reshape(-1, 3)
                curves.GetPointsAttr().Set(self._vt.Vec3fArray.FromNumpy(np.ascontiguousarray(ends)), time)
                curves.GetExtentAttr().Set(self._vt.Vec3fArray.FromNumpy(np.stack([ends.min(0), ends.max(0)])), time)
        self.frames_written += 1

    def close(self) -> None:
        """Set the time range, save, and move the file into place."""
        if self.frames_written == 0:
            raise ValueError("no frame was written")
        self.stage.SetStartTimeCode(float(self.start_frame))
        self.stage.SetEndTimeCode(float(self.start_frame + self.frames_written - 1))
        self.stage.GetRootLayer().Save()
        self.stage = None
        self._stack.close()

    def discard(self) -> None:
        """Drop the stage and the temporary file."""
        self.stage = None
        self._stack.__exit__(RuntimeError, None, None)


def validate_usd(path: str | os.PathLike) -> list[str]:
    """Run every registered USD validator on the file; return the error messages (warnings ignored)."""
    from pxr import Usd, UsdValidation

    stage = Usd.Stage.Open(str(path))
    registry = UsdValidation.ValidationRegistry()
    context = UsdValidation.ValidationContext(registry.GetOrLoadAllValidators())
    errors = context.Validate(stage)
    return [f"{e.GetName()}: {e.GetMessage()}" for e in errors if e.GetType() == UsdValidation.ValidationErrorType.Error]
