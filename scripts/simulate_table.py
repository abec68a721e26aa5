"""Simulate every shipped garment on every shipped motion, and every garment with each seam regime;
print the tables of docs/simulation.md and keep the numbers in docs/data/simulation_table.json.

    python scripts/simulate_table.py [--jobs 2] [--garments long-pants,short-pants]

Table 1: default settings, every seam stiff (the DARTs' default), garment x motion (``--motions``,
default ``TABLE_MOTIONS``, the whole motion).
Table 2: the first ``REGIME_SECONDS`` of the walk, with every seam of a garment set to one regime
(welded, loose, repulsive, partial); partial seams are measured on their sprung part (max) and free
part (mean).
"""
from __future__ import annotations

import argparse
import json
from multiprocessing import Pool
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "data" / "simulation_table.json"
PARTIAL = RESULTS.with_suffix(".partial.jsonl")  # rows as they finish, so that a stopped run resumes
REGIME_RUNS = ("welded", "loose", "repulsive", "partial")
REGIME_SECONDS = 2.0
#: table 1's motions: the walk, the squat and the deep poses where the body overlaps itself (issue 46)
TABLE_MOTIONS = ("walk", "squat", "sit", "kneel", "arms_down", "arms_crossed")


def run_one(job: tuple[str, str, str]) -> dict:
    import numpy as np

    from darts.body.io import load_body
    from darts.dart.io import load_dart
    from darts.motion.amass import load_motion
    from scenes import GARMENTS_DIR, MOTIONS_DIR
    from sim.body_track import build_body_track
    from sim.engine.settings import SimSettings
    from sim.run import simulate, summary

    garment, motion, regime = job
    dart = load_dart(GARMENTS_DIR / f"{garment}.npz")
    dart.set_seam("all", regime)
    settings = SimSettings()
    track = build_body_track(load_body(), load_motion(MOTIONS_DIR / f"{motion}.npz"), settings.fps, 0.5,
                             gap=settings.body_gap)
    if regime != "stiff":
        keep = track.settle_frames + int(REGIME_SECONDS * settings.fps)
        track.vertices = track.vertices[:keep]
    result = simulate(dart, track, settings, winding=True)
    stats = summary(result, len(dart.vertices))
    frames = result.frames
    gaps = [gap for frame in frames for gap in frame["seam_gap"].values()]
    row = {"garment": garment, "motion": motion, "regime": regime, "particles": result.particles,
           "frames": len(frames), "sim_fps": result.simulated_frames / result.wall_seconds, "stable": result.stable,
           "max_penetration": max((f["penetration"] for f in frames), default=0.0),
           "max_penetration_outside_body_overlap": max((f["penetration"] - f["penetration_in_body_overlap"]
                                                        for f in frames), default=0.0),
           "max_speed": max((f["max_speed"] for f in frames), default=0.0),
           "max_self_intersections": max((f["self_intersections"] for f in frames), default=0),
           **{key: stats[key] for key in ("max_penetration_winding", "max_penetration_winding_outside_body_overlap",
                                          "strain_mean", "strain_p99", "strain_max",
                                          "max_waist_slide", "max_substep_speed", "max_frame_speed")},
           "max_gap": max((g["sprung_max" if regime == "partial" else "max"] for g in gaps), default=0.0),
           "mean_gap": float(np.mean([g["mean"] for g in gaps])) if gaps else 0.0,
           "open_mean": float(np.mean([g["open_mean"] for g in gaps])) if regime == "partial" and gaps else None,
           "message": result.message}
    print(f"{garment:20s} {motion:14s} {regime:9s} {row['sim_fps']:5.2f} fps  pen {100 * row['max_penetration']:.2f} %"
          f"  gap {1e3 * row['max_gap']:.2f} mm  crossings {row['max_self_intersections']}", flush=True)
    return row


def _percent(fraction: float | None) -> str:
    return "-" if fraction is None else f"{100 * fraction:.2f}"


def markdown(rows: list[dict]) -> str:
    stiff = [r for r in rows if r["regime"] == "stiff"]
    lines = ["| garment | motion | particles | frames | sim fps | strain mean / p99 / max | waist slide (cm) "
             "| penetration: sign / winding (outside the body's overlap) | stable | max stiff seam gap (mm) "
             "| max self-crossing edges |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in stiff:
        waist = "-" if r.get("max_waist_slide") is None else f"{100 * r['max_waist_slide']:.1f}"
        lines.append(f"| {r['garment']} | {r['motion']} | {r['particles']} | {r['frames']} | {r['sim_fps']:.1f} | "
                     f"{100 * r['strain_mean']:.2f} / {100 * r['strain_p99']:.1f} / {100 * r['strain_max']:.0f} % | {waist} | "
                     f"{100 * r['max_penetration']:.2f} ({100 * r['max_penetration_outside_body_overlap']:.2f}) / "
                     f"{100 * r['max_penetration_winding']:.2f} "
                     f"({_percent(r.get('max_penetration_winding_outside_body_overlap'))}) % | "
                     f"{'yes' if r['stable'] else 'no'} | {1e3 * r['max_gap']:.2f} | {r.get('max_self_intersections', '-')} |")
    lines += ["", "| garment (walk) | " + " | ".join(f"{g} max gap (mm)" for g in ("welded", "stiff", "loose", "repulsive"))
              + " | partial sprung max / free mean (mm) | worst penetration | all stable |", "|---|---|---|---|---|---|---|---|"]
    by = {(r["garment"], r["motion"], r["regime"]): r for r in rows}
    for garment in sorted({r["garment"] for r in rows}):
        runs = [by[(garment, "walk", g)] for g in ("welded", "stiff", "loose", "repulsive", "partial")]
        partial = runs[-1]
        lines.append(f"| {garment} | " + " | ".join(f"{1e3 * r['max_gap']:.2f}" for r in runs[:4])
                     + f" | {1e3 * partial['max_gap']:.2f} / {1e3 * (partial['open_mean'] or 0):.1f}"
                     + f" | {100 * max(r['max_penetration'] for r in runs):.2f} % "
                     + f"| {'yes' if all(r['stable'] for r in runs) else 'no'} |")
    return "\n".join(lines)


def main() -> None:
    from darts.shipped import shipped_garments, shipped_motions

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--motions", default=",".join(TABLE_MOTIONS),
                        help=f"motions of table 1 (default {','.join(TABLE_MOTIONS)})")
    parser.add_argument("--keep-regimes", action="store_true",
                        help="rerun only the garment x motion table; keep the regime rows already in the JSON")
    parser.add_argument("--garments", default=",".join(shipped_garments()),
                        help="rerun only these garments' rows; keep the others' already in the JSON (default: all)")
    args = parser.parse_args()
    motions = [m for m in args.motions.split(",") if m in shipped_motions()]
    garments = [g for g in shipped_garments() if g in args.garments.split(",")]
    every = [(g, m, "stiff") for g in shipped_garments() for m in motions]
    every += [(g, "walk", regime) for g in shipped_garments() for regime in REGIME_RUNS]
    jobs = [job for job in every if job[0] in garments and not (args.keep_regimes and job[2] != "stiff")]
    kept = []
    if RESULTS.exists():
        kept = [r for r in json.loads(RESULTS.read_text()) if (r["garment"], r["motion"], r["regime"]) not in jobs]
    done = [json.loads(line) for line in PARTIAL.read_text().splitlines()] if PARTIAL.exists() else []
    finished = {(r["garment"], r["motion"], r["regime"]) for r in done}
    rows = list(done)
    with Pool(args.jobs) as pool, PARTIAL.open("a") as partial:
        for row in pool.imap_unordered(run_one, [j for j in jobs if j not in finished]):
            partial.write(json.dumps(row) + "\n")
            partial.flush()
            rows.append(row)
    rows += kept
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    order = {job: index for index, job in enumerate(every)}
    rows.sort(key=lambda r: order.get((r["garment"], r["motion"], r["regime"]), len(order)))
    RESULTS.write_text(json.dumps(rows, indent=1))
    PARTIAL.unlink()
    print(markdown(rows))


if __name__ == "__main__":
    main()
