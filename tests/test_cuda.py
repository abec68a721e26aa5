"""The CUDA path (issue 49): a few frames on a CUDA device at the defaults — captured as CUDA graphs,
the search statistics on the device — against the same frames on the CPU; and many worlds on one
GPU. Skipped where Warp sees no CUDA device (CI and this project's machines have none: these run
on a lent GPU, with ``benchmarks/gpu.py``)."""
from __future__ import annotations

import numpy as np
import pytest

from darts.geometry.warp_runtime import warp

wp = warp()
pytestmark = pytest.mark.skipif(not wp.is_cuda_available(), reason="no CUDA device")


def _run(device: str, **options):
    import sim
    from sim.engine.settings import SimSettings

    return sim.simulate("short-sleeve-top", "walk", SimSettings(device=device), frames=6, settle=0.3, winding=True,
                        measure_every=1, **options)


def test_a_few_cuda_frames_match_the_cpus_quality():
    cuda, cpu = _run("cuda"), _run("cpu")
    assert cuda.stable, cuda.message
    assert np.isfinite(cuda.garment).all()
    assert np.linalg.norm(cuda.garment - cpu.garment, axis=2).mean() < 5e-3
    assert cuda.stats["max_penetration"] <= cpu.stats["max_penetration"] + 0.003
    assert cuda.stats["strain_p99"] == pytest.approx(cpu.stats["strain_p99"], rel=0.25, abs=0.01)


def test_the_sweeps_are_captured_as_a_cuda_graph():
    from darts.api import load_body, load_garment, load_motion
    from sim.body_track import build_body_track
    from sim.engine.model import cloth_model
    from sim.engine.settings import SimSettings
    from sim.engine.simulation import Simulation

    body, dart = load_body(), load_garment("short-sleeve-top")
    track = build_body_track(body, load_motion("walk"), 30.0, 0.1)
    model = cloth_model(dart)
    solver = Simulation(model, track.place_rest(model.rest), track.faces, track.vertices[0], SimSettings(device="cuda"))
    for k in range(1, 4):
        solver.step_frame(track.vertices[k])
    assert solver.solver.replay.captured >= 1 and solver.measure().finite


def test_many_worlds_on_one_gpu():
    from sim.api import SimJob, simulate_many
    from sim.engine.settings import SimSettings

    jobs = [SimJob(garment, motion, SimSettings(device="cuda"), frames=4, settle=0.3)
            for garment, motion in [("short-sleeve-top", "walk"), ("long-pants", "squat"), ("short-skirt", "wave")]]
    runs = simulate_many(jobs)
    assert all(run.stable and np.isfinite(run.garment).all() for run in runs)
    assert all(run.stats["max_penetration"] < 0.02 for run in runs)
