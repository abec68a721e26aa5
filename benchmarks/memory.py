"""Peak memory of `darts-sim` against the number of frames: frames stream to the exporter.

    python benchmarks/memory.py [--out docs/data/benchmark_memory.json]

Runs the README's main job (short-sleeve top, walk, USD output, self-contact on) in a child
process twice: 120 frames at 30 fps (the baseline) and 600 frames (the same 4 s walk at 150 fps),
and reports each child's peak resident memory (ru_maxrss) and the ratio of the two.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

RUNNER = """
import resource, sys
from sim.cli import main
code = main(sys.argv[1:])
print("PEAK_KIB", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
sys.exit(code)
"""


def peak_mib(fps: int, frames: int, substeps: int, directory: Path) -> float:
    out = directory / f"walk_{frames}.usdc"
    command = [sys.executable, "-c", RUNNER, "short-sleeve-top", "walk", "-o", str(out), "--fps", str(fps),
               "--frames", str(frames), "--substeps", str(substeps), "--quiet"]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    line = next(l for l in done.stdout.splitlines() if l.startswith("PEAK_KIB"))
    return int(line.split()[1]) / 1024.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/data/benchmark_memory.json"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        # The same simulated time step (1/300 s) in both runs: 30 fps x 10 substeps, 150 fps x 2.
        short = peak_mib(30, 120, 10, Path(tmp))
        long = peak_mib(150, 600, 2, Path(tmp))
    result = {"peak_mib_120_frames": short, "peak_mib_600_frames": long, "ratio": long / short}
    print(json.dumps(result, indent=1))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
