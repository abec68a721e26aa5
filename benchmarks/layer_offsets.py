"""An outfit's layer offsets found on the simulation's device (``sim.engine.layers.LayerCover``, the
default) against the host surface distance of every frame (``covering_offsets`` of a host copy, as
before issue 49), in one process.

    python benchmarks/layer_offsets.py [--frames 20] [--out docs/data/benchmark_layer_offsets.json]

Long pants under a long-sleeve top on the walk (default body, 30 fps, 0.5 s settle, defaults): two
simulations of the same outfit, one finding its offsets each way, stepped frame by frame in turn;
CPU time (``time.process_time``) of ``step_frame`` and, separately, of one more finding of the
offsets, the first two frames left out. Both runs must stay identical to the bit.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


class HostCover:
    """The offsets as they were found before: ``covering_offsets`` of the particles copied to the host."""

    def __init__(self, simulation):
        self.simulation = simulation

    def offsets(self, out) -> float:
        from sim.engine.layers import covering_offsets

        found = covering_offsets(self.simulation.model, self.simulation.positions())
        out.assign(found.astype(np.float32))
        return float(found.max(initial=0.0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--out", default=str(ROOT / "docs" / "data" / "benchmark_layer_offsets.json"))
    args = parser.parse_args()
    import darts
    from sim.body_track import build_body_track
    from sim.engine.settings import SimSettings
    from sim.engine.simulation import Simulation
    from sim.outfit import outfit_model

    body, names = darts.load_body(), ["long-pants", "long-sleeve-top"]
    outfit = outfit_model([darts.load_garment(n) for n in names], names, body.shaped()[0][0].double().numpy(), body.faces)
    track = build_body_track(body, darts.load_motion("walk"), 30.0, 0.5)
    model = outfit.model
    runs = {name: Simulation(model, track.place_rest(model.rest), track.faces, track.vertices[0], SimSettings(),
                             track.parts) for name in ("device", "host")}
    runs["host"].layer_cover = HostCover(runs["host"])
    frame = dict.fromkeys(runs, 0.0)
    cover = dict.fromkeys(runs, 0.0)
    for k in range(1, args.frames + 1):
        for name, simulation in runs.items():
            start = time.process_time()
            simulation.step_frame(track.vertices[k])
            stepped = time.process_time()
            simulation.layer_cover.offsets(simulation.collider.offset)
            if k > 2:
                frame[name] += stepped - start
                cover[name] += time.process_time() - stepped
    timed = args.frames - 2
    report = {"scene": "long-pants + long-sleeve-top, walk", "frames": timed,
              "ms_per_frame": {n: 1e3 * s / timed for n, s in frame.items()},
              "ms_per_layer_offsets": {n: 1e3 * s / timed for n, s in cover.items()},
              "identical": bool(np.array_equal(runs["device"].positions(), runs["host"].positions())),
              "command": "python benchmarks/layer_offsets.py"}
    Path(args.out).write_text(json.dumps(report, indent=1))
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
