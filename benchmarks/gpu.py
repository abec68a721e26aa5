"""The CUDA path, measured: ms a frame and quality for issue 49's scenes, and many worlds on one GPU.

    python benchmarks/gpu.py [--device cuda] [--frames 30] [--worlds 1 8 64 256] [--scenes NAME ...]
                             [--budget SECONDS] [--out docs/data/benchmark_gpu.json]

Scenes (the default body, 30 fps, 0.5 s settle, the defaults): the shipped short-sleeve top (6k)
on the walk, the same top remade at 24k vertices (``darts.template(..., edge_length=0.0055)``),
the long pants on the squat, the outfit of long pants and a long-sleeve top on the walk. Each is
stepped frame by frame; after two untimed frames (kernels loaded, graphs captured) every frame's
wall time is taken between two ``wp.synchronize_device`` calls (a GPU's work is asynchronous; CPU
time would not see it), and the quality of the run as ``darts-sim --stats`` gives it (penetration by
closest point and winding number, strain p99, crossing edges). ``--compare-cpu`` runs each scene on
the CPU too, for the quality to match.

Many worlds: N copies of a mix of jobs (the top on the walk, pants on the squat, a skirt on the wave,
a dress on the walk, in turn) as worlds of one solver
(``sim.worlds.simulate_worlds``); garment-frames a second in aggregate (N x frames over the timed
frames' wall time) and each world's quality (the worst over the worlds).

Everything is written after each measurement (``--out``), so that a run cut short by the device's time
limit keeps what it measured; ``--budget`` stops starting new measurements after that many seconds.
On a machine without CUDA, ``--device cpu --frames 3 --worlds 1 2`` checks the script itself.
"""
from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"top-walk": (["short-sleeve-top"], "walk", None), "top24k-walk": (["short-sleeve-top"], "walk", 0.0055),
          "pants-squat": (["long-pants"], "squat", None), "outfit-walk": (["long-pants", "long-sleeve-top"], "walk", None)}
MIX = [("short-sleeve-top", "walk"), ("long-pants", "squat"), ("short-skirt", "wave"), ("sleeveless-dress", "walk")]


def _garments(names, edge_length, body):
    import darts

    if edge_length is None:
        return [darts.load_garment(name) for name in names]
    return [darts.template(name, body=body, edge_length=edge_length) for name in names]


def _timed_frames(simulation, bodies, frames: int, wp, after=None) -> list[float]:
    """Step ``frames`` frames (bodies(k) the body at frame k) after two untimed ones, calling
    ``after()`` (untimed) after each; each timed frame's wall seconds, device synchronised around it."""
    seconds = []
    for k in range(1, frames + 3):
        wp.synchronize_device(simulation.device)
        start = time.perf_counter()
        simulation.step_frame(bodies(k))
        wp.synchronize_device(simulation.device)
        if k > 2:
            seconds.append(time.perf_counter() - start)
        if after is not None:
            after()
    return seconds


def _quality(measures: list, strains: list) -> dict:
    return {"max_penetration": max(m.penetration for m in measures),
            "max_penetration_winding": max(m.penetration_winding for m in measures),
            "max_self_intersections": max(m.self_intersections for m in measures),
            "strain_p99": max(strains), "stable": all(m.finite for m in measures)}


def scene(name: str, device: str, frames: int) -> dict:
    import darts
    from darts.geometry.warp_runtime import warp
    from sim.body_track import build_body_track
    from sim.engine.settings import SimSettings
    from sim.engine.simulation import Simulation
    from sim.outfit import outfit_model
    from sim.quality import edge_strain
    from sim.run import job_model

    wp = warp()
    names, motion, edge_length = SCENES[name]
    body = darts.load_body()
    darts_ = _garments(names, edge_length, body)
    garments = darts_[0] if len(darts_) == 1 else outfit_model(darts_, names, body.shaped()[0][0].double().numpy(),
                                                               body.faces)
    model = job_model(garments)
    track = build_body_track(body, darts.load_motion(motion), 30.0, 0.5)
    frames = min(frames, len(track.vertices) - 3)
    simulation = Simulation(model, track.place_rest(model.rest), track.faces, track.vertices[0], SimSettings(device=device),
                            track.parts)
    measures, strains = [], []

    def measure():
        measures.append(simulation.measure(winding=True))
        strains.append(float(np.percentile(edge_strain(model, simulation.positions()), 99)))

    seconds = _timed_frames(simulation, lambda k: track.vertices[k], frames, wp, measure)
    return {"scene": name, "device": device, "particles": len(model.rest), "frames": frames,
            "ms_per_frame": 1e3 * float(np.mean(seconds)), "ms_per_frame_median": 1e3 * float(np.median(seconds)),
            **_quality(measures, strains)}


def worlds(count: int, device: str, frames: int) -> dict:
    import darts
    from darts.geometry.warp_runtime import warp
    from sim.body_track import build_body_track
    from sim.engine.settings import SimSettings
    from sim.engine.simulation import Simulation
    from sim.quality import edge_strain
    from sim.run import job_model
    from sim.worlds import WorldBodies, join_worlds, world_offsets

    wp = warp()
    body = darts.load_body()
    tracks, models, cache = [], [], {}
    for k in range(count):
        garment, motion = MIX[k % len(MIX)]
        if (garment, motion) not in cache:
            cache[garment, motion] = (job_model(darts.load_garment(garment)),
                                      build_body_track(body, darts.load_motion(motion), 30.0, 0.5))
        model, track = cache[garment, motion]
        models.append(model)
        tracks.append(track)
    frames = min([frames] + [len(t.vertices) - 3 for t in tracks])
    offsets = world_offsets(tracks)
    bodies = WorldBodies(tracks, offsets)
    model = join_worlds(models)
    positions = np.concatenate([t.place_rest(m.rest) + o for t, m, o in zip(tracks, models, offsets)])
    simulation = Simulation(model, positions, bodies.faces, bodies.at(0), SimSettings(device=device), bodies.parts,
                            bodies.world)
    started = time.perf_counter()
    seconds = _timed_frames(simulation, bodies.at, frames, wp)
    stepped = time.perf_counter() - started
    each = simulation.measure_worlds(winding=True)
    strain = edge_strain(model, simulation.positions())
    edge_world = model.world[model.edges[:, 0]]
    strains = [float(np.percentile(strain[edge_world == w], 99)) for w in range(count)]
    return {"worlds": count, "device": device, "particles": len(model.rest), "frames": frames,
            "ms_per_frame": 1e3 * float(np.mean(seconds)),
            "garment_frames_per_second": count * len(seconds) / float(np.sum(seconds)),
            "wall_seconds_with_warmup": stepped,
            "worst_world": {"max_penetration": max(m.penetration for m in each),
                            "max_penetration_winding": max(m.penetration_winding for m in each),
                            "max_self_intersections": max(m.self_intersections for m in each),
                            "strain_p99": max(strains), "stable": all(m.finite for m in each)}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cuda")
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--scenes", nargs="*", default=list(SCENES), choices=list(SCENES))
    parser.add_argument("--worlds", nargs="*", type=int, default=[1, 8, 64, 256])
    parser.add_argument("--compare-cpu", action="store_true", help="each scene on the CPU too (its quality)")
    parser.add_argument("--budget", type=float, default=float("inf"), help="seconds after which no new measurement starts")
    parser.add_argument("--out", default=str(ROOT / "docs" / "data" / "benchmark_gpu.json"))
    args = parser.parse_args()
    from darts.geometry.warp_runtime import warp

    wp = warp()
    device = wp.get_device(args.device)
    report = {"device": device.name if device.is_cuda else platform.processor() or "cpu", "warp": wp.config.version,
              "command": "python benchmarks/gpu.py " + " ".join(f"--{k.replace('_', '-')} {v}" for k, v in
                                                                vars(args).items() if k not in ("out",)),
              "scenes": [], "worlds": []}
    began = time.perf_counter()

    def save():
        Path(args.out).write_text(json.dumps(report, indent=1))

    for name in args.scenes:
        for on in [args.device] + (["cpu"] if args.compare_cpu else []):
            if time.perf_counter() - began < args.budget:
                report["scenes"].append(scene(name, on, args.frames))
                print(json.dumps(report["scenes"][-1]), flush=True)
                save()
    for count in args.worlds:
        if time.perf_counter() - began < args.budget:
            report["worlds"].append(worlds(count, args.device, args.frames))
            print(json.dumps(report["worlds"][-1]), flush=True)
            save()


if __name__ == "__main__":
    main()
