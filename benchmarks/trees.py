"""Running a command from another revision of this repository, for benchmarks against a baseline.

A revision is checked out as a git worktree (``worktree``) and its module run by the same
interpreter and packages with ``PYTHONPATH`` pointing at it (``run_module``); the child's CPU time
(user + system) and peak resident memory come from ``wait4``. CPU time, not the wall clock: a
shared machine's wall clock swings 2x between identical runs.
"""
from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@contextlib.contextmanager
def worktree(revision: str) -> Iterator[Path]:
    """A detached git worktree of ``revision`` in a temporary directory, removed afterwards."""
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "baseline"
        subprocess.run(["git", "worktree", "add", "--detach", str(tree), revision], cwd=ROOT, check=True,
                       capture_output=True)
        try:
            yield tree
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT, check=True)


def run_module(module_args: list[str], tree: Path) -> tuple[float, float]:
    """(CPU seconds, peak MiB) of ``python -m MODULE ARGS`` run in ``tree`` with ``tree`` first on the
    path; a non-zero exit raises."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    child = subprocess.Popen([sys.executable, "-m", *module_args], cwd=tree, env=env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        raise RuntimeError(f"{' '.join(module_args)} exited {code} in {tree}")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def write_result(out: Path, baseline: str, repeats: int, rows_name: str, rows: dict) -> None:
    """The benchmark's rows as JSON at ``out``, with the baseline revision, the repeats, the Python
    version and the machine's CPU count."""
    result = {"baseline": baseline, "repeats": repeats, "python": sys.version.split()[0], "cpus": os.cpu_count(),
              rows_name: rows}
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1))
