"""Preview renders of an animation (body and garment, flat-shaded, fixed front-left camera) with
matplotlib, through ``darts.render.draw_mesh``.

Points are in the world frame (Z up, metres). ``.gif`` uses Pillow, ``.mp4`` ffmpeg (on PATH),
``.png`` a contact sheet of evenly spaced frames. ``read_usd_animation`` reads what
``darts-sim`` writes (``/World/body`` and its garments' meshes), so a finished result can be rendered.
"""
from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError
from darts.fileio import atomic_path, check_output
from darts.render import WORLD_FRONT_LEFT, draw_mesh

PREVIEW_SUFFIXES = (".gif", ".mp4", ".png")


@dataclass
class Animation:
    """Meshes [F,3] with per-face RGB colours, and per-frame points [T,V,3] (world, Z up, metres)."""

    faces: dict[str, np.ndarray]
    colors: dict[str, np.ndarray]
    frames: dict[str, np.ndarray]
    fps: float
    numbers: np.ndarray | None = None  # the animation frame each stored frame is (default 0, 1, ...)
    total: int | None = None  # frames in the whole animation (default: those stored)

    @property
    def count(self) -> int:
        return len(next(iter(self.frames.values())))

    def number(self, index: int) -> int:
        return int(self.numbers[index]) if self.numbers is not None else index


def frames_to_draw(total: int, path: str | os.PathLike, max_frames: int = 60) -> np.ndarray:
    """Indices of the frames a preview of ``total`` frames draws: at most ``max_frames`` evenly
    spaced (6 for a .png contact sheet)."""
    wanted = 6 if Path(path).suffix.lower() == ".png" else max_frames
    return np.unique(np.linspace(0, total - 1, max(1, min(wanted, total))).round().astype(int))


def read_usd_animation(path: str | os.PathLike) -> Animation:
    """The body and garment meshes of a ``darts-sim`` USD file, every time sample: ``/World/body``
    and every other mesh under ``/World`` (one garment, ``/World/garment``, or an outfit's, one mesh
    each, in the file's order)."""
    from pxr import Usd, UsdGeom

    path = Path(path)
    if not path.is_file():
        raise DartsInputError(path, "no such file")
    try:
        stage = Usd.Stage.Open(str(path))
    except Exception:  # pxr raises Tf.ErrorException for anything it cannot read as a layer
        stage = None
    if stage is None:
        raise DartsInputError(path, "not a USD file")
    body = stage.GetPrimAtPath("/World/body")
    if not body or not body.IsA(UsdGeom.Mesh):
        raise DartsInputError(path, "has no mesh /World/body (not written by darts-sim)")
    world = stage.GetPrimAtPath("/World")
    garments = [prim for prim in world.GetChildren() if prim.IsA(UsdGeom.Mesh) and prim.GetName() != "body"]
    if not garments:
        raise DartsInputError(path, "has no garment mesh under /World (not written by darts-sim)")
    faces, colors, frames = {}, {}, {}
    for prim in [body, *garments]:
        name, mesh = prim.GetName(), UsdGeom.Mesh(prim)
        faces[name] = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), np.int64).reshape(-1, 3)
        color = mesh.GetDisplayColorAttr().Get()
        colors[name] = (np.asarray(color, np.float64) if color is not None and len(color) == len(faces[name])
                        else np.full((len(faces[name]), 3), 0.7))
        times = mesh.GetPointsAttr().GetTimeSamples() or [Usd.TimeCode.Default()]
        frames[name] = np.stack([np.asarray(mesh.GetPointsAttr().Get(t), np.float64) for t in times])
    return Animation(faces, colors, frames, float(stage.GetTimeCodesPerSecond()))


class _Painter:
    """One axes with a camera fixed over the whole animation (front-left view, orthographic)."""

    def __init__(self, axes, animation: Animation):
        self.axes, self.animation = axes, animation
        right, up = WORLD_FRONT_LEFT
        everything = np.concatenate([f.reshape(-1, 3) for f in animation.frames.values()])
        flat = np.stack([everything @ right, everything @ up], axis=1)
        self.limits = flat.min(0) - 0.05, flat.max(0) + 0.05
        self.names = list(animation.faces)
        offsets = np.cumsum([0] + [animation.frames[n].shape[1] for n in self.names])
        self.faces = np.concatenate([animation.faces[n] + o for n, o in zip(self.names, offsets)])
        self.colors = np.concatenate([animation.colors[n] for n in self.names])

    def draw(self, index: int) -> None:
        """One frame; both meshes drawn together so that triangles are depth-sorted together."""
        ax = self.axes
        ax.clear()
        points = np.concatenate([self.animation.frames[n][index] for n in self.names])
        draw_mesh(ax, points, self.faces, self.colors, *WORLD_FRONT_LEFT, two_sided=True)
        ax.set_xlim(self.limits[0][0], self.limits[1][0])
        ax.set_ylim(self.limits[0][1], self.limits[1][1])
        number = self.animation.number(index)
        ax.set_title(f"frame {number}  ({number / self.animation.fps:.2f} s)", fontsize=9)


def check_preview(path: str | os.PathLike) -> Path:
    """``path`` as a Path if a preview can be written there (``check_output``, a suffix of
    ``PREVIEW_SUFFIXES``, ffmpeg on PATH for .mp4), else a DartsInputError."""
    if Path(path).suffix.lower() not in PREVIEW_SUFFIXES:
        raise DartsInputError(path, f"preview must end in {', '.join(PREVIEW_SUFFIXES)}")
    path = check_output(path)
    if path.suffix.lower() == ".mp4" and shutil.which("ffmpeg") is None:
        raise DartsInputError(path, "an .mp4 preview needs ffmpeg on PATH; use .gif or .png")
    return path


def render_preview(animation: Animation, path: str | os.PathLike, max_frames: int = 60, size: float = 4.0,
                   progress: bool = False) -> int:
    """Render ``animation`` to ``path`` (.gif, .mp4 or .png contact sheet); returns the frames drawn:
    those of ``frames_to_draw`` among the stored ones. The file appears only when complete."""
    from matplotlib import animation as mpl_animation
    from matplotlib.figure import Figure
    from tqdm import tqdm

    path = check_preview(path)
    suffix = path.suffix.lower()
    picks = frames_to_draw(animation.count, path, max_frames)
    if suffix == ".png":
        figure = Figure(figsize=(size * len(picks) / 1.6, size))
        for slot, index in enumerate(tqdm(picks, desc="rendering", disable=not progress, leave=False)):
            _Painter(figure.add_subplot(1, len(picks), slot + 1), animation).draw(int(index))
        with atomic_path(path, keep_suffix=True) as tmp:
            figure.savefig(tmp, dpi=110, format="png", bbox_inches="tight")
        return len(picks)
    figure = Figure(figsize=(size, size))
    painter = _Painter(figure.add_subplot(), animation)
    stride_fps = animation.fps * len(picks) / (animation.total or animation.count)
    writer = mpl_animation.PillowWriter(fps=stride_fps) if suffix == ".gif" else mpl_animation.FFMpegWriter(fps=stride_fps)
    with atomic_path(path, keep_suffix=True) as tmp:
        with writer.saving(figure, str(tmp), dpi=100):
            for index in tqdm(picks, desc="rendering", disable=not progress, leave=False):
                painter.draw(int(index))
                writer.grab_frame()
    return len(picks)
