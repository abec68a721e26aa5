"""``darts-sim GARMENT [GARMENT ...] MOTION -o OUT``: drape a DART (or an outfit of several, inner
layer first) on the body and simulate it through a motion.

The command's arguments make a ``sim.api.SimJob`` (``job_from_args``), run by ``sim.api.run_job``
as the Python API and ``darts batch`` run theirs. Only the parser's own needs are imported at
start-up: ``darts-sim --help`` loads neither Warp nor torch.

Exit codes: 0 done, 2 bad input (one line, nothing written), 3 the run went unstable (the frames
before it are written, with a message saying where it stopped).
"""
from __future__ import annotations

import argparse
import shlex
import sys

import numpy as np

from darts import __version__
from darts.cli.errors import OneLineParser, run_guarded
from darts.dart.model import MATERIALS
from darts.shipped import garment_help, motion_help
from exporters.sequence import SEQUENCE_FORMATS
from sim.settings import SimSettings
from sim.solvers import default_substeps, solver_names


def _vector(text: str) -> tuple[float, float, float]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not np.all(np.isfinite(values)):
        raise argparse.ArgumentTypeError(f"expected three numbers X,Y,Z, got '{text}'")
    return values


def parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="darts-sim",
        description="Simulate a DART garment on a body posed by an AMASS motion (Warp cloth solver). "
                    "Output frames are in the AMASS world frame: Z up, metres.")
    p.add_argument("--version", action="version", version=f"darts-sim {__version__}")
    p.add_argument("garment", metavar="GARMENT", nargs="+",
                   help=garment_help() + "; several make an outfit, inner layer first (a top tucked into trousers "
                        "before them, a top worn over them after); an outfit folder (darts reconstruct PHOTO -o "
                        "OUT_DIR) stands for its garments in its layer order")
    p.add_argument("motion", metavar="MOTION", help=motion_help())
    p.add_argument("-o", "--output", metavar="OUT", required=True,
                   help="OUT.usd/.usda/.usdc, or a directory for an OBJ/PLY sequence (see --format)")
    p.add_argument("--format", choices=SEQUENCE_FORMATS, default="obj", help="mesh sequence format (default obj)")
    p.add_argument("--fps", type=float, default=30.0, help="simulation and output frame rate (default 30)")
    p.add_argument("--start", type=int, default=0, help="first motion frame, at --fps (default 0)")
    p.add_argument("--end", type=int, help="last motion frame, exclusive, at --fps (default: the end)")
    p.add_argument("--frames", type=int, help="number of frames from --start")
    p.add_argument("--settle", type=float, default=0.5,
                   help="seconds in which the body blends from its rest pose into the first frame (default 0.5)")
    defaults = SimSettings()
    p.add_argument("--solver", choices=solver_names(), default=defaults.solver, help=f"default {defaults.solver}")
    p.add_argument("--substeps", type=int, default=None,
                   help="substeps per frame (default: " + ", ".join(f"{k} {default_substeps(k)}" for k in solver_names()) + ")")
    p.add_argument("--iterations", type=int, default=defaults.iterations, help="XPBD sweeps per substep (default 2)")
    p.add_argument("--device", default="cpu", help="Warp device: cpu (default) or cuda[:N]")
    p.add_argument("--body", metavar="PATH", help="SMPL/SMPL-H/SMPL-X model file (default: the bundled body)")
    p.add_argument("--betas", type=float, nargs="+", metavar="B",
                   help="body shape to simulate on (default: the shape the DART was made for); the body changes "
                        "from the DART's shape into this one during --settle")
    p.add_argument("--material", choices=sorted(MATERIALS), help="replace the garment's material")
    p.add_argument("--seam", action="append", default=[], metavar="NAME=REGIME[:STIFFNESS]",
                   help="seam regime (welded, stiff, loose, repulsive, partial); NAME 'all' sets every seam")
    p.add_argument("--wind", type=_vector, default=(0.0, 0.0, 0.0), metavar="X,Y,Z", help="wind in m/s (world frame)")
    p.add_argument("--gust", type=float, default=0.0, help="relative gust strength of the wind, 0..1")
    p.add_argument("--no-ground", action="store_true", help="no ground plane at z = 0")
    p.add_argument("--no-self-contact", action="store_true", help="let the garment pass through itself (faster)")
    p.add_argument("--no-ccd", action="store_true",
                   help="push particles inside the body out at the closest body point only, without tracing their "
                        "path back to the face they entered by")
    p.add_argument("--no-tethers", action="store_true",
                   help="xpbd: without the long-range tethers that hold the garment's length over many edges at once "
                        "(it then stretches and waistbands slide unless many more substeps are taken)")
    p.add_argument("--no-crease", action="store_true",
                   help="keep each particle off its closest body face only, not also off a second face within a "
                        "thickness of where that push puts it (creases, where the body overlaps itself)")
    p.add_argument("--max-speed", type=float, default=defaults.max_speed,
                   help=f"m/s; a faster particle stops the run as unstable (default {defaults.max_speed:g})")
    p.add_argument("--seed", type=int, default=0, help="seed of the wind gusts (runs are deterministic)")
    p.add_argument("--seam-curves", action="store_true", help="USD only: draw each seam pair as a curve")
    p.add_argument("--stats", metavar="stats.json", help="write per-frame measurements as JSON")
    p.add_argument("--preview", metavar="PREVIEW", help="also render preview.gif, .mp4 (needs ffmpeg) or .png "
                                                        "(body and garment, shaded, fixed camera)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return p


def job_from_args(args):
    """The ``SimJob`` that parsed ``darts-sim`` arguments describe."""
    from sim.api import SimJob

    settings = SimSettings(fps=args.fps, substeps=args.substeps, iterations=args.iterations, solver=args.solver,
                           device=args.device, wind=args.wind, gust=args.gust, ground=not args.no_ground, seed=args.seed,
                           max_speed=args.max_speed, self_contact=not args.no_self_contact,
                           continuous_collision=not args.no_ccd, crease_contacts=not args.no_crease,
                           tethers=not args.no_tethers)
    garment = args.garment[0] if len(args.garment) == 1 else list(args.garment)
    return SimJob(garment, args.motion, settings, start=args.start, end=args.end, frames=args.frames,
                  settle=args.settle, body=args.body, betas=args.betas, material=args.material, seams=tuple(args.seam),
                  output=args.output, format=args.format, seam_curves=args.seam_curves, stats=args.stats,
                  preview=args.preview)


#: SimSettings fields -> the darts-sim flag that sets them (an "off" flag for the booleans on by default).
_SETTING_FLAGS = {"fps": "--fps", "substeps": "--substeps", "iterations": "--iterations", "solver": "--solver",
                  "device": "--device", "wind": "--wind", "gust": "--gust", "max_speed": "--max-speed", "seed": "--seed",
                  "ground": "--no-ground", "self_contact": "--no-self-contact", "continuous_collision": "--no-ccd",
                  "crease_contacts": "--no-crease", "tethers": "--no-tethers"}


def command_line(job) -> str:
    """The ``darts-sim`` command that runs ``job`` (for the record: ``darts batch`` runs jobs by the
    API); settings left at their defaults are left out."""
    garments = job.garment if isinstance(job.garment, (list, tuple)) else [job.garment]
    argv = [*(str(g) for g in garments), str(job.motion), "-o", str(job.output)]
    defaults = SimSettings()
    for name, flag in _SETTING_FLAGS.items():
        value = getattr(job.settings, name)
        if value == getattr(defaults, name):
            continue
        if isinstance(value, bool):
            argv += [flag]
        else:
            argv += [flag, ",".join(f"{v:g}" for v in value) if isinstance(value, tuple) else f"{value}"]
    options = [("--start", job.start, 0), ("--end", job.end, None), ("--frames", job.frames, None),
               ("--settle", job.settle, 0.5), ("--body", job.body, None), ("--material", job.material, None),
               ("--format", job.format, "obj"), ("--stats", job.stats, None), ("--preview", job.preview, None)]
    argv += [item for flag, value, default in options if value != default
             for item in (flag, f"{value:g}" if isinstance(value, float) else str(value))]
    if job.betas:
        argv += ["--betas", *(f"{b:g}" for b in job.betas)]
    for setting in job.seams:
        argv += ["--seam", setting]
    argv += ["--seam-curves"] if job.seam_curves else []
    return "darts-sim " + shlex.join(argv)


def _main(argv: list[str] | None) -> int:
    from sim.api import run_job

    args = parser().parse_args(argv)
    run = run_job(job_from_args(args), keep_frames=False, progress=not args.quiet)
    if not args.quiet:
        _print_summary(run.stats, args.output if run.stats["frames"] else None)
    if not run.stable:
        print(f"darts-sim: {run.message}", file=sys.stderr)
    return run.exit_code


def _print_summary(stats: dict, output: str | None) -> None:
    gaps = ", ".join(f"{name} {gap * 1e3:.2f}" for name, gap in stats["max_seam_gap"].items())
    settle = stats["simulated_frames"] - len(stats["frames"])
    print(f"{len(stats['frames'])} frames recorded after {settle} settle frames, {stats['particles']} particles, "
          f"{stats['solver']} "
          f"{stats['substeps']} substeps x {stats['iterations']} iterations at {stats['fps']:g} fps")
    print(f"wall {stats['wall_seconds']:.1f} s, {stats['sim_fps']:.2f} simulated frames/s, "
          f"max penetration {100 * stats['max_penetration']:.2f} % of vertices, max speed {stats['max_speed']:.2f} m/s")
    print(f"max seam gap (mm): {gaps or 'no seams'}")
    if output:
        print(f"wrote {output}")


def main(argv: list[str] | None = None) -> int:
    """Console entry point of ``darts-sim``."""
    return run_guarded("darts-sim", _main, argv)


if __name__ == "__main__":
    sys.exit(main())
