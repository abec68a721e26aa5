"""Many worlds on the CPU: N jobs in one solver (``sim.simulate_many``) against the same N jobs run one
after the other (``sim.run_job``), whole runs at the defaults, in one process.

    python benchmarks/worlds.py [--frames 45] [--repeats 2] [--out docs/data/benchmark_worlds.json]

The four jobs mix garments and motions (a top walking, trousers squatting, a skirt walking on
another body shape, a dress waving). Each configuration is timed by CPU (``time.process_time`` of
the whole call: loading, posing the bodies, building the models and tethers, stepping, measuring,
as a user gets them), the two alternated ``--repeats`` times after one warm-up of each (which
compiles the kernels); each job's quality (penetration by closest point and winding number,
strain p99, crossing edges, seam gap) is reported from both, so that the cost is compared at equal
quality. On the CPU a many-world run is allowed to be no faster: one core steps the same
particles either way; what it saves is per-launch and per-frame overhead.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

JOBS = [("short-sleeve-top", "walk", None), ("long-pants", "squat", None), ("short-skirt", "walk", [1.0, -0.5]),
        ("sleeveless-dress", "wave", None)]


def _jobs(frames: int):
    from sim.api import SimJob

    return [SimJob(garment, motion, frames=frames, betas=betas, winding=True, measure_every=5)
            for garment, motion, betas in JOBS]


def _quality(stats: dict) -> dict:
    return {key: stats[key] for key in ("stable", "max_penetration", "max_penetration_winding", "strain_p99",
                                        "max_self_intersections", "particles")} | {
        "max_seam_gap_mm": 1e3 * max(stats["max_seam_gap"].values(), default=0.0)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=45)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--out", default=str(ROOT / "docs" / "data" / "benchmark_worlds.json"))
    args = parser.parse_args()
    import torch

    from sim.api import run_job, simulate_many

    torch.set_num_threads(1)
    runs = {"one solver": lambda: simulate_many(_jobs(args.frames), keep_frames=False),
            "one after another": lambda: [run_job(job, keep_frames=False) for job in _jobs(args.frames)]}
    for run in runs.values():  # warm-up: kernels compiled, files cached
        run()
    cpu = {name: [] for name in runs}
    quality = {}
    for _ in range(args.repeats):
        for name, run in runs.items():
            start = time.process_time()
            results = run()
            cpu[name].append(time.process_time() - start)
            quality[name] = [_quality(r.stats) for r in results]
    many, alone = min(cpu["one solver"]), min(cpu["one after another"])
    report = {"jobs": [{"garment": g, "motion": m, "betas": b} for g, m, b in JOBS], "frames": args.frames,
              "cpu_s": cpu, "ratio_one_solver_to_one_after_another": many / alone, "quality": quality,
              "command": "python benchmarks/worlds.py"}
    Path(args.out).write_text(json.dumps(report, indent=1))
    print(f"{len(JOBS)} jobs x {args.frames} frames: one solver {many:.1f} s CPU, one after another {alone:.1f} s "
          f"(ratio {many / alone:.2f})")
    for name, rows in quality.items():
        for (garment, motion, _), row in zip(JOBS, rows):
            print(f"  {name:18s} {garment:17s} {motion:6s} pen {100 * row['max_penetration']:.2f} % "
                  f"winding {100 * row['max_penetration_winding']:.2f} % strain p99 {100 * row['strain_p99']:.1f} % "
                  f"crossings {row['max_self_intersections']} seam {row['max_seam_gap_mm']:.1f} mm")


if __name__ == "__main__":
    main()
