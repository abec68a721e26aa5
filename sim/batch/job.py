"""One batch job: one simulation (``sim.api.run_job``), its files in the job's folder, its numbers in the manifest."""
from __future__ import annotations

from pathlib import Path

from darts.jobs import Job
from sim.batch.spec import JOB_FOLDER


def run_simulation(job: Job, folder: Path) -> dict:
    """Run the job's ``SimJob`` with its outputs in ``folder``; the manifest fields: stable, sim_fps,
    max_penetration (fraction of particles), max_seam_gap (m, over every seam), max_speed (m/s),
    frames, and the message of an unstable run as ``error``."""
    from sim.api import SimJob, run_job

    request = dict(job.inputs["job"])
    for key in ("output", "stats", "preview"):
        if request.get(key) is not None:
            request[key] = request[key].replace(JOB_FOLDER, str(folder))
    run = run_job(SimJob.from_dict(request), keep_frames=False)
    stats = run.stats
    gaps = stats["max_seam_gap"].values()
    return {
        "status": "ok" if run.stable else "unstable", "stable": stats["stable"], "error": run.message,
        "frames": len(stats["frames"]), "particles": stats["particles"], "sim_fps": round(stats["sim_fps"], 3),
        "max_penetration": stats["max_penetration"], "max_seam_gap": max(gaps, default=0.0),
        "max_speed": stats["max_speed"], "outputs": sorted(p.name for p in folder.iterdir()),
    }
