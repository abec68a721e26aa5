"""Jobs per hour of `darts batch` on Ray against a serial loop over the same jobs, in one script.

    python benchmarks/batch.py [--spec scenes/batch/example.toml] [--frames 60] [--materials own silk]
        [--out docs/data/benchmark_batch.json]

The jobs are the SPEC's (default: the shipped example, 2 garments x 2 motions x 2 body shapes)
times ``--materials`` (default: each DART's own and silk: 16 jobs), run with ``--frames``
recorded frames each. The serial baseline is what a user would write: one
process, the jobs one after another (``darts.jobs.run_one``, the same job function), torch at its
default threading. Ray runs them with ``darts.jobs.run_jobs`` on ``--workers`` (default: every
core), its start-up (about 6 s) included in its wall time.
"""
from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

from darts.jobs import Job, run_jobs, run_one
from sim.batch.job import run_simulation
from sim.batch.spec import load_jobs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spec", type=Path, default=Path("scenes/batch/example.toml"))
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--materials", nargs="+", default=["own", "silk"])
    parser.add_argument("--workers", type=int, default=os.cpu_count())
    parser.add_argument("--out", type=Path, default=Path("docs/data/benchmark_batch.json"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        spec = Path(tmp) / args.spec.name
        text = args.spec.read_text().replace("frames = 6", f"frames = {args.frames}")
        spec.write_text(text.replace("[sweep]", f"[sweep]\nmaterials = {json.dumps(args.materials)}"))
        jobs = load_jobs(spec)
        started = time.perf_counter()
        serial = [run_one(run_simulation, job, Path(tmp) / "serial") for job in jobs]
        serial_s = time.perf_counter() - started
        started = time.perf_counter()
        parallel = run_jobs([Job(job.id, job.inputs) for job in jobs], Path(tmp) / "ray", run_simulation,
                            workers=args.workers, progress=False)
        ray_s = time.perf_counter() - started
    failed = [row["id"] for row in serial + parallel if row["status"] != "ok"]
    result = {
        "jobs": len(jobs), "frames_per_job": args.frames, "materials": args.materials, "workers": args.workers,
        "cores": os.cpu_count(),
        "serial_seconds": round(serial_s, 2), "ray_seconds": round(ray_s, 2),
        "serial_jobs_per_hour": round(3600 * len(jobs) / serial_s, 1), "ray_jobs_per_hour": round(3600 * len(jobs) / ray_s, 1),
        "speedup": round(serial_s / ray_s, 3), "failed": failed,
        "mean_job_seconds": {"serial": round(sum(r["wall_seconds"] for r in serial) / len(serial), 2),
                             "ray": round(sum(r["wall_seconds"] for r in parallel) / len(parallel), 2)},
    }
    print(json.dumps(result, indent=1))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
