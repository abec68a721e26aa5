"""Speed and quality of solver settings on one scene, against a baseline run in the same process.

    python benchmarks/solver_speed.py [--garment short-sleeve-top] [--motion walk] [--frames 30]
                                      [--out docs/data/benchmark_solver.json]

Scene: a shipped garment (default the 6k short-sleeve top) on the default body, a shipped motion at
30 fps after the 0.5 s settle, world frame Z up, metres. Each configuration steps the same frames,
the configurations alternated frame by frame in one process; only ``Simulation.step_frame`` is
timed, by CPU time (``time.process_time``; after one untimed frame that compiles the kernels), on
one core (Warp's CPU backend runs a launch on one thread). Quality over the recorded frames, measured
the same way for every configuration: edge strain (``sim.quality``: mean over edges and frames, the
largest 99th percentile and max of a frame), penetration by the closest point's sign and by the
body's winding number (largest fraction of particles inside over the frames), and the largest gap
of a stiff seam (m), and the most garment edges passing through a garment triangle in a frame. The
first configuration is the baseline (the default before long-range tethers and the contact skin:
XPBD 40 substeps x 2 sweeps, every particle searched every substep, self-contact searched every 2
substeps within 1 cm); ``ratio`` is each one's speed over it. The time of building the tethers (once per run, a few seconds) is not in
the frame rate. ``--profile`` adds where the time of the last configuration goes (cProfile, cumulative
seconds per frame of the solver's pieces).
"""
from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import time
from pathlib import Path

import numpy as np

from darts.body.io import load_body
from darts.dart.io import load_dart
from darts.motion.amass import load_motion
from scenes import resolve_garment, resolve_motion
from sim.body_track import build_body_track
from sim.model import cloth_model
from sim.quality import edge_strain
from sim.settings import SimSettings
from sim.simulation import Simulation

#: Self-contact as the previous defaults searched it: every 2 substeps, within 1 cm beyond the separation
#: (plus, now, what the particles travel until the next search, which the previous defaults did not add).
PREVIOUS_SELF_CONTACT = dict(self_contact_interval=2, self_contact_reach=0.01)
CONFIGURATIONS = {
    "xpbd 40x2 (the default before tethers)": dict(solver="xpbd", substeps=40, iterations=2, contact_skin=0.0,
                                                   tethers=False, **PREVIOUS_SELF_CONTACT),
    "xpbd 20x2, no tethers, no skin": dict(solver="xpbd", substeps=20, iterations=2, contact_skin=0.0, tethers=False,
                                           **PREVIOUS_SELF_CONTACT),
    "xpbd 20x2, tethers, 5 mm skin (the previous default)": dict(solver="xpbd", substeps=20, iterations=2,
                                                                 **PREVIOUS_SELF_CONTACT),
    "default (xpbd 20x2, tethers, 5 mm skin, self-contact every 4 substeps within 2 mm + travel)": {},
}
#: Functions whose cumulative time is the profile's rows (qualified name suffixes).
PROFILE_ROWS = {
    "body contact search and tracking": "collider.py:update",
    "self-contact search": "self_contact.py:search",
    "self-contact projection": "self_contact.py:resolve",
    "body contact projection": "collider.py:resolve",
    "friction": "collider.py:friction",
    "constraint sweeps (tethers, stretch, seams, bending)": "xpbd.py:launch",
    "whole frame": "simulation.py:step_frame",
}


class Trial:
    """One configuration on the scene: its simulation, its CPU time and its quality so far."""

    def __init__(self, dart, model, track, settings: SimSettings, profile: bool = False):
        self.dart, self.model, self.track, self.settings = dart, model, track, settings
        self.sim = Simulation(model, track.place_rest(model.rest), track.faces, track.vertices[0], settings)
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
                                                              "tethers", "self_contact_interval", "self_contact_reach")},
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


def compare(dart, model, track, configurations: dict[str, dict], frames: int, profile: bool = False) -> dict:
    """Every configuration on the same ``frames`` recorded frames (after the settle), alternated frame
    by frame in this process so that a busy machine slows them alike; the first is the baseline of
    ``ratio``. ``profile``: cProfile the last configuration."""
    names = list(configurations)
    trials = {name: Trial(dart, model, track, SimSettings(**configurations[name]), profile and name == names[-1])
              for name in names}
    for k in range(2, min(len(track.vertices), track.settle_frames + frames + 1)):
        for trial in trials.values():
            trial.step(k)
    results = {name: trial.row() for name, trial in trials.items()}
    for row in results.values():
        row["ratio"] = row["sim_fps"] / results[names[0]]["sim_fps"]
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--garment", default="short-sleeve-top")
    parser.add_argument("--motion", default="walk")
    parser.add_argument("--frames", type=int, default=30, help="recorded frames after the settle (default 30)")
    parser.add_argument("--profile", action="store_true", help="profile the last configuration")
    parser.add_argument("--out", type=Path, default=Path("docs/data/benchmark_solver.json"))
    args = parser.parse_args()
    dart = load_dart(resolve_garment(args.garment))
    model = cloth_model(dart)
    track = build_body_track(load_body(), load_motion(resolve_motion(args.motion)), 30.0, 0.5)
    results = compare(dart, model, track, CONFIGURATIONS, args.frames, args.profile)
    for name, row in results.items():
        print(name, json.dumps(row), flush=True)
    document = {"scene": {"garment": args.garment, "motion": args.motion, "frames": args.frames,
                          "particles": len(model.rest)}, "results": results}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(document, indent=1))


if __name__ == "__main__":
    main()
