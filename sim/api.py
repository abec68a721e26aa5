"""The library entry point of the simulator: ``sim.simulate(garment, motion, ...)`` drapes a DART on
the body and simulates it through a motion, returning the frames as arrays and the measures; the
``darts-sim`` command and ``darts batch`` run the same ``SimJob`` through ``run_job``.

Frames are in the AMASS world frame (Z up, metres); the first recorded frame is the motion's frame
``start`` after ``settle`` seconds in which the body blends from its rest pose (and from the DART's
body shape into ``betas``) into it. Bad input raises ``DartsInputError`` before anything is written.
"""
from __future__ import annotations

import json
import os
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from darts import arguments as check
from darts.errors import DartsInputError
from darts.fileio import atomic_path, check_output
from exporters.sequence import SEQUENCE_FORMATS
from exporters.usd import USD_SUFFIXES
from sim.engine.settings import SimSettings
from sim.engine.solvers import resolved_settings

#: Exit code of an unstable run (its frames before the blow-up are kept).
UNSTABLE_EXIT = 3


@dataclass
class SimJob:
    """One simulation: the garment (a DART, a ``garment.npz`` or a shipped name; or a list of them,
    an outfit, inner layer first) on the body posed by ``motion`` (a ``Motion``, an AMASS ``.npz``
    or a shipped name), and where its results go.

    ``start``/``end``/``frames`` count motion frames at ``settings.fps``; ``body`` is a ``BodyModel`` or
    an SMPL-format file (default: the bundled body); ``betas`` the shape simulated on (default: the DART's own);
    ``material`` replaces every garment's; ``seams`` are ``NAME=REGIME[:STIFFNESS]`` settings (in an
    outfit NAME applies to every garment with that seam, ``GARMENT/NAME`` to one).
    ``output``: a USD file (.usd/.usda/.usdc) or a folder of OBJ/PLY frames (``format``); ``stats``:
    a JSON of every frame's measures; ``preview``: a .gif/.mp4/.png picture of the run; ``winding``:
    also measure penetration by the body's winding number and an outfit's layer order (about four
    times the other measures' cost; default: when ``stats`` are written); ``measure_every``: the
    measures that query the body and the garment (penetration, crossing edges, layer order) on
    every N-th recorded frame and the last (1: every frame), so that measuring costs under a tenth
    of a frame (``sim.run.simulate``)."""

    garment: object
    motion: object
    settings: SimSettings = field(default_factory=SimSettings)  # or a dict of its fields
    start: int = 0
    end: int | None = None
    frames: int | None = None
    settle: float = 0.5
    body: object = None  # a BodyModel, an SMPL-format file, or None: the bundled body
    betas: Sequence[float] | None = None
    material: str | None = None
    seams: Sequence[str] = ()
    output: str | None = None
    format: str = "obj"
    seam_curves: bool = False
    stats: str | None = None
    preview: str | None = None
    winding: bool | None = None
    measure_every: int = 10

    def __post_init__(self):
        """Every value's type checked (``darts.arguments``: a DartsInputError naming the field) and
        normalised: ``settings`` given as a dict becomes a ``SimSettings``, sequences become tuples."""
        self.settings = settings_of(self.settings)
        garments = self.garment if isinstance(self.garment, (list, tuple)) else [self.garment]
        if not garments:
            raise DartsInputError(None, "garment: an outfit needs at least one garment")
        for garment in garments:
            _check_object(garment, "garment", "darts.dart.model", "Dart", "a path, a shipped garment's name or a Dart")
        _check_object(self.motion, "motion", "darts.motion.amass", "Motion", "a path, a shipped motion's name or a Motion")
        if self.body is not None:
            _check_object(self.body, "body", "darts.body.model", "BodyModel", "None, a path or a BodyModel")
        self.start = check.number(self.start, "start", 0, whole=True)
        self.end = check.optional_number(self.end, "end", 1, whole=True)
        self.frames = check.optional_number(self.frames, "frames", 1, whole=True)
        self.settle = check.number(self.settle, "settle", 0)
        self.betas = None if self.betas is None else check.number_list(self.betas, "betas")
        self.material = None if self.material is None else check.text(self.material, "material")
        self.seams = check.text_list(self.seams, "seams", "all=loose")
        for name in ("output", "stats", "preview"):
            if getattr(self, name) is not None:
                check.path_or(getattr(self, name), name, what="None or a path")
        self.format = check.text(self.format, "format", SEQUENCE_FORMATS)
        self.seam_curves = check.switch(self.seam_curves, "seam_curves")
        self.winding = None if self.winding is None else check.switch(self.winding, "winding")
        self.measure_every = check.number(self.measure_every, "measure_every", 1, whole=True)

    def check(self) -> SimSettings:
        """The settings resolved (``sim.engine.solvers.resolved_settings``) after every value of the job is
        checked; DartsInputError naming the first bad one, and every output checked writable."""
        settings = resolved_settings(self.settings)
        from darts.dart.model import MATERIALS, parse_seam_setting

        if self.material is not None and self.material not in MATERIALS:
            raise DartsInputError(None, f"unknown material '{self.material}' (one of {', '.join(sorted(MATERIALS))})")
        for text in self.seams:
            parse_seam_setting(text)
        self._check_outputs()
        return settings

    def _check_outputs(self) -> None:
        if self.output is not None:
            out = Path(self.output)
            if out.suffix and out.suffix.lower() not in USD_SUFFIXES:
                raise DartsInputError(out, f"output must end in {', '.join(USD_SUFFIXES)} or be a directory (no suffix)")
            check_output(out, directory=not out.suffix)
        if self.stats is not None:
            check_output(self.stats)
        if self.preview is not None:
            from darts.preview import check_preview

            check_preview(self.preview)

    def to_dict(self) -> dict:
        """The job as JSON-able values (garment, motion and body given as names or paths)."""
        values = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "settings"}
        if isinstance(self.garment, (list, tuple)):
            values["garment"] = [str(g) for g in self.garment]
        values["betas"] = None if self.betas is None else [float(b) for b in self.betas]
        values["seams"] = list(self.seams)
        return {**{k: str(v) if isinstance(v, os.PathLike) else v for k, v in values.items()},
                "settings": asdict(self.settings)}

    @classmethod
    def from_dict(cls, values: dict) -> SimJob:
        """The inverse of ``to_dict`` (a DartsInputError naming a missing or unknown key, or a bad value)."""
        values = check.mapping(values, "job", [f.name for f in fields(cls)], "SimJob's fields")
        missing = [name for name in ("garment", "motion") if name not in values]
        if missing:
            raise DartsInputError(None, f"job: '{missing[0]}' is missing")
        return cls(**values)


def settings_of(value) -> SimSettings:
    """``value`` as ``SimSettings``: itself, or a dict of its fields (unknown ones named)."""
    if isinstance(value, SimSettings):
        return value
    return SimSettings(**check.mapping(value, "settings", [f.name for f in fields(SimSettings)], "SimSettings fields"))


def _check_object(value, argument: str, module: str, kind: str, what: str) -> None:
    """``value`` is a path or an instance of ``module.kind`` (imported only when ``value`` is an
    object, so that checking a path loads neither torch nor Warp)."""
    if not check.is_path(value):
        import importlib

        check.path_or(value, argument, (getattr(importlib.import_module(module), kind),), what)


@dataclass
class Simulated:
    """A finished run. ``garment`` [F,V,3] and ``body`` [F,B,3] are the recorded frames (world frame,
    Z up, metres; None unless kept), ``garment_faces`` and ``body_faces`` their triangles (an
    outfit's garments one after the other: ``garment_slices[k]`` are garment ``garment_names[k]``'s
    vertices), ``stats``
    the ``--stats`` document (settings, totals, per-frame strain, penetration, seam gaps ...);
    ``stable`` False: the run stopped at ``message`` and the frames before it are what it kept."""

    garment: np.ndarray | None
    body: np.ndarray | None
    garment_faces: np.ndarray
    body_faces: np.ndarray
    fps: float
    stats: dict
    stable: bool
    message: str
    garment_names: list[str] = field(default_factory=lambda: ["garment"])
    garment_slices: list[slice] = field(default_factory=list)

    @property
    def exit_code(self) -> int:
        return 0 if self.stable else UNSTABLE_EXIT


def simulate(garment, motion, settings: SimSettings | None = None, *, keep_frames: bool = True,
             progress: bool = False, **options) -> Simulated:
    """Simulate ``garment`` on the body posed by ``motion`` (see ``SimJob`` for ``options``: start,
    end, frames, settle, body, betas, material, seams, output, format, stats, preview ...).

    >>> run = simulate("short-sleeve-top", "walk", frames=10)
    >>> run.garment.shape  # (10, vertices, 3), metres, Z up
    """
    known = [f.name for f in fields(SimJob) if f.name not in ("garment", "motion", "settings")]
    unknown = [name for name in options if name not in known]
    if unknown:
        raise DartsInputError(None, f"simulate: unknown option '{unknown[0]}' (options: {', '.join(known)})")
    job = SimJob(garment, motion, settings if settings is not None else SimSettings(), **options)
    return run_job(job, keep_frames=keep_frames, progress=progress)


def _frame_range(job: SimJob, count: int) -> tuple[int, int]:
    end = job.end if job.end is not None else count
    if job.frames is not None:
        end = job.start + job.frames
        if end > count and job.start < count:  # asked for more than the motion has: say so, do not cut it short
            raise DartsInputError(None, f"frames {job.frames} from frame {job.start} run past the motion's end: it has "
                                        f"{count} frames at {job.settings.fps:g} fps, {count - job.start} left from there")
    if not 0 <= job.start < end <= count:
        raise DartsInputError(None, f"frame range [{job.start}, {end}) is empty or outside the motion's {count} frames "
                                    f"at {job.settings.fps:g} fps")
    return job.start, end


@dataclass
class _Dressing:
    """The garments of a job (one, or an outfit's, inner first) and their names (``garment`` for a
    lone garment, as darts-sim has always written it; ``sim.outfit.garment_names`` in an outfit)."""

    darts: list
    names: list[str]

    @property
    def slices(self) -> list[slice]:
        ends = np.cumsum([0] + [len(d.vertices) for d in self.darts])
        return [slice(a, b) for a, b in zip(ends[:-1], ends[1:])]

    @property
    def faces(self) -> np.ndarray:
        """Every garment's triangles, indexing the garments' vertices one after the other."""
        return np.concatenate([d.faces + s.start for d, s in zip(self.darts, self.slices)])

    def colors(self, dart) -> np.ndarray:
        from darts.dart.export import panel_colors

        return panel_colors(len(dart.panel_names))[dart.panel]


def _load_garments(job: SimJob) -> _Dressing:
    from darts.api import load_garment
    from darts.dart.model import MATERIALS, Dart, parse_seam_setting
    from darts.outfit_folder import outfit_garments
    from sim.outfit import garment_names

    given = list(job.garment) if isinstance(job.garment, (list, tuple)) else [job.garment]
    # An outfit folder (darts reconstruct PHOTO -o OUT_DIR) stands for its garments, inner layer first.
    given = [part for g in given for part in
             (outfit_garments(g) if isinstance(g, (str, os.PathLike)) and Path(g).is_dir() else [g])]
    if not given:
        raise DartsInputError(None, "no garment given")
    # A shallow copy is enough: material and seams are replaced below, never changed in place.
    darts = [replace(g) if isinstance(g, Dart) else load_garment(g) for g in given]
    labels = [g.category if isinstance(g, Dart) else Path(str(g)).stem for g in given]
    names = garment_names(labels) if len(darts) > 1 else ["garment"]
    for dart in darts:
        if job.material is not None:
            dart.material_name, dart.material = job.material, dict(MATERIALS[job.material])
    for text in job.seams:
        name, regime, stiffness = parse_seam_setting(text)
        owner, _, seam = name.rpartition("/")
        if owner and owner not in names:
            raise DartsInputError(None, f"seam setting '{text}': no garment '{owner}' (garments: {', '.join(names)})")
        chosen = [d for d, n in zip(darts, names) if n == owner or (not owner and (seam == "all" or seam in d.seam_names))]
        if owner and seam != "all" and seam not in chosen[0].seam_names:
            raise DartsInputError(None, f"seam setting '{text}': {owner} has no seam '{seam}' "
                                        f"(its seams: {', '.join(chosen[0].seam_names)})")
        if not chosen and len(darts) > 1:
            raise DartsInputError(None, f"seam setting '{text}': no garment of the outfit has a seam '{seam}' ("
                                        + "; ".join(f"{n}: {', '.join(d.seam_names)}" for d, n in zip(darts, names)) + ")")
        if not chosen:
            darts[0].seam(seam)  # the garment has no such seam: the error names the seams it has
        for dart in chosen:
            dart.set_seam(seam, regime, stiffness)
    return _Dressing(darts, names)


def _load_motion(job: SimJob):
    from darts.api import load_motion

    motion = load_motion(job.motion, job.settings.fps)
    start, end = _frame_range(job, motion.num_frames)
    return motion.with_frames(trans=motion.trans[start:end], **{name: arr[start:end] for name, arr in motion.parts().items()})


def _shape(job: SimJob, dart, body) -> tuple[np.ndarray, np.ndarray]:
    """(the DART's own betas, the betas to simulate on), checked against the body: a DART made for
    another body model (``Dart.body_model`` against the body's name) is refused, not draped on a
    body it was not cut for."""
    source = job.garment if isinstance(job.garment, (str, os.PathLike)) else None
    name = getattr(body, "name", None)
    if name and dart.body_model and dart.body_model != name:
        raise DartsInputError(source, f"was made for the body '{dart.body_model}', and the run's body is '{name}': "
                                      "give --body the file it was made on")
    own = np.asarray(dart.body_betas, np.float64)
    if len(own) > body.num_betas:
        raise DartsInputError(job.garment if isinstance(job.garment, (str, os.PathLike)) else None,
                              f"was made for {len(own)} shape coefficients, the body has {body.num_betas}")
    if job.betas is None:
        return own, own
    return own, check.betas(job.betas, body.num_betas)


def check_device(device: str) -> None:
    from darts.geometry.warp_runtime import warp

    wp = warp()
    if device not in [str(d) for d in wp.get_devices()] and not (device == "cuda" and wp.is_cuda_available()):
        raise DartsInputError(None, f"Warp device '{device}' is not available here (devices: "
                              f"{', '.join(str(d) for d in wp.get_devices())})")


class _Frames:
    """What the run's consumers get of every recorded frame: the writer, the frames a preview draws,
    and (``keep``) every frame for the caller (float32)."""

    def __init__(self, job: SimJob, track, keep: bool):
        from darts.preview import frames_to_draw

        total = len(track.vertices) - track.settle_frames
        self.drawn = set(frames_to_draw(total, job.preview).tolist()) if job.preview else set()
        self.keep, self.writer, self.parts = keep, None, []
        self.seen, self.numbers, self.garment, self.body = 0, [], [], []

    def __call__(self, garment: np.ndarray, body: np.ndarray) -> None:
        if self.writer is not None:
            self.writer.write_frame({"body": body, **{name: garment[part] for name, part in self.parts}})
        if self.keep or self.seen in self.drawn:
            self.numbers.append(self.seen)
            self.garment.append(garment.astype(np.float32))
            self.body.append(body.astype(np.float32))
        self.seen += 1

    def render_preview(self, job: SimJob, dressing: _Dressing, track, progress: bool) -> None:
        from darts.preview import Animation, render_preview

        drawn = [i for i, n in enumerate(self.numbers) if n in self.drawn]
        animation = Animation(faces={"body": np.asarray(track.faces), "garment": dressing.faces},
                              colors={"body": np.full((len(track.faces), 3), 0.8),
                                      "garment": np.concatenate([dressing.colors(d) for d in dressing.darts])},
                              frames={"garment": np.stack([self.garment[i] for i in drawn]),
                                      "body": np.stack([self.body[i] for i in drawn])},
                              fps=job.settings.fps, numbers=np.array([self.numbers[i] for i in drawn]), total=self.seen)
        render_preview(animation, job.preview, progress=progress)


def _writer(job: SimJob, dressing: _Dressing, track):
    """The output writer with the body (grey) and each garment (coloured by panel) declared."""
    from exporters.sequence import MeshSequenceWriter
    from exporters.usd import UsdAnimationWriter

    out = Path(job.output)
    writer = UsdAnimationWriter(out, job.settings.fps) if out.suffix else MeshSequenceWriter(out, job.settings.fps, job.format)
    writer.add_mesh("body", track.faces, track.vertices.shape[1], np.full((len(track.faces), 3), 0.8))
    for name, dart in zip(dressing.names, dressing.darts):
        writer.add_mesh(name, dart.faces, len(dart.vertices), dressing.colors(dart))
        if job.seam_curves and len(dart.pairs):
            writer.add_curves(name, dart.pairs)
    return writer


class _NothingToKeep(Exception):
    """The run went unstable before its first recorded frame: no output is written."""

    def __init__(self, result):
        super().__init__(result.message)
        self.result = result


@dataclass
class _Prepared:
    """A checked, loaded job ready to step: its settings (resolved), garments (a DART or an
    ``Outfit``), body track, and what its recorded frames go to."""

    job: SimJob
    settings: SimSettings
    dressing: _Dressing
    garments: object
    track: object
    frames: _Frames

    @property
    def winding(self) -> bool:
        """Whether to measure by winding number: as asked, else when stats are written."""
        return self.job.winding if self.job.winding is not None else self.job.stats is not None

    def writer(self):
        """The job's output writer (None without an output), its frames routed to it."""
        self.frames.writer = _writer(self.job, self.dressing, self.track) if self.job.output is not None else None
        return self.frames.writer


def _prepare(job: SimJob, keep_frames: bool, progress: bool) -> _Prepared:
    """Check every input and output of ``job``, load its garments, motion and body, pose the body."""
    from darts.api import load_body
    from sim.body_track import build_body_track

    if not isinstance(job, SimJob):
        raise check.refuse("job", "a SimJob", job)
    settings = job.check()
    dressing = _load_garments(job)
    motion = _load_motion(job)
    body = load_body(job.body)
    if settings.device != "cpu":
        check_device(settings.device)
    own, target = _shape(job, dressing.darts[0], body)
    garments = dressing.darts[0]
    if len(dressing.darts) > 1:
        from sim.outfit import outfit_model

        garments = outfit_model(dressing.darts, dressing.names, body.shaped(own)[0][0].double().numpy(), body.faces)
    track = build_body_track(body, motion, settings.fps, job.settle, betas=target, start_betas=own, progress=progress,
                             gap=settings.body_gap)
    frames = _Frames(job, track, keep_frames)
    frames.parts = list(zip(dressing.names, dressing.slices))
    return _Prepared(job, settings, dressing, garments, track, frames)


def _finish(prepared: _Prepared, result, keep_frames: bool, progress: bool) -> Simulated:
    """The job's preview and stats written, and what it returns."""
    from sim.run import summary

    job, frames, dressing, track, settings = (prepared.job, prepared.frames, prepared.dressing, prepared.track,
                                              prepared.settings)
    if job.preview and result.frames:
        frames.render_preview(job, dressing, track, progress)
    stats = summary(result, sum(len(d.vertices) for d in dressing.darts))
    if job.stats:
        with atomic_path(job.stats) as tmp:
            Path(tmp).write_text(json.dumps(stats, indent=1))
    kept = keep_frames and bool(frames.garment)
    return Simulated(garment=np.stack(frames.garment) if kept else None, body=np.stack(frames.body) if kept else None,
                     garment_faces=dressing.faces, body_faces=np.asarray(track.faces), fps=settings.fps, stats=stats,
                     stable=result.stable, message=result.message, garment_names=dressing.names,
                     garment_slices=dressing.slices)


def run_job(job: SimJob, keep_frames: bool = True, progress: bool = False) -> Simulated:
    """Check every input and output of ``job``, simulate, write its output, stats and preview."""
    from contextlib import nullcontext

    from sim.run import simulate as run_frames

    keep_frames, progress = check.switch(keep_frames, "keep_frames"), check.switch(progress, "progress")
    prepared = _prepare(job, keep_frames, progress)
    try:
        with prepared.writer() or nullcontext():
            result = run_frames(prepared.garments, prepared.track, prepared.settings, prepared.frames, progress=progress,
                                winding=prepared.winding, measure_every=job.measure_every)
            if not result.frames:
                raise _NothingToKeep(result)
    except _NothingToKeep as nothing:
        result = nothing.result
    return _finish(prepared, result, keep_frames, progress)


def _check_distinct_outputs(jobs: Sequence[SimJob]) -> None:
    """No two jobs write the same file (output, stats or preview): a DartsInputError naming it."""
    seen = {}
    for index, job in enumerate(jobs):
        for name in ("output", "stats", "preview"):
            path = getattr(job, name, None) if isinstance(job, SimJob) else None
            if path is None:
                continue
            key = os.path.abspath(path)
            if key in seen:
                raise DartsInputError(path, f"is written by job {seen[key]} and job {index}: give each job its own files")
            seen[key] = index


def simulate_many(jobs: Sequence[SimJob], keep_frames: bool = True, progress: bool = False,
                  worlds: int | None = None) -> list[Simulated]:
    """Run ``jobs`` as many worlds of one solver (``sim.worlds``): their particles, constraints and
    bodies side by side in the same arrays, each job its own garments, motion and body shape, no
    contact between jobs; each job's ``Simulated``, outputs, stats and preview as ``run_job`` gives
    them. Every job is checked before any runs. Jobs that cannot share a solver (other settings,
    another cloth thickness or friction, other measuring) run in separate solvers, in order of their
    first job; ``worlds``: at most this many jobs per solver (default: all that can share one).
    A job that goes unstable stops there with its good frames, and the others go on."""
    from sim.worlds import World, simulate_grouped

    if isinstance(jobs, SimJob) or not isinstance(jobs, Sequence):
        raise check.refuse("jobs", "a list of SimJobs", jobs)
    keep_frames, progress = check.switch(keep_frames, "keep_frames"), check.switch(progress, "progress")
    worlds = check.optional_number(worlds, "worlds", 1, whole=True)
    _check_distinct_outputs(jobs)
    prepared = [_prepare(job, keep_frames, progress) for job in jobs]
    writers = []
    try:
        writers.extend(p.writer() for p in prepared)
        results = simulate_grouped([World(p.garments, p.track, p.frames, p.settings, p.winding, p.job.measure_every)
                                    for p in prepared], size=worlds, progress=progress)
    except BaseException:
        for writer in writers:
            if writer is not None:
                writer.discard()
        raise
    done = []
    for p, writer, result in zip(prepared, writers, results):
        if writer is not None:
            writer.close() if result.frames else writer.discard()
        done.append(_finish(p, result, keep_frames, progress))
    return done
