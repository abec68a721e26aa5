"""The fuzz run that ``docs/api.md`` reports: damaged inputs through the commands in child processes
(``tests.fuzz_cases``: native crashes show as signals) and wrong arguments through the Python API
(``tests.fuzz_api``), counted by outcome into ``docs/data/fuzz.json``.

    python scripts/fuzz_report.py                      # 250 cases per kind of input, 1,000 API calls
    python scripts/fuzz_report.py --per-kind 20 --api 100 --out /tmp/fuzz.json

Exit 1 when any case crashed natively, let a traceback out, printed more than one line for exit 2,
or (API) raised anything but one DartsInputError line.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.fuzz_api import call_case  # noqa: E402
from tests.fuzz_cases import KINDS, RandomPick, run_cases  # noqa: E402


def command_counts(kind: str, cases: int) -> tuple[dict, list[dict]]:
    """Outcome counts of ``cases`` damaged inputs of ``kind`` through their commands, and the failures."""
    counts, failures = Counter(), []
    for result in run_cases(kind, 0, cases, timeout=3600.0):
        counts["cases"] += 1
        if "runs" not in result:
            counts["native crashes" if "signal" in result else "other child failures"] += 1
            failures.append({"kind": kind, **result})
            continue
        for run in result["runs"]:
            counts["command runs"] += 1
            if run["exit"] is None:
                counts["tracebacks"] += 1
                failures.append({"kind": kind, "case": result["case"], **run})
            elif run["exit"] == 2 and run["stderr"].count("\n") != 1:
                counts["exit 2 in more than one line"] += 1
                failures.append({"kind": kind, "case": result["case"], **run})
            else:
                counts[f"exit {run['exit']}"] += 1
    return dict(counts), failures


def api_counts(cases: int) -> tuple[dict, list[dict]]:
    """Outcome counts of ``cases`` API calls with one wrong argument, and the failures."""
    counts, failures = Counter(), []
    for seed in range(cases):
        case = call_case(RandomPick(seed))
        counts["cases"] += 1
        outcome = case["outcome"]
        if outcome == "input error" and not case["one_line"]:
            outcome = "input error in more than one line"
        counts[outcome] += 1
        if outcome not in ("returned", "input error"):
            failures.append({"seed": seed, **case})
    return dict(counts), failures


def table(report: dict) -> list[str]:
    """The report as the Markdown table of ``docs/api.md``."""
    rows = ["| input | cases | command runs / calls | exit 0 / returned | exit 2 (one line) / DartsInputError | exit 3 "
            "(unstable) | tracebacks / bare exceptions | native crashes |", "|---|---|---|---|---|---|---|---|"]
    for kind, c in report["commands"].items():
        rows.append(f"| damaged {kind} | {c['cases']} | {c.get('command runs', 0)} | {c.get('exit 0', 0)} | "
                    f"{c.get('exit 2', 0)} | {c.get('exit 3', 0)} | {c.get('tracebacks', 0)} | {c.get('native crashes', 0)} |")
    a = report["api"]
    rows.append(f"| Python API, one wrong argument | {a['cases']} | {a['cases']} | {a.get('returned', 0)} | "
                f"{a.get('input error', 0)} | – | {a.get('bare', 0)} | 0 |")
    total = a["cases"] + sum(c["cases"] for c in report["commands"].values())
    rows.append(f"| **all** | **{total}** | | | | | **{len(report['failures'])} failures** | |")
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--per-kind", type=int, default=250, help="damaged inputs per kind (default 250)")
    parser.add_argument("--api", type=int, default=1000, help="API calls (default 1000)")
    parser.add_argument("--out", default=str(ROOT / "docs" / "data" / "fuzz.json"))
    args = parser.parse_args()
    report, failures, started = {"commands": {}}, [], time.process_time()
    wall = time.monotonic()
    for kind in KINDS:
        report["commands"][kind], found = command_counts(kind, args.per_kind)
        failures += found
        print(kind, report["commands"][kind], flush=True)
    report["api"], found = api_counts(args.api)
    failures += found
    print("api", report["api"], flush=True)
    report.update(failures=failures[:50], command=f"python scripts/fuzz_report.py --per-kind {args.per_kind} --api {args.api}",
                  wall_seconds=round(time.monotonic() - wall), parent_cpu_seconds=round(time.process_time() - started))
    Path(args.out).write_text(json.dumps(report, indent=1) + "\n")
    print("\n".join(table(report)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
