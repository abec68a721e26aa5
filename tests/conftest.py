"""Shared fixtures: the bundled body, and helpers to run the CLIs in-process."""
from __future__ import annotations

import numpy as np
import pytest

from darts.body.io import load_body
from darts.cli.main import main as darts_main


@pytest.fixture(scope="session")
def body():
    return load_body()


@pytest.fixture
def run_darts(capsys):
    """Run `darts ARGS...`; returns (exit code, stdout, stderr)."""

    def run(*args):
        code = darts_main([str(a) for a in args])
        out = capsys.readouterr()
        return code, out.out, out.err

    return run
