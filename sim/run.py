"""One simulation run: a DART on a body track, frame by frame, with per-frame measurements.

Frames handed to ``sink`` and measured are the recorded ones (after the settle period), in the
world frame (Z up, metres). Seam gaps are measured on the DART's own vertices (both ends of every
pair), penetration on the solver's particles. An outfit (``sim.outfit.Outfit``) runs the same way:
``sink`` gets its garments' vertices one after the other, and each frame adds every garment's own
measures and, with ``winding``, the layer order (``sim.outfit.layer_order``: under an inner garment's
cloth, and inside its closed surface).
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from darts.dart.model import Dart
from darts.interrupts import raise_if_interrupted
from sim.body_track import BodyTrack
from sim.engine.model import ClothModel, cloth_model
from sim.engine.settings import SimSettings
from sim.engine.simulation import FrameMeasure, Simulation
from sim.outfit import Outfit, layer_crossings, layer_order
from sim.quality import WaistSlide, edge_strain, strain_summary, waist_slide


@dataclass
class RunResult:
    """What a run measured; ``stable`` False means it stopped at ``message`` keeping the frames before."""

    frames: list[dict] = field(default_factory=list)
    stable: bool = True
    message: str = ""
    wall_seconds: float = 0.0
    simulated_frames: int = 0
    particles: int = 0
    settings: SimSettings | None = None  # what the run stepped with (the solver's substeps filled in)


def seam_gap_stats(dart: Dart, vertices: np.ndarray) -> dict[str, dict[str, float]]:
    """Per seam: mean and max gap (m) over its pairs; partial seams add ``sprung_max`` and
    ``open_mean``, the gaps on the sprung and unsprung parts."""
    stats = dart.seam_gaps(vertices)
    gaps = np.linalg.norm(vertices[dart.pairs[:, 0]] - vertices[dart.pairs[:, 1]], axis=1)
    active = dart.pair_active
    for index, seam in enumerate(dart.seams):
        if seam.regime == "partial":
            mine = dart.pair_seam == index
            sprung, open_ = gaps[mine & active], gaps[mine & ~active]
            stats[seam.name]["sprung_max"] = float(sprung.max()) if len(sprung) else 0.0
            stats[seam.name]["open_mean"] = float(open_.mean()) if len(open_) else 0.0
    return stats


def _garment_measures(dart: Dart, vertices: np.ndarray, body: np.ndarray, slide: WaistSlide | None) -> dict:
    """One garment's waist slide (m, ``sim.quality.WaistSlide``; None without a waist line) on the
    body at ``body`` [B,3], and its seam gaps."""
    return {"waist_slide": None if slide is None else slide(vertices, body), "seam_gap": seam_gap_stats(dart, vertices)}


def _layer_strain(model: ClothModel, strain: np.ndarray, layer: int) -> dict[str, float]:
    return strain_summary(strain[model.layer[model.edges[:, 0]] == layer])


def _layer_measures(outfit: Outfit, particles: np.ndarray, track: BodyTrack, k: int, winding: bool) -> dict:
    """An outfit frame's layer order (``layers``: under an inner garment's cloth; ``layers_closed``:
    inside its closed surface; None without ``winding``) and crossing edges between the garments."""
    under, inside = layer_order(outfit, particles, track.vertices[k], track.faces) if winding else (None, None)
    return {"layers": under, "layers_closed": inside, "layer_crossings": layer_crossings(outfit, particles)}


class JobRecorder:
    """One job's side of the frame loop: which measures each frame needs, whether the run is still
    stable, and every recorded frame's measures (``RunResult.frames``), handed to ``sink``.

    ``garments`` is a DART or an ``Outfit`` on ``track``; particles are given in the job's own world
    frame. Frames ``k`` count from the track's first (the settle blend's); the measures that query the
    body or the garment are taken on every ``measure_every``-th recorded frame and the last."""

    def __init__(self, garments: Dart | Outfit, model: ClothModel, track: BodyTrack, settings: SimSettings,
                 sink: Callable[[np.ndarray, np.ndarray], None] | None, winding: bool, measure_every: int):
        self.garments, self.model, self.track, self.settings = garments, model, track, settings
        self.outfit = garments if isinstance(garments, Outfit) else None
        self.sink, self.winding, self.measure_every = sink, winding, measure_every
        self.result = RunResult(particles=len(model.rest), settings=settings)
        self.previous = None  # the particles at the last frame, settle or recorded
        self.slides = None  # each garment's WaistSlide (None without a waist line), from the first recorded frame

    @property
    def total(self) -> int:
        """Frames of the track, the settle blend's included."""
        return len(self.track.vertices)

    def wants(self, k: int) -> tuple[bool, bool]:
        """(the body and garment queries, the winding-number ones) at frame ``k``."""
        recorded = k - self.track.settle_frames
        full = recorded >= 0 and (recorded % self.measure_every == 0 or k == self.total - 1)
        return full, self.winding and full

    def stopped(self, k: int, measure: FrameMeasure, diagnose: Callable[[], str]) -> bool:
        """True (and the run's message set) when frame ``k`` has a non-finite value or a particle
        faster than ``settings.max_speed``; ``diagnose()`` says where it starts."""
        limit = self.settings.max_speed
        if measure.finite and measure.max_speed <= limit:
            return False
        phase, index = ("settle", k) if k < self.track.settle_frames else ("frame", k - self.track.settle_frames)
        what = "a non-finite position or velocity" if not measure.finite else f"a particle at {measure.max_speed:.1f} m/s"
        self.result.stable = False
        self.result.message = (f"unstable at {phase} {index}: {what} (limit {limit:g} m/s); {diagnose()}; "
                               f"kept the {len(self.result.frames)} good frames before it")
        return True

    def take(self, k: int, particles: np.ndarray, measure: FrameMeasure) -> None:
        """Frame ``k``'s particles [P,3] (world frame) and measure (its queries kept where ``wants``
        asked for them): a settle frame is only remembered, a recorded one measured and sunk."""
        full, winding = self.wants(k)
        if not full:
            measure = replace(measure, penetration=None, penetration_in_body_overlap=None, self_intersections=None)
        if not winding:
            measure = replace(measure, penetration_winding=None, penetration_winding_in_body_overlap=None)
        previous, self.previous = self.previous, particles
        if k < self.track.settle_frames:
            return
        model, outfit, garments, fps = self.model, self.outfit, self.garments, self.settings.fps
        # the recorded frames' largest speed: each particle's displacement since the last frame
        frame_speed = 0.0 if previous is None else float(np.linalg.norm(particles - previous, axis=1).max()) * fps
        vertices = particles[model.particle_of_vertex]
        body = self.track.vertices[k]
        if self.slides is None:  # the first recorded frame: the settled waistbands are tied to the skin
            faces = self.track.faces
            self.slides = ([waist_slide(garments, vertices, body, faces)] if outfit is None else
                           [waist_slide(dart, part, body, faces) for dart, part in zip(outfit.darts, outfit.split(vertices))])
        strain = edge_strain(model, particles)
        frame = {"strain": strain_summary(strain), "penetration": measure.penetration,
                 "penetration_in_body_overlap": measure.penetration_in_body_overlap,
                 "penetration_winding": measure.penetration_winding,
                 "penetration_winding_in_body_overlap": measure.penetration_winding_in_body_overlap,
                 "max_speed": measure.max_speed, "max_substep_speed": measure.max_substep_speed,
                 "frame_speed": frame_speed, "self_intersections": measure.self_intersections}
        if outfit is None:
            frame.update(_garment_measures(garments, vertices, body, self.slides[0]))
        else:
            each = {name: {"strain": _layer_strain(model, strain, layer), **_garment_measures(dart, part, body, slide)}
                    for layer, (name, dart, part, slide) in enumerate(zip(outfit.names, outfit.darts,
                                                                           outfit.split(vertices), self.slides))}
            waists = [g["waist_slide"] for g in each.values() if g["waist_slide"] is not None]
            frame.update(waist_slide=waists[0] if waists else None, garments=each,
                         seam_gap={f"{name}/{seam}": gap for name, g in each.items() for seam, gap in g["seam_gap"].items()},
                         **(_layer_measures(outfit, particles, self.track, k, self.winding) if full else
                            {"layers": None, "layers_closed": None, "layer_crossings": None}))
        self.result.frames.append(frame)
        if self.sink is not None:
            self.sink(vertices, body)


def job_model(garments: Dart | Outfit) -> ClothModel:
    """The solver's model of a DART, or an outfit's joined one."""
    return garments.model if isinstance(garments, Outfit) else cloth_model(garments)


def simulate(garments: Dart | Outfit, track: BodyTrack, settings: SimSettings,
             sink: Callable[[np.ndarray, np.ndarray], None] | None = None, progress: bool = False,
             winding: bool = False, measure_every: int = 1) -> RunResult:
    """Drape ``garments`` (a DART, or an outfit of several) from the rest pose through ``track``;
    ``sink(garment [V,3], body [B,3])`` gets every recorded frame; ``winding``: also measure
    penetration by the body's winding number (and an outfit's layer order). Stops early
    (``stable`` False) on a non-finite value or a particle faster than ``settings.max_speed``, which
    every frame checks. The measures that query the body or the garment (penetration, crossing
    edges, an outfit's layer order) are taken on every ``measure_every``-th recorded frame and the
    last (None on the others; the run's maxima over those frames); strain, seam gaps, the waist and
    the speeds on every frame."""
    from tqdm import tqdm

    model = job_model(garments)
    solver = Simulation(model, track.place_rest(model.rest), track.faces, track.vertices[0], settings, track.parts)
    recorder = JobRecorder(garments, model, track, solver.settings, sink, winding, measure_every)
    result = recorder.result
    start = time.perf_counter()
    bar = tqdm(total=recorder.total - 1, unit="frame", desc="simulating", disable=not progress, leave=False)
    for k in range(recorder.total):
        if k > 0:
            raise_if_interrupted()
            solver.step_frame(track.vertices[k])
            result.simulated_frames += 1
            bar.update(1)
        full, wind = recorder.wants(k)
        measure = solver.measure(winding=wind, bodies=full)
        if recorder.stopped(k, measure, solver.diagnose):
            break
        recorder.take(k, solver.positions(), measure)
    bar.close()
    result.wall_seconds = time.perf_counter() - start
    return result


def summary(result: RunResult, vertices: int) -> dict:
    """The ``--stats`` document: run settings, totals and every frame's measurements."""
    frames, settings = result.frames, result.settings
    measured = [f for f in frames if f["penetration"] is not None]  # the frames the body was queried on
    seams = frames[0]["seam_gap"].keys() if frames else []
    return {
        "vertices": vertices, "particles": result.particles, "solver": settings.solver,
        "substeps": settings.substeps, "iterations": settings.iterations, "fps": settings.fps,
        "wall_seconds": result.wall_seconds, "simulated_frames": result.simulated_frames,
        "sim_fps": result.simulated_frames / result.wall_seconds if result.wall_seconds > 0 else 0.0,
        "stable": result.stable, "message": result.message,
        "max_penetration": max((f["penetration"] for f in measured), default=0.0),
        "max_penetration_outside_body_overlap": max((f["penetration"] - f["penetration_in_body_overlap"] for f in measured),
                                                    default=0.0),
        "max_penetration_winding": max((f["penetration_winding"] for f in measured), default=0.0)
        if measured and measured[0]["penetration_winding"] is not None else None,
        "max_penetration_winding_outside_body_overlap": max(
            (f["penetration_winding"] - f["penetration_winding_in_body_overlap"] for f in measured), default=0.0)
        if measured and measured[0]["penetration_winding"] is not None else None,
        "measured_frames": len(measured),
        "max_speed": max((f["max_speed"] for f in frames), default=0.0),
        # cloth buzzing between contacts: the substeps' largest speed against the recorded frames'
        "max_substep_speed": max((f["max_substep_speed"] for f in frames), default=0.0),
        "max_frame_speed": max((f["frame_speed"] for f in frames), default=0.0),
        "max_self_intersections": max((f["self_intersections"] for f in measured), default=0),
        "strain_mean": float(np.mean([f["strain"]["mean"] for f in frames])) if frames else 0.0,
        "strain_p99": max((f["strain"]["p99"] for f in frames), default=0.0),
        "strain_max": max((f["strain"]["max"] for f in frames), default=0.0),
        "max_waist_slide": max((f["waist_slide"] for f in frames), default=None)
        if frames and frames[0]["waist_slide"] is not None else None,
        "self_contact": settings.self_contact,
        "max_seam_gap": {s: max(f["seam_gap"][s]["max"] for f in frames) for s in seams},
        **_outfit_summary(frames),
        "frames": frames,
    }


def _outfit_summary(frames: list[dict]) -> dict:
    """An outfit's totals: per garment its strain and largest seam gap, and the largest fraction of
    each outer garment under an inner one's cloth and inside its closed surface over the run (None
    unless measured)."""
    if not frames or "garments" not in frames[0]:
        return {}
    names = list(frames[0]["garments"])
    measured = [f for f in frames if f["layer_crossings"] is not None]
    layers = measured[0]["layers"] if measured else None
    return {
        "garments": {name: {"strain_mean": float(np.mean([f["garments"][name]["strain"]["mean"] for f in frames])),
                            "strain_max": max(f["garments"][name]["strain"]["max"] for f in frames),
                            "max_seam_gap": max((g["max"] for f in frames for g in f["garments"][name]["seam_gap"].values()),
                                                default=0.0)}
                     for name in names},
        "max_layer_inside": None if layers is None else {pair: max(f["layers"][pair] for f in measured) for pair in layers},
        "max_layer_inside_closed": None if layers is None else {pair: max(f["layers_closed"][pair] for f in measured)
                                                                for pair in layers},
        "max_layer_crossings": {pair: max(f["layer_crossings"][pair] for f in measured)
                                for pair in (measured[0]["layer_crossings"] if measured else {})},
    }
