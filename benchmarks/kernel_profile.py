"""Where a default frame's CPU time goes, kernel by kernel.

    python benchmarks/kernel_profile.py [--scene GARMENT:MOTION] [--frames N] [--out docs/data/kernel_profile.json]

The scene (default: the shipped short-sleeve top on the walk, default body, 30 fps, default
settings) is stepped through its 0.5 s settle untimed, then ``--frames`` frames timed by CPU time
(``time.process_time``, one core): first as users run it (the frame rate alone), then again from
the start with every kernel launch (``sim.engine.launch.Launcher``) and BVH refit timed on the host; the
sweeps a default step replays as one captured block run launch by launch there, so that each of
their kernels is seen; each launch's time includes the 2-3 µs of replaying a recorded launch from
Python. Prints ms per frame and launches per frame, largest first; the rest of the frame (Python,
numpy) is the difference from the whole.
"""
from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from pathlib import Path

from darts.body.io import load_body
from darts.dart.io import load_dart
from darts.geometry.warp_runtime import warp
from darts.motion.amass import load_motion
from darts.shipped import resolve_garment, resolve_motion
from sim.body_track import build_body_track
from sim.engine import launch
from sim.engine.model import cloth_model
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation

wp = warp()


class KernelClock:
    """CPU seconds and calls per kernel (and per BVH refit), while ``timing`` is on."""

    def __init__(self):
        self.seconds, self.calls, self.timing = Counter(), Counter(), False

    def timed(self, name: str, call) -> None:
        if not self.timing:
            call()
            return
        start = time.process_time()
        call()
        self.seconds[name] += time.process_time() - start
        self.calls[name] += 1

    def install(self) -> None:
        """Time every ``Launcher`` call and ``wp.Mesh.refit``; run replayed blocks launch by launch."""
        launcher_call, refit = launch.Launcher.__call__, wp.Mesh.refit
        clock = self

        def timed_launch(launcher, kernel, dim, inputs):
            clock.timed(kernel.key, lambda: launcher_call(launcher, kernel, dim, inputs))

        def timed_refit(mesh):
            clock.timed("BVH refit", lambda: refit(mesh))

        launch.Launcher.__call__ = timed_launch
        wp.Mesh.refit = timed_refit
        launch.Replay.run = lambda replay, key, block: block()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="short-sleeve-top:walk", metavar="GARMENT:MOTION")
    parser.add_argument("--frames", type=int, default=30, help="timed frames after the settle (default 30)")
    parser.add_argument("--out", type=Path, default=Path("docs/data/kernel_profile.json"))
    args = parser.parse_args()
    garment, motion = args.scene.split(":")
    model = cloth_model(load_dart(resolve_garment(garment)))
    track = build_body_track(load_body(), load_motion(resolve_motion(motion)), 30.0, 0.5, gap=SimSettings().body_gap)
    first = track.settle_frames + 1
    frames = min(args.frames, len(track.vertices) - first)

    def frame_ms() -> float:
        """CPU ms per frame of a default run of the scene, over the frames after the settle."""
        simulation = Simulation(model, track.place_rest(model.rest), track.faces, track.vertices[0], SimSettings(), track.parts)
        for k in range(1, first):
            simulation.step_frame(track.vertices[k])
        clock.timing = True
        start = time.process_time()
        for k in range(first, first + frames):
            simulation.step_frame(track.vertices[k])
        clock.timing = False
        return 1e3 * (time.process_time() - start) / frames

    clock = KernelClock()
    alone = frame_ms()  # as users run it, nothing timed inside
    clock.install()
    whole = frame_ms()
    rows = {name: {"ms_per_frame": 1e3 * seconds / frames, "calls_per_frame": clock.calls[name] / frames}
            for name, seconds in clock.seconds.most_common()}
    timed = sum(row["ms_per_frame"] for row in rows.values())
    print(f"{args.scene}, {len(model.rest)} particles, {frames} frames: {alone:.1f} ms a frame (CPU), "
          f"{1e3 / alone:.2f} frames/s; launch by launch {whole:.1f} ms, {timed:.1f} of them in kernels and refits")
    for name, row in rows.items():
        print(f"  {name:32s} {row['ms_per_frame']:7.2f} ms  {row['calls_per_frame']:5.1f} calls")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"scene": args.scene, "particles": len(model.rest), "frames": frames,
                                    "frame_ms": alone, "frame_ms_launch_by_launch": whole, "kernels": rows}, indent=1))


if __name__ == "__main__":
    main()
