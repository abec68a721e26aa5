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
from dataclasses import dataclass, field

import numpy as np

from darts.dart.model import Dart
from darts.interrupts import raise_if_interrupted
from sim.body_track import BodyTrack
from sim.engine.model import ClothModel, cloth_model
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
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

    outfit = garments if isinstance(garments, Outfit) else None
    model = outfit.model if outfit is not None else cloth_model(garments)
    solver = Simulation(model, track.place_rest(model.rest), track.faces, track.vertices[0], settings, track.parts)
    result = RunResult(particles=len(model.rest), settings=solver.settings)
    total = len(track.vertices)
    start = time.perf_counter()
    bar = tqdm(total=total - 1, unit="frame", desc="simulating", disable=not progress, leave=False)
    previous = None  # the particles at the last frame, settle or recorded
    slides = None  # each garment's WaistSlide (None without a waist line), from the first recorded frame
    for k in range(total):
        if k > 0:
            raise_if_interrupted()
            solver.step_frame(track.vertices[k])
            result.simulated_frames += 1
            bar.update(1)
        recorded = k - track.settle_frames  # the recorded frame's number (negative in the settle)
        full = recorded >= 0 and (recorded % measure_every == 0 or k == total - 1)
        measure = solver.measure(winding=winding and full, bodies=full)
        phase = "settle" if k < track.settle_frames else "frame"
        index = k if k < track.settle_frames else k - track.settle_frames
        if not measure.finite or measure.max_speed > settings.max_speed:
            what = "a non-finite position or velocity" if not measure.finite else f"a particle at {measure.max_speed:.1f} m/s"
            result.stable = False
            result.message = (f"unstable at {phase} {index}: {what} (limit {settings.max_speed:g} m/s); "
                              f"{solver.diagnose()}; kept the {len(result.frames)} good frames before it")
            break
        if k < track.settle_frames:
            previous = solver.positions()
            continue
        particles = solver.positions()
        # the recorded frames' largest speed: each particle's displacement since the last frame
        frame_speed = 0.0 if previous is None else float(np.linalg.norm(particles - previous, axis=1).max()) * settings.fps
        previous = particles
        vertices = particles[model.particle_of_vertex]
        body = track.vertices[k]
        if slides is None:  # the first recorded frame: the settled waistbands are tied to the skin
            slides = ([waist_slide(garments, vertices, body, track.faces)] if outfit is None else
                      [waist_slide(dart, part, body, track.faces) for dart, part in zip(outfit.darts, outfit.split(vertices))])
        strain = edge_strain(model, particles)
        frame = {"strain": strain_summary(strain), "penetration": measure.penetration,
                 "penetration_in_body_overlap": measure.penetration_in_body_overlap,
                 "penetration_winding": measure.penetration_winding,
                 "penetration_winding_in_body_overlap": measure.penetration_winding_in_body_overlap,
                 "max_speed": measure.max_speed, "max_substep_speed": measure.max_substep_speed,
                 "frame_speed": frame_speed, "self_intersections": measure.self_intersections}
        if outfit is None:
            frame.update(_garment_measures(garments, vertices, body, slides[0]))
        else:
            each = {name: {"strain": _layer_strain(model, strain, layer), **_garment_measures(dart, part, body, slide)}
                    for layer, (name, dart, part, slide) in enumerate(zip(outfit.names, outfit.darts,
                                                                           outfit.split(vertices), slides))}
            waists = [g["waist_slide"] for g in each.values() if g["waist_slide"] is not None]
            frame.update(waist_slide=waists[0] if waists else None, garments=each,
                         seam_gap={f"{name}/{seam}": gap for name, g in each.items() for seam, gap in g["seam_gap"].items()},
                         **(_layer_measures(outfit, particles, track, k, winding) if full else
                            {"layers": None, "layers_closed": None, "layer_crossings": None}))
        result.frames.append(frame)
        if sink is not None:
            sink(vertices, body)
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
