"""Animated meshes as a numbered sequence of OBJ or PLY files in one directory.

The directory is filled beside its target and renamed into place when closed; an existing target
is replaced only if it holds nothing but such a sequence.
"""
from __future__ import annotations

import re
import shutil
import tempfile
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError
from darts.fileio import Janitor, remove_stale_temporaries, temporary_prefix
from exporters.streaming import StreamingWriter

SEQUENCE_FORMATS = ("obj", "ply")
_FRAME_FILE = re.compile(r"^[A-Za-z0-9_]+_\d{4,}\.(obj|ply)$")


class MeshSequenceWriter(StreamingWriter):
    """``add_mesh`` each mesh once, ``write_frame`` per frame (``NAME_0000.obj``, ...), then ``close``."""

    def __init__(self, directory, fps: float, file_format: str = "obj"):
        self.path = Path(directory)
        if file_format not in SEQUENCE_FORMATS:
            raise DartsInputError(None, f"unknown sequence format '{file_format}' (one of {', '.join(SEQUENCE_FORMATS)})")
        if self.path.exists() and (not self.path.is_dir()
                                   or any(not _FRAME_FILE.match(p.name) for p in self.path.iterdir())):
            raise DartsInputError(self.path, "exists and is not a mesh sequence; choose another output")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(self.path)
        self.fps, self.format = float(fps), file_format
        self._tmp = Path(tempfile.mkdtemp(prefix=temporary_prefix(self.path), dir=self.path.parent))
        self._janitor = Janitor(self._tmp)  # removes the folder if this process is killed
        self._meshes: dict[str, tuple[np.ndarray, np.ndarray | None]] = {}
        self.frames_written = 0

    def add_mesh(self, name: str, faces: np.ndarray, vertex_count: int, face_colors: np.ndarray | None = None) -> None:
        self._meshes[name] = (np.asarray(faces), face_colors)

    def add_curves(self, name: str, segments: np.ndarray, width: float = 0.002) -> None:
        """Curves are a USD feature; a mesh sequence has none."""

    def write_frame(self, points: dict[str, np.ndarray]) -> None:
        import trimesh

        for name, (faces, colors) in self._meshes.items():
            mesh = trimesh.Trimesh(np.asarray(points[name], np.float64), faces, process=False)
            if colors is not None:
                mesh.visual.face_colors = (255 * np.asarray(colors)).astype(np.uint8)
            mesh.export(self._tmp / f"{name}_{self.frames_written:04d}.{self.format}")
        self.frames_written += 1

    def close(self) -> None:
        if self.frames_written == 0:
            raise ValueError("no frame was written")
        if self.path.exists():
            shutil.rmtree(self.path)
        self._tmp.rename(self.path)
        self._janitor.release()

    def discard(self) -> None:
        shutil.rmtree(self._tmp, ignore_errors=True)
        self._janitor.release()
