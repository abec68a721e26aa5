"""``darts-sim GARMENT MOTION -o OUT``: drape a DART on the body and simulate it through a motion.

Exit codes: 0 done, 2 bad input (one line, nothing written), 3 the run went unstable (the frames
before it are written, with a message saying where it stopped).
"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from darts import __version__
from darts.body.io import load_body
from darts.cli.errors import OneLineParser, run_guarded
from darts.dart.export import panel_colors
from darts.dart.io import load_dart
from darts.dart.model import MATERIALS, parse_seam_setting
from darts.errors import DartsInputError
from darts.fileio import atomic_path, check_output
from darts.motion.amass import load_motion
from darts.motion.resample import resample
from darts.preview import Animation, check_preview, frames_to_draw, render_preview
from exporters.sequence import SEQUENCE_FORMATS, MeshSequenceWriter
from exporters.usd import USD_SUFFIXES, UsdAnimationWriter
from scenes import garment_help, resolve_garment, resolve_motion, shipped_motions
from sim.body_track import build_body_track
from sim.run import simulate, summary
from sim.settings import SimSettings
from sim.solvers import solver_class, solver_names

UNSTABLE_EXIT = 3


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
    p.add_argument("garment", metavar="GARMENT", help=garment_help())
    p.add_argument("motion", metavar="MOTION", help=f"AMASS .npz or a shipped motion: {', '.join(shipped_motions())}")
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
                   help="substeps per frame (default: " + ", ".join(f"{k} {solver_class(k).default_substeps}" for k in solver_names()) + ")")
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


def _frame_range(args, count: int) -> tuple[int, int]:
    end = args.end if args.end is not None else count
    if args.frames is not None:
        if args.frames < 1:
            raise DartsInputError(None, f"--frames must be >= 1, got {args.frames}")
        end = min(count, args.start + args.frames)
    if not 0 <= args.start < end <= count:
        raise DartsInputError(None, f"frame range [{args.start}, {end}) is empty or outside the motion's {count} frames at --fps")
    return args.start, end


def check_outputs(args) -> None:
    """Every output of the run can be written (``check_output``): ``-o`` (a USD file, or a folder
    for a mesh sequence), ``--stats`` and ``--preview``; else a DartsInputError before any work."""
    out = Path(args.output)
    if out.suffix and out.suffix.lower() not in USD_SUFFIXES:
        raise DartsInputError(out, f"output must end in {', '.join(USD_SUFFIXES)} or be a directory (no suffix)")
    check_output(out, directory=not out.suffix)
    if args.stats:
        check_output(args.stats)
    if args.preview:
        check_preview(args.preview)


def _writer(args):
    out = Path(args.output)
    if out.suffix:
        return UsdAnimationWriter(out, args.fps)
    return MeshSequenceWriter(out, args.fps, args.format)


class _NothingToKeep(Exception):
    """The run went unstable before its first recorded frame: no output is written."""

    def __init__(self, result):
        super().__init__(result.message)
        self.result = result


def _fill(writer, args, dart, track) -> None:
    """Declare the body (grey) and the garment (coloured by panel) on ``writer``."""
    writer.add_mesh("body", track.faces, track.vertices.shape[1], np.full((len(track.faces), 3), 0.8))
    writer.add_mesh("garment", dart.faces, len(dart.vertices), panel_colors(len(dart.panel_names))[dart.panel])
    if args.seam_curves and len(dart.pairs):
        writer.add_curves("garment", dart.pairs)


class _PreviewFrames:
    """The frames a ``--preview`` will draw, kept (float32) as they are written; nothing else is kept."""

    def __init__(self, args, track):
        self.total = len(track.vertices) - track.settle_frames
        self.wanted = set(frames_to_draw(self.total, args.preview).tolist()) if args.preview else set()
        self.seen, self.numbers, self.garment, self.body = 0, [], [], []

    def __call__(self, garment: np.ndarray, body: np.ndarray) -> None:
        if self.seen in self.wanted:
            self.numbers.append(self.seen)
            self.garment.append(garment.astype(np.float32))
            self.body.append(body.astype(np.float32))
        self.seen += 1

    def render(self, args, dart, track) -> None:
        animation = Animation(faces={"body": np.asarray(track.faces), "garment": dart.faces},
                              colors={"body": np.full((len(track.faces), 3), 0.8),
                                      "garment": panel_colors(len(dart.panel_names))[dart.panel]},
                              frames={"garment": np.stack(self.garment), "body": np.stack(self.body)},
                              fps=args.fps, numbers=np.array(self.numbers), total=self.seen)
        render_preview(animation, args.preview, progress=not args.quiet)


def settings_from_args(args) -> SimSettings:
    settings = SimSettings(fps=args.fps, substeps=args.substeps, iterations=args.iterations, solver=args.solver,
                           device=args.device, wind=args.wind, gust=args.gust, ground=not args.no_ground, seed=args.seed,
                           max_speed=args.max_speed, self_contact=not args.no_self_contact,
                           continuous_collision=not args.no_ccd, crease_contacts=not args.no_crease,
                           tethers=not args.no_tethers)
    try:
        settings.check()
    except ValueError as exc:
        raise DartsInputError(None, str(exc)) from None
    if args.settle < 0 or not np.isfinite(args.settle):
        raise DartsInputError(None, f"--settle must be >= 0 seconds, got {args.settle}")
    return settings


@dataclass
class SimOutcome:
    """What one ``darts-sim`` run ended with: its exit code (0 done, 3 unstable), the ``--stats``
    document and, when unstable, the message saying where it stopped."""

    code: int
    stats: dict
    message: str
    wrote: bool


def _shape(args, dart, body) -> tuple[np.ndarray, np.ndarray]:
    """(the DART's own betas, the betas to simulate on), checked against the body."""
    own = np.asarray(dart.body_betas, np.float64)
    if len(own) > body.num_betas:
        raise DartsInputError(args.garment, f"was made for {len(own)} shape coefficients, the body has {body.num_betas}")
    if args.betas is None:
        return own, own
    target = np.asarray(args.betas, np.float64)
    if len(target) > body.num_betas or not np.isfinite(target).all():
        raise DartsInputError(None, f"--betas must be at most {body.num_betas} finite numbers, got {len(target)}")
    return own, target


def execute(args) -> SimOutcome:
    """Run ``darts-sim`` for parsed ``args``: check every input and output, simulate, write the
    output, the stats and the preview. Bad input raises DartsInputError before anything is written."""
    settings = settings_from_args(args)
    check_outputs(args)
    dart = load_dart(resolve_garment(args.garment))
    if args.material:
        dart.material_name, dart.material = args.material, dict(MATERIALS[args.material])
    for text in args.seam:
        dart.set_seam(*parse_seam_setting(text))
    motion = load_motion(resolve_motion(args.motion))
    motion = resample(motion, args.fps) if abs(motion.fps - args.fps) > 1e-9 else motion
    start, end = _frame_range(args, motion.num_frames)
    motion = motion.with_frames(trans=motion.trans[start:end],
                                **{name: arr[start:end] for name, arr in motion.parts().items()})
    body = load_body(args.body)
    if args.device != "cpu":
        _check_device(args.device)
    own, target = _shape(args, dart, body)
    track = build_body_track(body, motion, args.fps, args.settle, betas=target, start_betas=own, progress=not args.quiet)

    preview = _PreviewFrames(args, track)
    try:
        with _writer(args) as writer:
            _fill(writer, args, dart, track)
            def write(garment: np.ndarray, body: np.ndarray) -> None:
                writer.write_frame({"garment": garment, "body": body})
                preview(garment, body)

            result = simulate(dart, track, settings, write, progress=not args.quiet, winding=args.stats is not None)
            if not result.frames:
                raise _NothingToKeep(result)
    except _NothingToKeep as nothing:
        result = nothing.result
    if args.preview and result.frames:
        preview.render(args, dart, track)
    stats = summary(result, settings, len(dart.vertices))
    if args.stats:
        with atomic_path(args.stats) as tmp:
            Path(tmp).write_text(json.dumps(stats, indent=1))
    return SimOutcome(0 if result.stable else UNSTABLE_EXIT, stats, result.message, bool(result.frames))


def _main(argv: list[str] | None) -> int:
    args = parser().parse_args(argv)
    outcome = execute(args)
    if not args.quiet:
        _print_summary(outcome.stats, args.output if outcome.wrote else None)
    if outcome.code == UNSTABLE_EXIT:
        print(f"darts-sim: {outcome.message}", file=sys.stderr)
    return outcome.code


def _check_device(device: str) -> None:
    from darts.geometry.warp_runtime import warp

    wp = warp()
    if device not in [str(d) for d in wp.get_devices()] and not (device == "cuda" and wp.is_cuda_available()):
        raise DartsInputError(None, f"Warp device '{device}' is not available here (devices: "
                              f"{', '.join(str(d) for d in wp.get_devices())})")


def _print_summary(stats: dict, output: str | None) -> None:
    gaps = ", ".join(f"{name} {gap * 1e3:.2f}" for name, gap in stats["max_seam_gap"].items())
    settle = stats["simulated_frames"] - len(stats["frames"])
    print(f"{len(stats['frames'])} frames recorded after {settle} settle frames, {stats['particles']} particles, {stats['solver']} "
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
