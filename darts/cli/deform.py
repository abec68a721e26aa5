"""``darts deform``: fit a DART's feature lines to target lines with the CRDL."""
from __future__ import annotations

import json

from darts.cli.reconstruct import add_silhouette_options
from darts.crdl import SOLVERS
from darts.crdl.targets import EDITS
from darts.errors import DartsInputError
from darts.fileio import atomic_path, check_output
from darts.shipped import garment_help


def deform(args) -> int:
    from darts import api

    if (args.lines is None) == (not args.edit):
        raise DartsInputError(None, "darts deform needs either --lines LINES.npz or one or more --edit NAME=METRES")
    if (args.mask is None) != (args.camera is None):
        raise DartsInputError(None, "--mask and --camera go together")
    check_output(args.output, (".npz",))
    if args.report:
        check_output(args.report)
    deformed, report = api.deform(args.garment, args.lines, args.edit, args.body, args.mask, args.camera, args.solver,
                                  args.silhouette_weight, progress=True, silhouette=args.silhouette)
    api.save_garment(deformed, args.output)
    if args.report:
        with atomic_path(args.report) as tmp:
            tmp.write_text(json.dumps(report, indent=1))
    print(f"wrote {args.output}: {args.solver}, {report['iterations']} iterations in {report['wall_seconds']:.2f} s, "
          f"ARAP energy {report['arap_energy']:.4g}, handle RMSE {1e3 * report['handle_rmse']:.2f} mm, "
          f"{100 * report['penetration']:.2f} % of vertices inside the body")
    return 0


def add_parser(groups) -> None:
    """Register ``darts deform``."""
    parser = groups.add_parser(
        "deform", help="deform a DART so that its feature lines reach target lines (the CRDL)",
        description="Deform a DART with the Constrained Rigid Deformation Layer: as rigid as possible (ARAP), "
                    "feature lines on their targets, outside the body. Targets come from --lines or from --edit.")
    parser.add_argument("garment", metavar="GARMENT", help=garment_help())
    parser.add_argument("-o", "--output", required=True, metavar="OUT.npz", help="the deformed DART")
    parser.add_argument("--lines", metavar="LINES.npz",
                        help="target loops: one [K,3] array per line name (canonical frame, Y up, metres)")
    parser.add_argument("--edit", action="append", default=[], metavar="NAME=METRES",
                        help=f"procedural target, repeatable; NAME one of {', '.join(EDITS)} "
                             "(hem/sleeve: lengthen > 0, shorten < 0; the others: widen > 0)")
    parser.add_argument("--mask", metavar="MASK.png", help="garment silhouette seen by --camera (white = garment)")
    parser.add_argument("--camera", metavar="CAMERA.json", help="pinhole camera of the mask (see docs/crdl.md)")
    add_silhouette_options(parser)
    parser.add_argument("--solver", choices=SOLVERS, default="local-global",
                        help="local-global (fast, default) or adam (the paper's optimiser)")
    parser.add_argument("--report", metavar="REPORT.json",
                        help="write arap_energy, handle_rmse (m), penetration, iterations, wall_seconds")
    parser.add_argument("--body", metavar="PATH",
                        help="the SMPL-format body the DART was made for (default: the bundled body; the shape "
                             "comes from the DART)")
    parser.set_defaults(run=deform)
