"""``darts batch SPEC -o OUT_DIR``: every job of a SPEC as a darts-sim run, on Ray, resumable.

Exit codes: 0 every job succeeded, 1 some failed or went unstable (see the manifest), 2 bad input.
"""
from __future__ import annotations

from pathlib import Path

from darts.errors import DartsInputError
from darts.jobs import MANIFEST, Job, check_cluster_options, check_out_dir, run_jobs


def _table(rows: list[dict]) -> str:
    lines = [f"{'job':46s} {'status':9s} {'wall s':>7s} {'sim fps':>7s} {'pen %':>6s} {'gap mm':>6s}  error"]
    for row in rows:
        measured = row["status"] != "failed"
        lines.append(f"{row['id'][:46]:46s} {row['status']:9s} {row['wall_seconds']:7.1f} "
                     + (f"{row['sim_fps']:7.2f} {100 * row['max_penetration']:6.2f} {1e3 * row['max_seam_gap']:6.2f}"
                        if measured else f"{'-':>7s} {'-':>6s} {'-':>6s}")
                     + f"  {row.get('error', '')[:100]}")
    return "\n".join(lines)


def batch(args) -> int:
    from sim.batch.job import run_simulation, run_simulations
    from sim.batch.spec import JOB_FOLDER, load_jobs

    out = Path(args.output)
    jobs = [Job(job.id, {**job.inputs, "command": job.inputs["command"].replace(JOB_FOLDER, str(out / job.id))})
            for job in load_jobs(args.spec)]
    check_cluster_options(args.workers, args.address)
    if args.worlds < 1:
        raise DartsInputError(None, f"--worlds must be at least 1, got {args.worlds}")
    if args.list:  # writes nothing, not even OUT_DIR
        for job in jobs:
            print(f"{job.id}\n  {job.inputs['command']}")
        return 0
    check_out_dir(out)
    rows = run_jobs(jobs, args.output, run_simulation, workers=args.workers, address=args.address, retry=args.retry,
                    group=run_simulations if args.worlds > 1 else None, group_size=args.worlds)
    print(_table(rows))
    failed = [row for row in rows if row["status"] != "ok"]
    print(f"{len(rows) - len(failed)} of {len(rows)} jobs succeeded; manifest: {Path(args.output) / MANIFEST}")
    return 1 if failed else 0


def add_parser(groups) -> None:
    """Register ``darts batch``."""
    parser = groups.add_parser(
        "batch", help="run many darts-sim jobs from a SPEC (TOML/JSON) on Ray, resumable",
        description="Run every job of a SPEC (garments x motions x body shapes x materials x seam settings, "
                    "or an explicit list; docs/batch.md) as a darts-sim run on Ray: locally with one worker "
                    "per core, or on the cluster at --address. Each job writes into OUT_DIR/<job>/; "
                    "OUT_DIR/manifest.jsonl has one row per job. Re-running skips finished jobs.")
    parser.add_argument("spec", metavar="SPEC", help="batch SPEC, .toml or .json (example: scenes/batch/example.toml)")
    parser.add_argument("-o", "--output", required=True, metavar="OUT_DIR", help="folder of the jobs and the manifest")
    parser.add_argument("--address", metavar="ADDR", help="join the Ray cluster at host:port (default: start Ray here)")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="jobs at once (default: one per core here, every CPU of a cluster)")
    parser.add_argument("--retry", type=int, default=0, metavar="K",
                        help="re-run a job up to K times when its worker process dies (default 0)")
    parser.add_argument("--worlds", type=int, default=1, metavar="N",
                        help="jobs per worker stepped together as worlds of one solver (sim.simulate_many; "
                             "for a GPU, device = \"cuda\" in the SPEC's [sim], where one GPU holds many garments; "
                             "default 1: one job at a time)")
    parser.add_argument("--list", action="store_true", help="print the jobs and their darts-sim commands, run nothing")
    parser.set_defaults(run=batch)
