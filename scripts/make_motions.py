"""Write the shipped procedural motions to scenes/motions/ (classic SMPL-H AMASS layout, 60 fps)."""
from __future__ import annotations

import argparse
from pathlib import Path

from darts.body.io import load_body
from darts.motion.amass import save_motion
from darts.motion.procedural import MOTIONS, build_motion


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("-o", "--output-dir", default="scenes/motions")
    parser.add_argument("--fps", type=float, default=60.0)
    args = parser.parse_args()
    body = load_body()
    for name in MOTIONS:
        motion = build_motion(name, body, args.fps)
        path = Path(args.output_dir) / f"{name}.npz"
        save_motion(motion, path)
        print(f"{path}: {motion.num_frames} frames, {motion.duration:.2f} s")


if __name__ == "__main__":
    main()
