"""`darts-sim` as users run it, against the default of an earlier revision: process CPU time and
quality of whole commands (issue 46: the 6k top on the walk with ``--stats``, against main at b1a32ab).

    python benchmarks/command_speed.py [--baseline b1a32ab] [--scenes short-sleeve-top:walk ...]
                                       [--repeats 3] [--out docs/data/benchmark_command_speed.json]

Each scene's command, ``darts-sim GARMENT MOTION -o OUT.usdc --stats STATS.json`` at the defaults,
runs in a fresh interpreter from this tree and from a git worktree of ``--baseline`` (the same
interpreter and packages), the two alternated ``--repeats`` times after one short untimed run of
each (Warp compiles its kernels once per source); the child's CPU time (user + system) is the
measure, median over the repeats, and includes everything the command does: start-up, the body
track, the tethers, the settle, every frame, the measures ``--stats`` takes, the USD file.
Quality is each tree's ``--stats`` summary with every recorded frame measured (the baseline measures
every frame; this tree is run once more with ``--measure-every 1``, untimed, since by default it
measures every 10th): strain mean / p99 / max over the run, penetration by the closest point's
sign and by the winding number (worst frame), the largest stiff-seam gap (m) and the most crossing
edges in a frame. Runs are deterministic, so one quality run per tree says it.
"""
from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from pathlib import Path

from trees import ROOT, run_module, worktree, write_result

#: Issue 46's measure: the 6k short-sleeve top on the walk.
SCENES = ("short-sleeve-top:walk",)
QUALITY = ("strain_mean", "strain_p99", "strain_max", "max_penetration", "max_penetration_winding",
           "max_self_intersections")


def command(scene: str, out: Path, extra: tuple[str, ...] = ()) -> list[str]:
    garment, motion = scene.split(":")
    return ["sim.cli", garment, motion, "-o", str(out / "out.usdc"), "--stats", str(out / "stats.json"), *extra]


def quality(stats_path: Path) -> dict:
    stats = json.loads(stats_path.read_text())
    row = {key: stats[key] for key in QUALITY}
    row["max_seam_gap"] = max(stats["max_seam_gap"].values(), default=0.0)
    row["simulated_frames"] = stats["simulated_frames"]
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="b1a32ab", help="git revision to compare with (default: issue 46's)")
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), metavar="GARMENT:MOTION")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path("docs/data/benchmark_command_speed.json"))
    args = parser.parse_args()
    rows = {}
    with worktree(args.baseline) as baseline, tempfile.TemporaryDirectory() as tmp:
        trees = {"now": ROOT, "baseline": baseline}
        out = {which: Path(tmp) / which for which in trees}
        for folder in out.values():
            folder.mkdir()
        for scene in args.scenes:
            for which, tree in trees.items():  # compile the kernels, untimed
                run_module(command(scene, out[which], ("--frames", "2")), tree)
            cpu = {which: [] for which in trees}
            for _ in range(args.repeats):
                for which, tree in trees.items():
                    cpu[which].append(run_module(command(scene, out[which]), tree)[0])
            measured = {"baseline": quality(out["baseline"] / "stats.json")}
            run_module(command(scene, out["now"], ("--measure-every", "1")), ROOT)
            measured["now"] = quality(out["now"] / "stats.json")
            row = {which: {"cpu_s": statistics.median(cpu[which]), "cpu_s_runs": cpu[which], **measured[which]}
                   for which in trees}
            row["speedup"] = row["baseline"]["cpu_s"] / row["now"]["cpu_s"]
            rows[scene] = row
            print(f"{scene}: now {row['now']['cpu_s']:.1f} s CPU, baseline {row['baseline']['cpu_s']:.1f} s: "
                  f"{row['speedup']:.2f}x", flush=True)
            for which in trees:
                print(f"  {which:8s}", {key: row[which][key] for key in (*QUALITY, "max_seam_gap")}, flush=True)
    write_result(args.out, args.baseline, args.repeats, "scenes", rows)


if __name__ == "__main__":
    main()
