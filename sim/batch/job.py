"""One batch job: one simulation (``sim.api.run_job``), its files in the job's folder, its numbers in
the manifest; or several jobs at once as worlds of one solver (``sim.api.simulate_many``)."""
from __future__ import annotations

from pathlib import Path

from darts.jobs import Job
from sim.batch.spec import JOB_FOLDER


def _sim_job(job: Job, folder: Path):
    """The job's ``SimJob``, its outputs in ``folder``."""
    from sim.api import SimJob

    request = dict(job.inputs["job"])
    for key in ("output", "stats", "preview"):
        if request.get(key) is not None:
            request[key] = request[key].replace(JOB_FOLDER, str(folder))
    return SimJob.from_dict(request)


def _manifest_fields(run, folder: Path) -> dict:
    """The manifest fields of a finished run: stable, sim_fps, max_penetration (fraction of
    particles), max_seam_gap (m, over every seam), max_speed (m/s), frames, and the message of an
    unstable run as ``error``."""
    stats = run.stats
    gaps = stats["max_seam_gap"].values()
    return {
        "status": "ok" if run.stable else "unstable", "stable": stats["stable"], "error": run.message,
        "frames": len(stats["frames"]), "particles": stats["particles"], "sim_fps": round(stats["sim_fps"], 3),
        "max_penetration": stats["max_penetration"], "max_seam_gap": max(gaps, default=0.0),
        "max_speed": stats["max_speed"], "outputs": sorted(p.name for p in folder.iterdir()),
    }


def run_simulation(job: Job, folder: Path) -> dict:
    """Run the job's ``SimJob`` with its outputs in ``folder``; its manifest fields."""
    from sim.api import run_job

    return _manifest_fields(run_job(_sim_job(job, folder), keep_frames=False), folder)


def run_simulations(jobs: list[Job], folders: list[Path]) -> list[dict]:
    """Run the jobs' ``SimJob``s as worlds of one solver (``sim.api.simulate_many``; jobs that cannot
    share one run in their own), each job's outputs in its folder; each job's manifest fields. The
    ``sim_fps`` of each is its frames over the whole group's wall time (the group's garment-frames
    a second are the sum over its jobs)."""
    from sim.api import simulate_many

    runs = simulate_many([_sim_job(job, folder) for job, folder in zip(jobs, folders)], keep_frames=False)
    return [_manifest_fields(run, folder) for run, folder in zip(runs, folders)]
