"""``darts dataset make OUT_DIR --count N``: the synthetic training set of the reconstruction networks
(docs/dataset.md), made on Ray, resumable: re-running the same command makes only what is missing.

Exit codes: 0 every job done (garments whose drape left the body are dropped, and counted), 1 some
job failed (see the manifests), 2 bad input.
"""
from __future__ import annotations

import json
import math
from collections import Counter
from functools import partial
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError
from darts.fileio import atomic_path
from darts.jobs import MANIFEST, Job, check_cluster_options, check_out_dir, ray_session, read_manifest, run_jobs
from sim.dataset.recipe import DEFAULT_RECIPE, RECIPES

SUMMARY = "summary.json"


def garment_jobs(count: int, views: int, seed: int, categories: list[str], recipe: int = DEFAULT_RECIPE) -> list[Job]:
    """One job per garment: enough garments for ``count`` samples at ``views`` pictures each."""
    return [Job(f"g{index:05d}", {"seed": seed, "index": index, "categories": categories, "recipe": recipe})
            for index in range(math.ceil(count / views))]


def check_same_dataset(out: Path, seed: int, recipe: int) -> None:
    """A dataset being finished keeps its seed and recipe: else one line, exit 2."""
    from sim.dataset.make import GARMENTS

    for row in read_manifest(out / GARMENTS / MANIFEST).values():  # none before it is begun
        made = (row.get("seed"), row.get("recipe", 1))  # rows from before the versions are recipe 1
        if made != (seed, recipe):
            raise DartsInputError(out, f"was made with --seed {made[0]} --recipe {made[1]}, not --seed {seed} "
                                       f"--recipe {recipe}: finish it with those, or choose another OUT_DIR")


def sample_jobs(garment_rows: list[dict], views: int, unseen: bool = True) -> list[Job]:
    """``views`` pictures of every finished garment in its split; test garments also in test_unseen
    (unless not ``unseen``: the posed dataset has one appearance range)."""
    from sim.dataset.make import GARMENTS

    jobs = []
    for row in garment_rows:
        if row["status"] != "ok":
            continue
        for split in (row["split"], "test_unseen") if row["split"] == "test" and unseen else (row["split"],):
            for view in range(views):
                name = f"{row['id']}-{view}"
                jobs.append(Job(f"{split}-{name}", {"garment_folder": f"{GARMENTS}/{row['id']}", "split": split,
                                                    "view": view}, folder=f"{split}/{name}"))
    return jobs


def _stats(values) -> dict:
    values = np.asarray([v for v in values if v is not None], np.float64)
    if not len(values):
        return {}
    return {"mean": round(float(values.mean()), 3), "median": round(float(np.median(values)), 3),
            "max": round(float(values.max()), 3)}


#: (garment stages timed, garment measures, sample measures) of each kind of dataset's summary
SUMMARY_KEYS = {
    "rest": (("template_s", "crdl_s", "drape_s"), ("drape_penetration", "drape_drop"),
             ("line_boundary_median_px", "line_off_mask_max_px", "line_behind_body")),
    "posed": (("build_s", "simulate_s"), ("penetration", "frame"), ("garment_pixels", "joints_in_view")),
}


def summarise(garments: list[dict], samples: list[dict], args) -> dict:
    """Counts per split and category, times per stage, the garments' and the samples' measures
    (for the rest-pose dataset: drape penetration and drop, how the lines sit on the masks), failures."""
    ok_garments = [r for r in garments if r["status"] == "ok"]
    ok_samples = [r for r in samples if r["status"] == "ok"]
    split_of = {r["id"]: r["split"] for r in samples}
    stages, garment_keys, sample_keys = SUMMARY_KEYS["posed" if args.posed else "rest"]
    return {
        "command": f"darts dataset make OUT_DIR --count {args.count} --seed {args.seed} --views {args.views}"
                   + (f" --categories {' '.join(args.categories)}" if args.categories else "")
                   + (" --posed" if args.posed else "") + (f" --recipe {args.recipe}" if args.recipe != DEFAULT_RECIPE else ""),
        "garments": len(ok_garments), "samples": len(ok_samples),
        "garments_dropped": {r["id"]: r["error"] for r in garments if r["status"] == "unstable"},
        "garments_failed": {r["id"]: r["error"] for r in garments if r["status"] == "failed"},
        "samples_failed": {r["id"]: r["error"] for r in samples if r["status"] != "ok"},
        "samples_per_split": dict(Counter(split_of[r["id"]] for r in ok_samples)),
        "samples_per_category": dict(sorted(Counter(r["category"] for r in ok_samples).items())),
        "garments_per_split": dict(Counter(r["split"] for r in ok_garments)),
        "vertices": _stats(r["vertices"] for r in ok_garments),
        "seconds_per_garment": {stage: _stats(r[stage] for r in ok_garments) for stage in stages}
        | {"wall": _stats(r["wall_seconds"] for r in ok_garments)},
        "seconds_per_sample": {"render": _stats(r["render_s"] for r in ok_samples),
                               "wall": _stats(r["wall_seconds"] for r in ok_samples)},
        "garment_measures": {key: _stats(r[key] for r in ok_garments) for key in garment_keys},
        "sample_measures": {split: {key: _stats(r[key] for r in ok_samples if split_of[r["id"]] == split)
                                    for key in sample_keys}
                            for split in sorted(set(split_of.values()))},
    }


def make(args) -> int:
    from darts.templates.categories import CATEGORIES
    from sim.dataset.make import GARMENTS, make_garment, make_garments, render_sample
    from sim.dataset.posed import make_posed_garment, make_posed_garments
    from sim.dataset.posed_sample import render_posed_sample

    if args.count < 1:
        raise DartsInputError(None, f"--count must be >= 1, got {args.count}")
    if args.views < 1:
        raise DartsInputError(None, f"--views must be >= 1, got {args.views}")
    unknown = [c for c in args.categories or [] if c not in CATEGORIES]
    if unknown:
        raise DartsInputError(None, f"unknown categor{'y' if len(unknown) == 1 else 'ies'} {', '.join(unknown)} "
                                    f"(one of {', '.join(CATEGORIES)})")
    check_cluster_options(args.workers, args.address)
    if args.worlds < 1:
        raise DartsInputError(None, f"--worlds must be >= 1, got {args.worlds}")
    if args.device != "cpu":
        from sim.api import check_device

        check_device(args.device)
    out = Path(args.output)
    check_out_dir(out)
    check_same_dataset(out, args.seed, args.recipe)
    categories = list(dict.fromkeys(args.categories)) if args.categories else list(CATEGORIES)
    with ray_session(args.address, args.workers) as session:
        options = dict(workers=args.workers, retry=args.retry, session=session)
        one, group = (make_posed_garment, make_posed_garments) if args.posed else (make_garment, make_garments)
        garments = run_jobs(garment_jobs(args.count, args.views, args.seed, categories, args.recipe), out / GARMENTS,
                            partial(one, device=args.device), description="garments",
                            group=partial(group, device=args.device) if args.worlds > 1 else None,
                            group_size=args.worlds, **options)
        samples = run_jobs(sample_jobs(garments, args.views, unseen=not args.posed), out,
                           render_posed_sample if args.posed else render_sample, description="samples", **options)
    summary = summarise(garments, samples, args)
    with atomic_path(out / SUMMARY) as tmp:
        tmp.write_text(json.dumps(summary, indent=1))
    print(f"{summary['samples']} samples of {summary['garments']} garments: "
          + ", ".join(f"{k} {v}" for k, v in sorted(summary["samples_per_split"].items())))
    if summary["garments_dropped"]:
        print(f"{len(summary['garments_dropped'])} garments dropped (their drape left the body or blew up)")
    failed = len(summary["garments_failed"]) + len(summary["samples_failed"])
    if failed:
        print(f"{failed} jobs failed; see {out / GARMENTS / MANIFEST} and {out / MANIFEST}")
    print(f"wrote {out / SUMMARY}")
    return 1 if failed else 0


def add_parser(groups) -> None:
    """Register ``darts dataset``."""
    dataset = groups.add_parser("dataset", help="the synthetic dataset of the reconstruction networks")
    commands = dataset.add_subparsers(dest="command", required=True)
    parser = commands.add_parser(
        "make", help="make (or finish making) a dataset of rendered, draped garments",
        description="Make a synthetic dataset (docs/dataset.md): per garment a category, a body shape and CRDL "
                    "edits, a short drape, and --views pictures with masks, camera, feature lines and DART, each "
                    "deterministic from (--seed, index). Runs on Ray; re-running finishes what is missing.")
    parser.add_argument("output", metavar="OUT_DIR")
    parser.add_argument("--count", type=int, required=True, metavar="N",
                        help="pictures in the train, validation and test parts (the test garments are also "
                             "rendered in test_unseen)")
    parser.add_argument("--seed", type=int, default=0, help="dataset seed (default 0)")
    parser.add_argument("--views", type=int, default=2, metavar="V", help="pictures per garment (default 2)")
    parser.add_argument("--recipe", type=int, choices=sorted(RECIPES), default=DEFAULT_RECIPE,
                        help="the edit ranges' version (docs/dataset.md; 2: sleeve and leg lengths up to the elbow and "
                             "the knee; 3: 2 with 1's short sleeves; 4: each length drawn as where the garment ends "
                             "along its body's limb; default 1)")
    parser.add_argument("--categories", nargs="+", metavar="C", help="only these categories (default: all ten)")
    parser.add_argument("--posed", action="store_true",
                        help="the posed dataset: each garment simulated on a shipped motion up to a random frame, with "
                             "another garment worn with it, pictured by a free camera against clutter (docs/dataset.md)")
    parser.add_argument("--device", default="cpu", help="Warp device the drapes and posed runs step on (cpu, cuda[:N]; "
                                                        "default cpu)")
    parser.add_argument("--worlds", type=int, default=1, metavar="N",
                        help="garments per worker whose drapes (or posed runs) step together as worlds of one solver "
                             "(sim.simulate_many; for --device cuda; default 1)")
    parser.add_argument("--address", metavar="ADDR", help="join the Ray cluster at host:port (default: start Ray here)")
    parser.add_argument("--workers", type=int, metavar="N", help="jobs at once (default: one per core)")
    parser.add_argument("--retry", type=int, default=0, metavar="K", help="re-run a job whose worker died, up to K times")
    parser.set_defaults(run=make)
