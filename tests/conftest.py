"""Shared fixtures: the bundled body, helpers to run the CLIs (darts, darts-sim) in-process, and the
hypothesis profiles of the fuzz tests: ``ci`` (derandomised, 25 examples a test; the default) and
``long`` (``HYPOTHESIS_PROFILE=long``, 1,000)."""
from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, settings

from darts.body.io import load_body
from darts.cli.main import main as darts_main
from sim.cli import main as sim_main

if os.environ.get("PYTEST_XDIST_WORKER"):
    # Each xdist worker on one torch thread: two workers with torch's default threads on CI's two
    # cores ran an import test 10x slower than alone (42.9 s against 4.5 s) while the other worker
    # simulated — the guide's rule for worker processes.
    import torch

    torch.set_num_threads(1)

for _name, _examples in (("ci", 25), ("long", 1000)):
    settings.register_profile(_name, max_examples=_examples, derandomize=_name == "ci", deadline=None,
                              suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(scope="session")
def body():
    return load_body()


def _runner(main, capsys):
    def run(*args):
        code = main([str(a) for a in args])
        out = capsys.readouterr()
        return code, out.out, out.err

    return run


@pytest.fixture
def run_darts(capsys):
    """Run `darts ARGS...`; returns (exit code, stdout, stderr)."""
    return _runner(darts_main, capsys)


@pytest.fixture
def run_sim(capsys):
    """Run `darts-sim ARGS...`; returns (exit code, stdout, stderr)."""
    return _runner(sim_main, capsys)
