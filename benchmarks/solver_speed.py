"""Speed and quality of solver settings, against a baseline run in the same process, on several scenes.

    python benchmarks/solver_speed.py [--scenes GARMENT:MOTION ...] [--frames N] [--configurations NAME ...]
                                      [--variant KEY=VALUE[,KEY=VALUE ...] ...] [--profile] [--perturbed N]
                                      [--out docs/data/benchmark_solver.json]

Scenes (issue 30): the 6k short-sleeve top on the walk (30 frames after the settle), the short
skirt and the long pants on the walk and the squat (the whole motion), on the default body at 30 fps
after the 0.5 s settle, world frame Z up, metres. In each scene every configuration steps the same
frames, the configurations alternated frame by frame in one process; only
``Simulation.step_frame`` is timed, by CPU time (``time.process_time``; after one untimed frame that
compiles the kernels), on one core (Warp's CPU backend runs a launch on one thread). Quality over
the recorded frames, measured the same way for every configuration: edge strain (``sim.quality``:
mean over edges and frames, the largest 99th percentile and max of a frame), penetration by the
closest point's sign and by the body's winding number (largest fraction of particles inside over
the frames), the largest gap of a stiff seam (m), and the most garment edges passing through a
garment triangle in a frame. The first configuration is the baseline (the default when issue 30 was
filed); ``ratio`` is each one's speed over it. The time of building the tethers (once per run, a few
seconds) is not in the frame rate. ``--profile`` adds where the time of the last configuration goes
(cProfile, cumulative seconds per frame of the solver's pieces). Penetration, the largest strain and
the crossings are chaotic (a micrometre at the start moves them by tens of per cent at the end of a
walk): ``--perturbed N`` runs every configuration N more times from start positions moved by a
micrometre and reports each measure's spread, so that a difference can be told from that noise.
``--variant untangle_step=0`` adds a row of the default with those ``SimSettings`` fields changed
(named by its text; after the ``--configurations`` rows), so that a knob is measured against the
default without editing this file.
"""
from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import time
from dataclasses import fields
from pathlib import Path

import numpy as np

from darts.body.io import load_body
from darts.dart.io import load_dart
from darts.errors import DartsInputError
from darts.motion.amass import load_motion
from darts.shipped import resolve_garment, resolve_motion
from sim.body_track import build_body_track
from sim.engine.model import cloth_model
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
from sim.quality import edge_strain

#: The scenes of issue 30: the 6k top on the walk, a skirt and pants on the walk and the squat.
SCENES = ("short-sleeve-top:walk", "short-skirt:walk", "short-skirt:squat", "long-pants:walk", "long-pants:squat")
#: The default when issue 30 was filed: self-contact searched every 2 substeps within 1 cm, every
#: particle searching the BVH at every search (no lists), every kernel launched from Python.
ISSUE_30_DEFAULT = dict(solver="xpbd", substeps=20, iterations=2, self_contact_interval=2, self_contact_reach=0.01,
                        self_contact_list_reach=0.0, replay_launches=False)
CONFIGURATIONS = {
    ("issue 30's default: xpbd 20x2, tethers, 5 mm skin, self-contact searched every 2 substeps within 1 cm, "
     "launches from Python"): ISSUE_30_DEFAULT,
    "self-contact searched every 2 substeps within 2 mm + travel, broad phase every 10 substeps": dict(self_contact_interval=2),
    "the same with bending every 2 substeps": dict(self_contact_interval=2, bending_interval=2),
    "the default with every launch from Python": dict(replay_launches=False),
    "default: searched every 4 substeps within 2 mm + travel, broad phase every 10 substeps, launches replayed": {},
    # A lead, not the default (issue 30): small steps, 25 x 1 (better seams and penetration, more strain),
    # with the surface tethers trimmed by 1 % (less strain); self-contact searched as often in time.
    ("small steps: xpbd 25x1, bending and body search every 2 substeps, self-contact every 5, broad phase every 12, "
     "tethers x 0.99"):
        dict(substeps=25, iterations=1, bending_interval=2, contact_interval=2, self_contact_interval=5,
             self_contact_broad_interval=12, tether_scale=0.99),
}
#: Functions whose cumulative time is the profile's rows (qualified name suffixes).
PROFILE_ROWS = {
    "body contact search and tracking": "collider.py:update",
    "self-contact search (candidate lists, search, edges)": "self_contact.py:search",
    "constraint sweeps, contact projection, friction, velocities (one captured block)": "launch.py:run",
    "whole frame": "simulation.py:step_frame",
}


#: m: the standard deviation of the normal noise a perturbed run adds to every start coordinate.
PERTURBATION = 1e-6
#: The quality measures of a row (``Trial.row``), each the worse the larger.
QUALITY = ("strain_mean", "strain_p99", "strain_max", "max_penetration", "max_penetration_winding",
           "max_stiff_seam_gap", "max_self_crossing_edges")


class Trial:
    """One configuration on the scene: its simulation, its CPU time and its quality so far; with a
    ``perturbation_seed``, started from positions moved by ``PERTURBATION`` (seeded normal noise)."""

    def __init__(self, dart, model, track, settings: SimSettings, profile: bool = False,
                 perturbation_seed: int | None = None):
        self.dart, self.model, self.track, self.settings = dart, model, track, settings
        start = track.place_rest(model.rest)
        if perturbation_seed is not None:
            start = start + np.random.default_rng(perturbation_seed).normal(0.0, PERTURBATION, start.shape)
        self.sim = Simulation(model, start, track.faces, track.vertices[0], settings)
        self.sim.step_frame(track.vertices[1])  # compiles the kernels; not timed
        self.stiff = np.isin(dart.pair_seam, [i for i, s in enumerate(dart.seams) if s.regime == "stiff"])
        self.cpu, self.frames, self.strains, self.stable = 0.0, 0, [], True
        self.p99 = self.worst = self.pen = self.pen_w = self.gap = 0.0
        self.crossings = 0
        self.profiler = cProfile.Profile() if profile else None

    def step(self, k: int) -> None:
        """Step frame ``k`` (timed by CPU, ``time.process_time``) and measure it once past the settle."""
        if not self.stable:
            return
        start = time.process_time()
        if self.profiler:
            self.profiler.enable()
        self.sim.step_frame(self.track.vertices[k])
        if self.profiler:
            self.profiler.disable()
        self.cpu += time.process_time() - start
        self.frames += 1
        if k < self.track.settle_frames:
            return
        m = self.sim.measure(winding=True)
        if not m.finite or m.max_speed > self.settings.max_speed:
            self.stable = False
            return
        x = self.sim.positions()
        s = edge_strain(self.model, x)
        self.strains.append(s.mean())
        self.p99, self.worst = max(self.p99, float(np.percentile(s, 99))), max(self.worst, float(s.max()))
        self.pen, self.pen_w = max(self.pen, m.penetration), max(self.pen_w, m.penetration_winding)
        self.crossings = max(self.crossings, m.self_intersections)
        v = x[self.model.particle_of_vertex]
        if self.stiff.any():
            pairs = self.dart.pairs[self.stiff]
            self.gap = max(self.gap, float(np.linalg.norm(v[pairs[:, 0]] - v[pairs[:, 1]], axis=1).max()))

    def row(self) -> dict:
        settings = self.settings
        row = {"settings": {k: getattr(settings, k) for k in ("solver", "substeps", "iterations", "contact_skin",
                                                              "tethers", "tether_scale", "bending_interval",
                                                              "self_contact_interval", "replay_launches",
                                                              "contact_interval",
                                                              "self_contact_broad_interval", "self_contact_list_reach",
                                                              "self_contact_reach")},
               "sim_fps": self.frames / self.cpu, "stable": self.stable,
               "strain_mean": float(np.mean(self.strains)) if self.strains else None,
               "strain_p99": self.p99, "strain_max": self.worst, "max_penetration": self.pen,
               "max_penetration_winding": self.pen_w, "max_stiff_seam_gap": self.gap,
               "max_self_crossing_edges": self.crossings}
        if self.profiler:
            stats = pstats.Stats(self.profiler).stats
            row["profile_ms_per_frame"] = {
                label: 1e3 * sum(v[3] for key, v in stats.items() if f"{Path(key[0]).name}:{key[2]}".endswith(suffix))
                / self.frames for label, suffix in PROFILE_ROWS.items()}
        return row


def compare(dart, model, track, configurations: dict[str, dict], frames: int, profile: bool = False,
            perturbed: int = 0) -> dict:
    """Every configuration on the same ``frames`` recorded frames (after the settle), alternated frame
    by frame in this process so that a busy machine slows them alike; the first is the baseline of
    ``ratio``. ``perturbed``: each configuration also runs that many times from start positions
    perturbed by ``PERTURBATION`` (seeds 1, 2, ...); its row keeps the unperturbed run's quality,
    adds ``spread`` (the least and the most of each quality measure over all its runs: how far a
    chaotic measure moves by itself) and counts every run in its frame rate. ``profile``: a second
    copy of the last configuration runs alongside under cProfile (its rows go to the last
    configuration's ``profile_ms_per_frame``; the profiler's overhead stays out of the ratios)."""
    names = list(configurations)
    trials = {name: [Trial(dart, model, track, SimSettings(**configurations[name]), perturbation_seed=seed)
                     for seed in [None, *range(1, perturbed + 1)]] for name in names}
    profiled = Trial(dart, model, track, SimSettings(**configurations[names[-1]]), profile=True) if profile else None
    for k in range(2, min(len(track.vertices), track.settle_frames + frames + 1)):
        for trial in [*(t for runs in trials.values() for t in runs), *([profiled] if profiled else [])]:
            trial.step(k)
    results = {}
    for name, runs in trials.items():
        rows = [run.row() for run in runs]
        results[name] = row = rows[0]
        row["sim_fps"] = sum(run.frames for run in runs) / sum(run.cpu for run in runs)
        if perturbed:
            values = {measure: [r[measure] for r in rows if r[measure] is not None] for measure in QUALITY}
            row["spread"] = {measure: [min(v), max(v)] for measure, v in values.items() if v}
    for row in results.values():
        row["ratio"] = row["sim_fps"] / results[names[0]]["sim_fps"]
    if profiled:
        results[names[-1]]["profile_ms_per_frame"] = profiled.row()["profile_ms_per_frame"]
    return results


def configuration(start: str) -> str:
    """The one configuration whose name starts with ``start`` (argparse's error for none or several)."""
    found = [name for name in CONFIGURATIONS if name.startswith(start)]
    if len(found) != 1:
        raise argparse.ArgumentTypeError(f"{start!r} starts {len(found)} configuration names, not one: "
                                         + "; ".join(name.split(":")[0] for name in CONFIGURATIONS))
    return found[0]


def variant(text: str) -> tuple[str, dict]:
    """A configuration from ``KEY=VALUE[,KEY=VALUE ...]`` (``SimSettings`` fields; true / false,
    whole numbers, numbers, else the text), named by ``text``; argparse's error for an unknown key
    or a value the settings refuse."""
    names = {f.name for f in fields(SimSettings)}
    changes = {}
    for item in text.split(","):
        key, _, value = item.partition("=")
        if key not in names or not value:
            raise argparse.ArgumentTypeError(f"{item!r}: not KEY=VALUE of a SimSettings field")
        lowered = value.lower()
        if lowered in ("true", "false"):
            changes[key] = lowered == "true"
            continue
        for kind in (int, float, str):
            try:
                changes[key] = kind(value)
                break
            except ValueError:
                continue
    try:
        SimSettings(**changes)
    except DartsInputError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text, changes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), metavar="GARMENT:MOTION",
                        help=f"shipped garment and motion names or files (default: {' '.join(SCENES)})")
    parser.add_argument("--frames", type=int, default=None,
                        help="recorded frames after the settle "
                             "(default: 30 for the first scene, the whole motion for the others)")
    parser.add_argument("--configurations", nargs="+", default=list(CONFIGURATIONS), type=configuration,
                        metavar="NAME", help="which rows, each by its name's start, e.g. 'default' or 'small' "
                                             "(default: all; the first is the baseline)")
    parser.add_argument("--variant", type=variant, action="append", default=[], metavar="KEY=VALUE[,KEY=VALUE...]",
                        help="a row more: the default with these SimSettings fields changed (repeatable)")
    parser.add_argument("--profile", action="store_true", help="profile the last configuration (a copy of it, run alongside)")
    parser.add_argument("--perturbed", type=int, default=0, metavar="N",
                        help=f"also run each configuration N times from start positions perturbed by {PERTURBATION:g} m "
                             "and report each quality measure's spread over the runs (default 0)")
    parser.add_argument("--out", type=Path, default=Path("docs/data/benchmark_solver.json"))
    args = parser.parse_args()
    body = load_body()
    document = {"scenes": []}
    for index, scene in enumerate(args.scenes):
        garment, motion = scene.split(":")
        dart = load_dart(resolve_garment(garment))
        model = cloth_model(dart)
        track = build_body_track(body, load_motion(resolve_motion(motion)), 30.0, 0.5, gap=SimSettings().body_gap)
        frames = args.frames or (30 if index == 0 else len(track.vertices))
        configurations = {name: CONFIGURATIONS[name] for name in args.configurations} | dict(args.variant)
        results = compare(dart, model, track, configurations, frames, args.profile, args.perturbed)
        for name, row in results.items():
            print(scene, name, json.dumps(row), flush=True)
        document["scenes"].append({"garment": garment, "motion": motion,
                                   "frames": min(frames, len(track.vertices) - track.settle_frames - 1),
                                   "particles": len(model.rest), "results": results})
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(document, indent=1))  # after every scene: a long run keeps what it has


if __name__ == "__main__":
    main()
