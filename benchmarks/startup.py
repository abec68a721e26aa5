"""Start-up cost of the commands: CPU seconds and peak memory of `darts ... --help`, `darts body info`,
`darts-sim --help` ..., against a baseline revision, and what each command imports.

    python benchmarks/startup.py [--baseline 9c35e5c] [--repeats 7] [--out docs/data/benchmark_startup.json]

Each command runs in a fresh interpreter (``python -m darts.cli.main ...``), once from this tree and
once from a git worktree of ``--baseline`` (the same interpreter and packages, ``PYTHONPATH`` pointing
at the worktree), alternated ``--repeats`` times; the child's CPU time (user + system, from
``wait4``) and peak resident memory are recorded and the median reported. ``python -X importtime``
of this tree names each command's five costliest imports (cumulative microseconds). Timed by CPU,
not by the wall clock: a shared machine's wall clock swings 2x between identical runs.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
from pathlib import Path

from trees import ROOT, run_module, worktree, write_result

COMMANDS = {
    "darts --help": ["darts.cli.main", "--help"],
    "darts body info": ["darts.cli.main", "body", "info"],
    "darts motion info walk": ["darts.cli.main", "motion", "info", "walk"],
    "darts template --help": ["darts.cli.main", "template", "--help"],
    "darts deform --help": ["darts.cli.main", "deform", "--help"],
    "darts reconstruct --help": ["darts.cli.main", "reconstruct", "--help"],
    "darts batch --help": ["darts.cli.main", "batch", "--help"],
    "darts-sim --help": ["sim.cli", "--help"],
}


def costliest_imports(module_args: list[str], count: int = 5) -> list[tuple[str, int]]:
    """The ``count`` top-level imports of this tree's command with the largest cumulative time (us)."""
    done = subprocess.run([sys.executable, "-X", "importtime", "-m", *module_args], cwd=ROOT, capture_output=True,
                          text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    rows = []
    for line in done.stderr.splitlines():
        if line.startswith("import time:") and "|" in line and "cumulative" not in line:
            _, cumulative, name = line.split("|")
            if not name.startswith("  "):  # imported by the command itself, not by another import
                rows.append((name.strip(), int(cumulative)))
    return sorted(rows, key=lambda r: -r[1])[:count]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="9c35e5c",
                        help="git revision to compare with (default: before issue 31's lazy imports)")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--out", type=Path, default=Path("docs/data/benchmark_startup.json"))
    args = parser.parse_args()
    with worktree(args.baseline) as baseline:
        samples = {name: {"now": [], "baseline": []} for name in COMMANDS}
        for _ in range(args.repeats):
            for name, module_args in COMMANDS.items():
                for which, tree in (("now", ROOT), ("baseline", baseline)):
                    samples[name][which].append(run_module(module_args, tree))
    rows = {}
    for name, module_args in COMMANDS.items():
        row = {which: {"cpu_s": statistics.median(s[0] for s in runs), "peak_mib": statistics.median(s[1] for s in runs)}
               for which, runs in samples[name].items()}
        row["speedup"] = row["baseline"]["cpu_s"] / row["now"]["cpu_s"]
        row["costliest_imports_us"] = costliest_imports(module_args)
        rows[name] = row
        print(f"{name:26s} now {row['now']['cpu_s']:.2f} s CPU {row['now']['peak_mib']:4.0f} MiB   "
              f"baseline {row['baseline']['cpu_s']:.2f} s {row['baseline']['peak_mib']:4.0f} MiB   "
              f"{row['speedup']:.1f}x", flush=True)
    write_result(args.out, args.baseline, args.repeats, "commands", rows)


if __name__ == "__main__":
    main()
