"""Cost of our solver against garment size, with a per-kernel profile, in one process.

    python benchmarks/scaling.py [--frames 20] [--out docs/data/benchmark_scaling.json]

The shipped short-sleeve top's category is rebuilt at edge lengths that give about 2k, 6k, 20k and
50k vertices (DARTs cached in benchmarks/.cache/), then each is simulated on the default body
walking (30 fps, 0.5 s settle, the first ``--frames`` frames after the first, not timed: it compiles
the kernels) with the reference settings: XPBD, 10 substeps x 4 iterations, self-contact on. Every
Warp launch and BVH refit is timed on the host (the CPU backend runs them synchronously), so the
breakdown adds up to the frame time less Python overhead. Reported: particles, simulated frames per
second, microseconds per particle per substep, and the share of each kernel; at 6k also the same
run without the body contact's continuous test, and without crease contacts, for their cost.
"""
from __future__ import annotations

import argparse
import collections
import json
import time
from dataclasses import replace
from pathlib import Path

from darts.body.io import load_body
from darts.dart.build import make_dart
from darts.dart.io import load_dart, save_dart
from darts.geometry.warp_runtime import warp
from darts.motion.amass import load_motion
from darts.shipped import resolve_motion
from sim.body_track import build_body_track
from sim.engine.model import cloth_model
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation

wp = warp()
CACHE = Path(__file__).resolve().parent / ".cache"
#: Edge lengths (m) of the short-sleeve top giving about 2k, 6k, 20k and 50k vertices.
EDGE_LENGTHS = {"2k": 0.0195, "6k": 0.011, "20k": 0.0061, "50k": 0.0039}


class LaunchTimer:
    """Times every ``wp.launch`` (by kernel) and ``wp.Mesh.refit`` while active."""

    def __init__(self):
        self.seconds = collections.Counter()
        self._launch, self._refit = wp.launch, wp.Mesh.refit

    def __enter__(self):
        launch, refit, seconds = self._launch, self._refit, self.seconds

        def timed_launch(kernel, *args, **kwargs):
            start = time.perf_counter()
            launch(kernel, *args, **kwargs)
            seconds[kernel.key] += time.perf_counter() - start

        def timed_refit(mesh):
            start = time.perf_counter()
            refit(mesh)
            seconds["bvh refit"] += time.perf_counter() - start

        wp.launch, wp.Mesh.refit = timed_launch, timed_refit
        return self

    def __exit__(self, *exc):
        wp.launch, wp.Mesh.refit = self._launch, self._refit


def garment(size: str, body) -> Path:
    path = CACHE / f"short-sleeve-top-{size}.npz"
    if not path.exists():
        CACHE.mkdir(exist_ok=True)
        save_dart(make_dart("short-sleeve-top", body, edge_length=EDGE_LENGTHS[size]), path)
    return path


def measure(path: Path, track, frames: int, settings: SimSettings) -> dict:
    model = cloth_model(load_dart(path))
    solver = Simulation(model, track.place_rest(model.rest), track.faces, track.vertices[0], settings, track.parts)
    solver.step_frame(track.vertices[1])  # compiles the kernels
    with LaunchTimer() as timer:
        start = time.perf_counter()
        for k in range(2, frames + 2):
            solver.step_frame(track.vertices[k])
        wall = time.perf_counter() - start
    finite = solver.measure().finite
    per_substep = wall / (frames * settings.substeps)
    return {"particles": solver.count, "triangles": len(model.faces), "frames": frames, "sim_fps": frames / wall,
            "us_per_particle_substep": 1e6 * per_substep / solver.count, "finite": finite,
            "share": {name: t / wall for name, t in timer.seconds.most_common()},
            "ms_per_frame": {name: 1e3 * t / frames for name, t in timer.seconds.most_common()}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--sizes", default=",".join(EDGE_LENGTHS))
    parser.add_argument("--out", type=Path, default=Path("docs/data/benchmark_scaling.json"))
    args = parser.parse_args()
    body = load_body()
    track = build_body_track(body, load_motion(resolve_motion("walk")), 30.0, 0.5)
    settings = SimSettings(substeps=10, iterations=4)
    rows = {}
    for size in args.sizes.split(","):
        row = measure(garment(size, body), track, args.frames, settings)
        rows[size] = row
        top = ", ".join(f"{k} {100 * v:.0f} %" for k, v in list(row["share"].items())[:4])
        print(f"{size}: {row['particles']} particles, {row['sim_fps']:.2f} fps, "
              f"{row['us_per_particle_substep']:.3f} us/particle/substep ({top})", flush=True)
    # What the body contact's continuous test and crease contacts each cost: the 6k run without it.
    ablations = {}
    if "6k" in rows:
        for name in ("continuous_collision", "crease_contacts"):
            without = measure(garment("6k", body), track, args.frames, replace(settings, **{name: False}))
            ablations[name] = without
            print(f"6k without {name}: {without['sim_fps']:.2f} fps; with it {rows['6k']['sim_fps'] / without['sim_fps']:.3f} x "
                  f"the speed; body contact search {rows['6k']['ms_per_frame']['find_contacts']:.2f} against "
                  f"{without['ms_per_frame']['find_contacts']:.2f} ms a frame", flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"settings": {"solver": "xpbd", "substeps": 10, "iterations": 4, "self_contact": True,
                                                 "motion": "walk", "fps": 30}, "sizes": rows,
                                    "6k_without": ablations}, indent=1))


if __name__ == "__main__":
    main()
