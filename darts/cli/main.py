"""The ``darts`` command: body and motion tools.

    darts body info [--body PATH] [--betas B ...] [--json]
    darts body export -o body.npz [--body PATH] [--betas B ...]
    darts body pose MOTION -o OUT.npz [--fps F] [--body PATH] [--betas B ...] [--ground]
    darts motion info MOTION [--json]
    darts template CATEGORY -o garment.npz [--edge-length L] [--seam NAME=REGIME[:STIFFNESS]] [--accessory collar|tie]
                   [--seat-ease M]
    darts template --list
    darts inspect garment.npz [--json] [--png out.png]
    darts export garment.npz -o out.obj|ply|glb
    darts import mesh.obj|ply|stl|glb|usd -o garment.npz [--category C] [--units mm|cm|m] [--up y|z]
                 [--report r.json] [--png p.png]

MOTION is an AMASS-format .npz, or the name of a shipped motion (walk, run, wave, jumping_jacks,
twist, squat). Bad input prints one ``darts: error: FILE: problem`` line and exits with code 2.
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from darts import __version__
from darts.body.io import export_smpl_npz, read_body
from darts.cli.deform import add_parser as add_deform_parser
from darts.cli.errors import OneLineParser, run_guarded
from darts.cli.garment import add_parsers as add_garment_parsers
from darts.cli.importer import add_parser as add_import_parser
from darts.cli.reconstruct import add_parsers as add_reconstruct_parsers
from darts.errors import DartsInputError
from darts.fileio import check_output, save_npz
from darts.motion.amass import load_motion
from darts.shipped import motion_help, resolve_motion, shipped_motions


def _add_body_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--body", metavar="PATH",
                        help="SMPL / SMPL-H / SMPL-X model file (.pkl or .npz); default: the bundled body")
    parser.add_argument("--betas", type=float, nargs="+", metavar="B", help="shape coefficients (at most the model's count)")


def _positive_fps(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"fps must be positive, got {text}")
    return value


def _check_betas(model, betas) -> None:
    if betas is not None and len(betas) > model.num_betas:
        raise DartsInputError(None, f"--betas has {len(betas)} values, the body has {model.num_betas} shape directions")
    if betas is not None and not np.isfinite(betas).all():
        raise DartsInputError(None, "--betas must be finite numbers")


def body_info(args) -> int:
    model = read_body(args.body)
    _check_betas(model, args.betas)
    vertices, joints = model.shaped(args.betas)
    names = model.joint_names
    info = {
        "name": model.name, "kind": model.kind, "gender": model.gender,
        "vertices": model.num_vertices, "faces": int(len(model.faces)), "joints": model.num_joints,
        "betas": model.num_betas, "pose_correctives": model.posedirs is not None,
        "height_m": round(float(vertices[:, 1].max() - vertices[:, 1].min()), 4),
        "joint_names": names, "parents": model.parents.tolist(),
    }
    if args.json:
        print(json.dumps(info, indent=1))
        return 0
    print(f"body        {info['name']} ({info['kind']}, {info['gender']})")
    print(f"vertices    {info['vertices']}\nfaces       {info['faces']}\njoints      {info['joints']}")
    print(f"betas       {info['betas']}\ncorrectives {'yes' if info['pose_correctives'] else 'none (posedirs zero)'}")
    print(f"height      {info['height_m']:.3f} m (rest pose, canonical frame, Y up)")
    for i, name in enumerate(names):
        parent = names[model.parents[i]] if model.parents[i] >= 0 else "-"
        print(f"  {i:2d} {name:16s} parent {parent:16s} at {np.round(joints[i].astype(float), 3).tolist()}")
    return 0


def body_export(args) -> int:
    check_output(args.output, (".npz",))
    model = read_body(args.body)
    _check_betas(model, args.betas)
    export_smpl_npz(model, args.output, betas=args.betas)
    print(f"wrote {args.output} ({model.num_vertices} vertices, {model.num_joints} joints)")
    return 0


def body_pose(args) -> int:
    from darts import api
    from darts.motion.posing import motion_betas

    check_output(args.output, (".npz",))
    model = api.load_body(args.body)
    _check_betas(model, args.betas)
    motion = api.load_motion(args.motion, args.fps)
    started = time.perf_counter()
    vertices, joints = api.pose(motion, model, betas=args.betas, ground=args.ground, progress=True)
    if not (np.isfinite(vertices).all() and np.isfinite(joints).all()):
        raise DartsInputError(args.motion, "posing produced NaN or infinite vertices")
    save_npz(args.output, vertices=vertices, joints=joints, faces=model.faces.astype(np.int32),
             fps=np.array(motion.fps), betas=motion_betas(model, motion, args.betas),
             frame=np.array("AMASS world: Z up, metres"))
    print(f"wrote {args.output}: {motion.num_frames} frames at {motion.fps:g} fps, "
          f"{model.num_vertices} vertices ({time.perf_counter() - started:.1f} s); "
          f"lowest point z = {vertices[..., 2].min():.3f} m")
    return 0


def motion_info(args) -> int:
    path = resolve_motion(args.motion)
    motion = load_motion(path)
    info = {
        "path": str(path), "format": motion.source_format, "frames": motion.num_frames,
        "fps": motion.fps, "duration_s": round(motion.duration, 4), "gender": motion.gender,
        "joints": {name: int(arr.shape[1]) for name, arr in motion.parts().items()},
        "betas": 0 if motion.betas is None else int(motion.betas.size),
        "travel_m": round(float(np.linalg.norm(motion.trans[-1, :2] - motion.trans[0, :2])), 4),
    }
    if args.json:
        print(json.dumps(info, indent=1))
        return 0
    for key, value in info.items():
        print(f"{key:11s} {value}")
    return 0


def render(args) -> int:
    from darts.preview import check_preview, read_usd_animation, render_preview

    check_preview(args.output)
    animation = read_usd_animation(args.usd)
    drawn = render_preview(animation, args.output, max_frames=args.max_frames, progress=True)
    print(f"wrote {args.output}: {drawn} of {animation.count} frames")
    return 0


#: Entry-point group of commands that other packages add to ``darts`` (``darts batch`` and
#: ``darts dataset`` come from ``sim``: they run the solver, which ``darts`` itself never imports).
PLUGIN_GROUP = "darts.commands"


def _add_plugin_parsers(groups) -> None:
    from importlib.metadata import entry_points

    for entry in sorted(entry_points(group=PLUGIN_GROUP), key=lambda e: e.name):
        entry.load()(groups)


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="darts", description="DARTs: bodies, motions and garment templates.",
                                     epilog=f"shipped motions: {', '.join(shipped_motions())}")
    parser.add_argument("--version", action="version", version=f"darts {__version__}")
    groups = parser.add_subparsers(dest="group", required=True)

    body = groups.add_parser("body", help="the SMPL-format body model").add_subparsers(dest="command", required=True)
    info = body.add_parser("info", help="vertex/face/joint counts, joint names, height")
    _add_body_args(info)
    info.add_argument("--json", action="store_true", help="print JSON")
    info.set_defaults(run=body_info)
    export = body.add_parser("export", help="write the body in the official SMPL .npz layout")
    _add_body_args(export)
    export.add_argument("-o", "--output", required=True, metavar="OUT.npz")
    export.set_defaults(run=body_export)
    pose = body.add_parser("pose", help="pose the body by an AMASS motion (vertices and joints in Z-up world)")
    pose.add_argument("motion", metavar="MOTION", help=motion_help())
    pose.add_argument("-o", "--output", required=True, metavar="OUT.npz")
    pose.add_argument("--fps", type=_positive_fps, help="resample to this frame rate")
    pose.add_argument("--ground", action="store_true", help="shift the sequence so its lowest point touches z = 0")
    _add_body_args(pose)
    pose.set_defaults(run=body_pose)

    motion = groups.add_parser("motion", help="AMASS-format motions").add_subparsers(dest="command", required=True)
    minfo = motion.add_parser("info", help="format, frames, fps, duration, joints")
    minfo.add_argument("motion", metavar="MOTION", help=motion_help())
    minfo.add_argument("--json", action="store_true", help="print JSON")
    minfo.set_defaults(run=motion_info)
    add_garment_parsers(groups, _add_body_args)
    add_import_parser(groups, _add_body_args)
    add_deform_parser(groups)
    add_reconstruct_parsers(groups)
    _add_plugin_parsers(groups)
    preview = groups.add_parser("render", help="render a darts-sim USD result (the body and every garment, fixed camera)")
    preview.add_argument("usd", metavar="OUT.usd", help="a USD file written by darts-sim")
    preview.add_argument("-o", "--output", required=True, metavar="PREVIEW",
                         help="preview.gif, preview.mp4 (needs ffmpeg) or preview.png (contact sheet of 6 frames)")
    preview.add_argument("--max-frames", type=int, default=60, help="frames drawn, evenly spaced (default 60)")
    preview.set_defaults(run=render)
    return parser


def _main(argv: list[str] | None) -> int:
    args = build_parser().parse_args(argv)
    return args.run(args)


def main(argv: list[str] | None = None) -> int:
    """Console entry point of ``darts``."""
    return run_guarded("darts", _main, argv)


if __name__ == "__main__":
    sys.exit(main())
