"""Simulate the shipped outfits on the walk and the squat (the whole motions, default settings) and
print the outfit table of docs/simulation.md; numbers in docs/data/outfits.json, pictures of the
walk in docs/images/outfit_*.png.

    python scripts/simulate_outfits.py [--jobs 2] [--cache ~/.cache/darts/outfits]

Each run's stats are kept in the cache as it finishes (a stopped run resumes where it stopped);
the table is made from them.
"""
from __future__ import annotations

import argparse
import json
import os
from multiprocessing import Pool
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: name -> garments, inner layer first
OUTFITS = {
    "pants-under-top": ["long-pants", "long-sleeve-top"],
    "skirt-under-tshirt": ["short-skirt", "short-sleeve-top"],
    "dress-under-top": ["sleeveless-dress", "long-sleeve-top"],
}
MOTIONS = ("walk", "squat")


def run_one(job: tuple[str, str, str]) -> dict:
    """One outfit on one motion: its stats in the cache, the walk's preview in docs/images."""
    import torch

    torch.set_num_threads(1)
    import sim

    name, motion, cache = job
    out = Path(cache) / f"{name}_{motion}.json"
    if out.is_file():
        return json.loads(out.read_text())
    preview = ROOT / "docs" / "images" / f"outfit_{name}.png" if motion == "walk" else None
    run = sim.simulate(OUTFITS[name], motion, stats=str(out.with_suffix(".stats.json")), keep_frames=False,
                       preview=None if preview is None else str(preview))
    s = run.stats
    row = {"outfit": name, "garments": OUTFITS[name], "motion": motion, "stable": s["stable"], "message": s["message"],
           "frames": len(s["frames"]), "particles": s["particles"], "sim_fps": s["sim_fps"],
           "max_layer_inside": s.get("max_layer_inside"), "max_layer_inside_closed": s.get("max_layer_inside_closed"),
           "max_layer_crossings": s.get("max_layer_crossings"), "max_penetration": s["max_penetration"],
           "max_penetration_winding": s["max_penetration_winding"], "max_crossings": s["max_self_intersections"],
           "garment_stats": s.get("garments"), "max_waist_slide": s["max_waist_slide"]}
    out.write_text(json.dumps(row, indent=1))
    return row


def table(rows: list[dict]) -> str:
    lines = ["| outfit (inner first) | motion | stable | outer under inner's cloth (max) | outer inside inner closed (max) "
             "| body penetration (max, winding) | crossing edges (max: all, between the garments) | max strain per garment "
             "| sim fps |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        inside = " | ".join(", ".join(f"{100 * v:.2f} %" for v in (r[key] or {}).values())
                            for key in ("max_layer_inside", "max_layer_inside_closed"))
        strain = ", ".join(f"{k} {100 * v['strain_max']:.0f} %" for k, v in (r["garment_stats"] or {}).items())
        lines.append(f"| {' + '.join(r['garments'])} | {r['motion']} | {'yes' if r['stable'] else 'no'} | {inside} | "
                     f"{100 * r['max_penetration']:.2f} %, {100 * (r['max_penetration_winding'] or 0):.2f} % | "
                     f"{r['max_crossings']}, {sum((r['max_layer_crossings'] or {}).values())} | {strain} | {r['sim_fps']:.2f} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--cache", type=Path, default=Path(os.path.expanduser("~/.cache/darts/outfits")))
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "data" / "outfits.json")
    args = parser.parse_args()
    args.cache.mkdir(parents=True, exist_ok=True)
    jobs = [(name, motion, str(args.cache)) for name in OUTFITS for motion in MOTIONS]
    with Pool(args.jobs) as pool:
        rows = pool.map(run_one, jobs, chunksize=1)
    args.out.write_text(json.dumps(rows, indent=1))
    print(table(rows))


if __name__ == "__main__":
    main()
