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
from sim.engine.settings import SimSettings, user_settings
from sim.engine.solvers import default_substeps, solver_names


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
    p.add_argument("--start", type=int, default=0, help="first motion frame, at --fps (default 0)")
    p.add_argument("--end", type=int, help="last motion frame, exclusive, at --fps (default: the end)")
    p.add_argument("--frames", type=int, help="number of frames from --start")
    p.add_argument("--settle", type=float, default=0.5,
                   help="seconds in which the body blends from its rest pose into the first frame (default 0.5)")
    _add_settings(p)
    p.add_argument("--body", metavar="PATH", help="SMPL/SMPL-H/SMPL-X model file (default: the bundled body)")
    p.add_argument("--betas", type=float, nargs="+", metavar="B",
                   help="body shape to simulate on (default: the shape the DART was made for); the body changes "
                        "from the DART's shape into this one during --settle")
    p.add_argument("--material", choices=sorted(MATERIALS), help="replace the garment's material")
    p.add_argument("--seam", action="append", default=[], metavar="NAME=REGIME[:STIFFNESS]",
                   help="seam regime (welded, stiff, loose, repulsive, partial); NAME 'all' sets every seam")
    p.add_argument("--seam-curves", action="store_true", help="USD only: draw each seam pair as a curve")
    p.add_argument("--stats", metavar="stats.json", help="write per-frame measurements as JSON")
    p.add_argument("--measure-every", type=int, default=10, metavar="N",
                   help="query the body and the garment for penetration, crossings and layer order on every N-th "
                        "recorded frame and the last (default 10; 1: every frame); strain, seams, waist and speeds "
                        "are measured on every frame")
    p.add_argument("--preview", metavar="PREVIEW", help="also render preview.gif, .mp4 (needs ffmpeg) or .png "
                                                        "(body and garment, shaded, fixed camera)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return p


def _add_settings(p: argparse.ArgumentParser) -> None:
    """A flag for every setting users set (``sim.engine.settings.user_settings``: its declaration), its
    value in the field's own name; a switch on by default turned off by its ``--no-...`` flag."""
    for setting in user_settings():
        if setting.kind == "bool":
            p.add_argument(setting.flag, dest=setting.name, action="store_false" if setting.default else "store_true",
                           help=setting.help)
            continue
        options = {"float": {"type": float}, "int": {"type": int}, "str": {},
                   "vector": {"type": _vector, "metavar": "X,Y,Z"}}[setting.kind]
        if setting.name == "solver":
            options["choices"] = solver_names()
        default = ", ".join(f"{k} {default_substeps(k)}" for k in solver_names()) if setting.name == "substeps" \
            else setting.default_text
        p.add_argument(setting.flag, dest=setting.name, default=setting.default, help=f"{setting.help} (default {default})",
                       **options)


def job_from_args(args):
    """The ``SimJob`` that parsed ``darts-sim`` arguments describe."""
    from sim.api import SimJob

    settings = SimSettings(**{setting.name: getattr(args, setting.name) for setting in user_settings()})
    garment = args.garment[0] if len(args.garment) == 1 else list(args.garment)
    return SimJob(garment, args.motion, settings, start=args.start, end=args.end, frames=args.frames,
                  settle=args.settle, body=args.body, betas=args.betas, material=args.material, seams=tuple(args.seam),
                  measure_every=args.measure_every,
                  output=args.output, format=args.format, seam_curves=args.seam_curves, stats=args.stats,
                  preview=args.preview)


def command_line(job) -> str:
    """The ``darts-sim`` command that runs ``job`` (for the record: ``darts batch`` runs jobs by the
    API); settings left at their defaults are left out."""
    garments = job.garment if isinstance(job.garment, (list, tuple)) else [job.garment]
    argv = [*(str(g) for g in garments), str(job.motion), "-o", str(job.output)]
    for setting in user_settings():
        value = getattr(job.settings, setting.name)
        if value == setting.default:
            continue
        if setting.kind == "bool":
            argv += [setting.flag]  # the switch away from the default
        else:
            argv += [setting.flag, ",".join(f"{v:g}" for v in value) if setting.kind == "vector" else f"{value}"]
    options = [("--start", job.start, 0), ("--end", job.end, None), ("--frames", job.frames, None),
               ("--settle", job.settle, 0.5), ("--body", job.body, None), ("--material", job.material, None),
               ("--format", job.format, "obj"), ("--stats", job.stats, None), ("--preview", job.preview, None),
               ("--measure-every", job.measure_every, 10)]
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
