"""Shared fixtures: the bundled body, and helpers to run the CLIs (darts, darts-sim) in-process."""
from __future__ import annotations

import pytest

from darts.body.io import load_body
from darts.cli.main import main as darts_main
from sim.cli import main as sim_main


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
