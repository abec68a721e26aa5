"""One batch job: one ``darts-sim`` run, its files in the job's folder, its numbers in the manifest."""
from __future__ import annotations

from pathlib import Path

from darts.jobs import Job
from sim.batch.spec import JOB_FOLDER


def run_simulation(job: Job, folder: Path) -> dict:
    """Run the job's darts-sim command with its outputs in ``folder``; the manifest fields: stable,
    sim_fps, max_penetration (fraction of particles), max_seam_gap (m, over every seam), max_speed
    (m/s), frames, and the message of an unstable run as ``error``."""
    from sim.cli import SimOutcome, execute, parser

    argv = [str(folder) if arg == JOB_FOLDER else arg.replace(JOB_FOLDER, str(folder)) for arg in job.inputs["argv"]]
    outcome: SimOutcome = execute(parser().parse_args(argv))
    stats = outcome.stats
    gaps = stats["max_seam_gap"].values()
    return {
        "status": "ok" if outcome.code == 0 else "unstable", "stable": stats["stable"], "error": outcome.message,
        "frames": len(stats["frames"]), "particles": stats["particles"], "sim_fps": round(stats["sim_fps"], 3),
        "max_penetration": stats["max_penetration"], "max_seam_gap": max(gaps, default=0.0),
        "max_speed": stats["max_speed"], "outputs": sorted(p.name for p in folder.iterdir()),
    }
