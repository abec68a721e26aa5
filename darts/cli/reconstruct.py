"""``darts reconstruct IMAGE -o garment.npz`` and ``darts classify IMAGE``: one picture to a DART
(docs/reconstruction.md)."""
from __future__ import annotations

import json
import os
import subprocess
import sys

from darts.crdl import SILHOUETTE_WEIGHTS
from darts.errors import DartsInputError
from darts.fileio import atomic_path, check_output
from darts.templates.defaults import DATASET_EDGE_LENGTH, DEFAULT_EDGE_LENGTH

SIM_SUFFIXES = (".usd", ".usda", ".usdc")


#: environment variables this command set itself (and so does not pass on to darts-sim)
_DEFAULTED: list[str] = []


def _small_tensor_threads() -> None:
    """One OpenMP thread for torch unless the user chose (set before torch is first imported): a
    photograph's tensors are small, and a second thread's spinning cost 13.5 s of CPU against 8.1 s
    for a photograph of two garments (``darts.threads``)."""
    if "OMP_NUM_THREADS" not in os.environ:
        os.environ["OMP_NUM_THREADS"] = "1"
        _DEFAULTED.append("OMP_NUM_THREADS")


def classify(args) -> int:
    _small_tensor_threads()
    from darts import api

    if args.mask is None:  # a photograph: every garment the person wears
        outfit = api.read_outfit(args.image, args.body)
        if args.json:
            print(json.dumps({"garments": [{**g.as_dict(), "probabilities": dict(g.ranked[: args.top])}
                                           for g in outfit.garments], "notes": outfit.notes}, indent=1))
            return 0
        for garment in reversed(outfit.garments):
            others = ", ".join(f"{c} {100 * p:.1f} %" for c, p in garment.ranked[1: args.top])
            line = f"{garment.kind:6s} {garment.category:20s} {100 * garment.probability:6.2f} %"
            print(line + (f"  ({others})" if others else ""))
        for note in outfit.notes:
            print(f"note: {note}")
        return 0
    ranked = api.classify(args.image, args.mask)[: args.top]
    if args.json:
        print(json.dumps([{"category": c, "probability": p} for c, p in ranked], indent=1))
    else:
        for category, probability in ranked:
            print(f"{category:20s} {100 * probability:6.2f} %")
    return 0


def reconstruct(args) -> int:
    _small_tensor_threads()
    from darts import api

    if (args.simulate is None) != (args.sim_out is None):
        raise DartsInputError(None, "--simulate MOTION and --sim-out OUT.usdc go together")
    if not str(args.output).lower().endswith(".npz"):
        return reconstruct_outfit(args)
    check_output(args.output, (".npz",))
    if args.report:
        check_output(args.report)
    if args.sim_out:
        check_output(args.sim_out, SIM_SUFFIXES)
    result = api.reconstruct(args.image, args.category, args.camera, args.mask, args.body, args.betas, args.edge_length,
                             progress=True, silhouette=args.silhouette, silhouette_weight=args.silhouette_weight,
                             accept_low_confidence=args.accept_low_confidence, garment=args.garment,
                             lengths=args.lengths)
    if not result.report["silhouette"]:
        result.report["note"] = ("no mask given or estimated: the CRDL fitted the regressed lines only, without its "
                                 "silhouette term; give the garment's mask (white = garment, the image's size) to use it")
    api.save_garment(result.dart, args.output)
    if args.report:
        with atomic_path(args.report) as tmp:
            tmp.write_text(json.dumps(result.report, indent=1))
    report = result.report
    print(f"{report['category']} ({100 * report['probability']:.1f} %): wrote {args.output}, {report['vertices']} vertices, "
          f"lines fitted to {1e3 * report['crdl']['handle_rmse']:.2f} mm, {100 * report['crdl']['penetration']:.2f} % inside "
          f"the body, {report['times']['total_s']:.1f} s" + ("" if report["silhouette"] else " (no mask: no silhouette term)")
          + (" (garment mask estimated on the fitted body)" if report["mask_estimated"] else "")
          + (" (low confidence, accepted)" if report["low_confidence"] else ""))
    return _simulate(args)


def reconstruct_outfit(args) -> int:
    """``darts reconstruct PHOTO -o OUT_DIR``: every garment of the photograph, an outfit folder."""
    from darts import api

    given = [flag for flag, value in (("--mask", args.mask), ("--camera", args.camera), ("--category", args.category))
             if value]
    if given:
        raise DartsInputError(args.output, f"-o OUT_DIR reads every garment of a photograph given alone; {', '.join(given)} "
                                           "reconstruct one garment: give -o garment.npz")
    check_output(args.output, directory=True)
    if args.report:
        check_output(args.report)
    if args.sim_out:
        check_output(args.sim_out, SIM_SUFFIXES)
    result = api.reconstruct_outfit(args.image, args.body, [args.garment] if args.garment else None, args.betas,
                                    args.edge_length, progress=True, silhouette=args.silhouette,
                                    silhouette_weight=args.silhouette_weight, lengths=args.lengths)
    result.save(args.output, source=str(args.image))
    if args.report:
        with atomic_path(args.report) as tmp:
            tmp.write_text(json.dumps(result.report(), indent=1))
    for name, garment in zip(result.file_names(), result.garments):
        report = garment.report
        unsure = ", ".join(f"{c['category']} {100 * c['probability']:.0f} %" for c in report["top_categories"])
        print(f"{report['garment']}: {report['category']} ({100 * report['probability']:.1f} %): wrote "
              f"{args.output}/{name}, {report['vertices']} vertices, lines fitted to "
              f"{1e3 * report['crdl']['handle_rmse']:.2f} mm, {100 * report['crdl']['penetration']:.2f} % inside the body"
              + (f" (category unsure: {unsure})" if report["low_confidence"] else ""))
    for note in result.outfit.notes:
        print(f"note: {note}")
    print(f"outfit of {len(result.garments)}, inner layer first: darts-sim {args.output} MOTION")
    return _simulate(args)


def _simulate(args) -> int:
    """With --simulate: darts-sim on what was written (a DART or an outfit folder), its exit code."""
    if not args.simulate:
        return 0
    command = [sys.executable, "-m", "sim.cli", str(args.output), args.simulate, "-o", args.sim_out]
    if args.body:
        command += ["--body", args.body]
    environment = {k: v for k, v in os.environ.items() if k not in _DEFAULTED}
    return subprocess.run(command, env=environment).returncode


def add_silhouette_options(parser) -> None:
    """--silhouette and --silhouette-weight (``darts reconstruct``, ``darts deform``)."""
    parser.add_argument("--silhouette", choices=list(SILHOUETTE_WEIGHTS), default="outline",
                        help="the CRDL's silhouette term with a mask: outline (distance field and outline matching, the "
                             "same cost at any picture size; default) or soft (1 - soft IoU of a soft rasteriser, slow)")
    parser.add_argument("--silhouette-weight", type=float, metavar="W",
                        help="weight of the silhouette term (default: "
                             + ", ".join(f"{k} {v:g}" for k, v in SILHOUETTE_WEIGHTS.items()) + ")")


def add_parsers(groups) -> None:
    """Register ``darts reconstruct`` and ``darts classify``."""
    parser = groups.add_parser(
        "reconstruct", help="one picture of a garment to a DART (classifier, feature-line regressor, CRDL)",
        description="Classify the garment in IMAGE (unless --category), regress its feature lines, deform the "
                    "category's template onto them with the CRDL (with the silhouette term when --mask is given) "
                    "and write a DART. Without --camera the picture is a photograph: the person in it is found and "
                    "the body's pose, shape and camera fitted to it (none found: the dataset's default camera with "
                    "--mask, else refused unless --accept-low-confidence); without "
                    "--mask the garment network gives the garment's mask and category; on the fitted body the lines "
                    "are regressed through its pose and the template fitted through it (docs/reconstruction.md).")
    parser.add_argument("image", metavar="IMAGE", help="RGB picture (PNG/JPEG), 224 x 224 or resized to it")
    parser.add_argument("-o", "--output", required=True, metavar="garment.npz|OUT_DIR",
                        help="garment.npz: one DART; OUT_DIR (a folder): every garment of a photograph given alone, "
                             "one DART each, fitted on the same body, with outfit.json (layer order) and report.json: "
                             "darts-sim OUT_DIR MOTION runs them as one outfit")
    parser.add_argument("--mask", metavar="MASK", help="garment mask, the image's size (white = garment): the CRDL's "
                        "silhouette term, and the classifier sees the garment alone")
    parser.add_argument("--camera", metavar="camera.json", help="the picture's camera (docs/crdl.md)")
    add_silhouette_options(parser)
    parser.add_argument("--category", help="skip the classifier")
    parser.add_argument("--lengths", action="store_true",
                        help="of a photograph given alone, move the garment's lines to where its sleeves and hems end in "
                             "the photograph before the CRDL (measured and reported either way; off by default: on "
                             "rendered photographs they made the lines less accurate, docs/reconstruction.md)")
    parser.add_argument("--garment", choices=("upper", "lower", "dress"),
                        help="of a photograph given alone, the garment to reconstruct (default: the outer one, the top "
                             "or the dress; with -o OUT_DIR every garment); the report lists every garment seen")
    parser.add_argument("--accept-low-confidence", action="store_true",
                        help="go on when the classifier's best guess is under 50 %% (the report says low_confidence); "
                             "without it such a picture is refused")
    parser.add_argument("--body", metavar="PATH", help="SMPL-format body (default: the bundled body)")
    parser.add_argument("--betas", type=float, nargs="+", metavar="B", help="body shape (default: the rest shape)")
    parser.add_argument("--edge-length", type=float, default=DATASET_EDGE_LENGTH, metavar="L",
                        help=f"template edge length in metres (default {DATASET_EDGE_LENGTH}, the dataset's; the shipped "
                             f"templates' {DEFAULT_EDGE_LENGTH} costs several times more with --mask)")
    parser.add_argument("--report", metavar="report.json",
                        help="category, probability, regressed lines, the CRDL's numbers and times per stage")
    parser.add_argument("--simulate", metavar="MOTION", help="then simulate the DART: run darts-sim with this motion")
    parser.add_argument("--sim-out", metavar="OUT.usdc", help="darts-sim's output with --simulate")
    parser.set_defaults(run=reconstruct)
    classifier = groups.add_parser(
        "classify", help="the garment categories of a picture, most likely first",
        description="With --mask: the categories of the garment in the mask (the classifier). Without: IMAGE is a "
                    "photograph of a person; every garment they wear (the top and the lower garment, or a dress) with "
                    "its categories, read from what is seen: where cloth gives way to skin along the arms and legs, "
                    "whether the cloth fills the gap between the legs, one cloth or two (docs/reconstruction.md). A "
                    "picture without a person is refused.")
    classifier.add_argument("image", metavar="IMAGE")
    classifier.add_argument("--body", metavar="PATH", help="SMPL-format body fitted to the person (default: the bundled body)")
    classifier.add_argument("--mask", metavar="MASK", help="garment mask (white = garment): classify the garment alone, "
                            "without its background (more robust to unseen backgrounds, docs/reconstruction.md)")
    classifier.add_argument("--top", type=int, default=3, help="how many categories to print (default 3)")
    classifier.add_argument("--json", action="store_true", help="print JSON")
    classifier.set_defaults(run=classify)
