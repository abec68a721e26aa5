"""Evaluate the shipped reconstruction networks on a dataset's held-out parts; writes
docs/data/reconstruction.json and the figures of docs/reconstruction.md, prints its tables.

    python scripts/evaluate_reconstruction.py --data ~/.cache/darts/dataset-s0 [--end-to-end 20]

1. Classifier: accuracy on val, test and test_unseen, confusion matrices (figure), on the
   picture as it is and on the garment alone (its mask given: what ``darts reconstruct --mask``
   and ``darts classify --mask`` do).
2. Table 1: Chamfer distance between predicted and ground-truth lines for Upper (the three tops),
   Lower (the two pants) and Skirts (the two skirts and the three dresses: the garments whose tube
   spans both legs, the paper's "dress categories", Fig. 3), for P2M-GCN, Im-Guided STM and ours,
   on test and test_unseen, each line regressed from the true category's F_g. Convention: per
   line, the mean over each set of points of the distance to the nearest point of the other set,
   the two directions averaged; unsquared in cm (and squared in cm^2); then averaged over lines.
   The initial lines F_g (no network) are the reference.
3. Fig. 4: the same per crease (W, LL, RL, LA, RA, N, H).
4. End to end, on ``--end-to-end`` test pictures (evenly over the categories): ``reconstruct``
   (classifier, regressor, CRDL with the silhouette term, the sample's body shape, templates at the
   dataset's 2 cm edges) against the undeformed template on the same body: surface Chamfer to the
   ground-truth draped garment (both directions' mean point-to-surface distance, averaged, cm),
   IoU of the garment's render (the body in front of it) with the input mask; then darts-sim on
   the walk (30 frames after a 0.5 s settle): stability and penetration. Runs on Ray (darts.jobs).
"""
from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
import torch

from darts.jobs import Job, run_jobs
from darts.regress.data import CATEGORY_IDS, load_split
from darts.regress.lines import CREASES, VARIANTS
from darts.regress.losses import chamfer_per_line
from darts.regress.shipped import shipped_model
from darts.regress.train import classify, regress
from darts.templates.categories import CATEGORIES

GROUPS = {"Upper": "top", "Lower": "pants", "Skirts": ("skirt", "dress")}
METHODS = {"p2m-gcn": "P2M-GCN", "im-stm": "Im-Guided STM", "ours": "Ours"}
PARTS = ("test", "test_unseen")
CLASSIFIER_INPUTS = {"picture": "the picture", "garment_alone": "the garment alone (mask given)"}


def group_of(category: str) -> str:
    family = CATEGORIES[category].family
    return next(g for g, f in GROUPS.items() if family in (f if isinstance(f, tuple) else (f,)))


def line_errors(pred: torch.Tensor, samples) -> dict:
    """Per group and per crease: mean unsquared (cm) and squared (cm^2) Chamfer over the real lines."""
    unsquared = chamfer_per_line(pred, samples.lines, squared=False)
    squared = chamfer_per_line(pred, samples.lines, squared=True)
    groups = np.array([group_of(CATEGORY_IDS[c]) for c in samples.categories.tolist()])
    out = {"all": {"cm": float(unsquared[samples.line_mask].mean()), "cm2": float(squared[samples.line_mask].mean())}}
    for group in GROUPS:
        mine = torch.from_numpy(groups == group)[:, None] & samples.line_mask
        out[group] = {"cm": float(unsquared[mine].mean()), "cm2": float(squared[mine].mean())}
        out[group]["creases"] = {CREASES[k]: float(unsquared[mine & (samples.creases == k)].mean())
                                 for k in range(len(CREASES)) if bool((mine & (samples.creases == k)).any())}
    return out


def confusion(predicted: np.ndarray, truth: np.ndarray) -> np.ndarray:
    matrix = np.zeros((len(CATEGORY_IDS), len(CATEGORY_IDS)), int)
    np.add.at(matrix, (truth, predicted), 1)
    return matrix


def end_to_end_job(job: Job, folder: Path) -> dict:
    """Reconstruct one test picture and its undeformed-template baseline, measure both, simulate."""
    from darts.body.io import load_body
    from darts.camera import Camera
    from darts.dart.build import make_dart
    from darts.dart.io import save_dart
    from darts.fileio import read_image, read_npz
    from darts.regress.pipeline import reconstruct
    from darts.regress.quality import reconstruction_measures
    from darts.templates.defaults import DATASET_EASE, DATASET_EDGE_LENGTH
    from sim.api import simulate

    sample = Path(job.inputs["sample"])
    meta = json.loads((sample / "meta.json").read_text())
    body = load_body(None)
    image, mask = read_image(sample / "image.png"), read_image(sample / "mask.png", "L") > 127
    camera = Camera.from_json(sample / "camera.json")
    result = reconstruct(image, body, None, camera, mask, betas=meta["betas"])
    baseline = make_dart(result.report["category"], body, betas=np.asarray(meta["betas"]), edge_length=DATASET_EDGE_LENGTH,
                         ease=DATASET_EASE)
    draped = read_npz(sample / "draped.npz")

    def measure(dart) -> dict:
        return reconstruction_measures(dart, draped, camera, mask, body, meta["betas"])

    save_dart(result.dart, folder / "garment.npz")
    outcome = simulate(result.dart, "walk", output=str(folder / "walk.usdc"), frames=30, keep_frames=False)
    return {"category": meta["category"], "predicted": result.report["category"],
            "probability": result.report["probability"], "times": result.report["times"],
            "ours": measure(result.dart), "template": measure(baseline),
            "sim": {"stable": outcome.stats["stable"], "max_penetration": outcome.stats["max_penetration"],
                    "max_speed": outcome.stats["max_speed"], "sim_fps": outcome.stats["sim_fps"]}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--end-to-end", type=int, default=20, help="test pictures reconstructed end to end")
    parser.add_argument("--out", type=Path, default=Path("docs/data/reconstruction.json"))
    parser.add_argument("--figures", type=Path, default=Path("docs/images"))
    args = parser.parse_args()
    torch.set_num_threads(2)
    parts = {name: load_split(args.data, name) for name in ("val",) + PARTS}
    classifier, classifier_record = shipped_model("classifier", "classifier")
    result = {"classifier": {"record": {k: v for k, v in classifier_record.items() if k not in ("loss",)}}, "lines": {}}
    for name, samples in parts.items():
        result["classifier"][name] = {"samples": len(samples)}
        for mode, garment in (("picture", None), ("garment_alone", samples.masks)):
            predicted = classify(classifier, samples.images, garment).argmax(1)
            result["classifier"][name][mode] = {
                "accuracy": float((predicted == samples.categories).float().mean()),
                "confusion": confusion(predicted.numpy(), samples.categories.numpy()).tolist()}
    for name in PARTS:
        samples = parts[name]
        result["lines"][name] = {"initial F_g": line_errors(samples.initial, samples)}
        for variant in VARIANTS:
            model, record = shipped_model("lines", f"lines_{variant}")
            result["lines"][name][variant] = line_errors(regress(model, samples), samples)
            result["lines"].setdefault("records", {})[variant] = {k: v for k, v in record.items() if k != "loss"}
    test = parts["test"]
    per_category = {c: [f for f, k in zip(test.folders, test.categories.tolist()) if k == i]
                    for i, c in enumerate(CATEGORY_IDS)}
    chosen = [folders[k] for k in range(args.end_to_end) for folders in per_category.values() if k < len(folders)]
    chosen = chosen[: args.end_to_end]
    with tempfile.TemporaryDirectory() as tmp:
        rows = run_jobs([Job(f.name, {"sample": str(f)}) for f in chosen], tmp, end_to_end_job, description="end to end")
    result["end_to_end"] = rows
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    figures(result, args.figures)
    print(tables(result))


def tables(result: dict) -> str:
    """The Markdown tables of docs/reconstruction.md."""
    out = ["| classifier accuracy | val | test | test_unseen |", "|---|---|---|---|"]
    for mode, label in CLASSIFIER_INPUTS.items():
        out.append(f"| {label} | " + " | ".join(f"{100 * result['classifier'][p][mode]['accuracy']:.2f} % "
                                               f"({result['classifier'][p]['samples']})" for p in ("val",) + PARTS) + " |")
    out.append("")
    for part in PARTS:
        lines = result["lines"][part]
        out += [f"**{part}** — Chamfer distance, cm (cm² in brackets)", "",
                "| method | Upper | Lower | Skirts | all |", "|---|---|---|---|---|"]
        for key, label in [("initial F_g", "initial lines F_g (no network)")] + list(METHODS.items()):
            row = lines[key]
            out.append(f"| {label} | " + " | ".join(f"{row[g]['cm']:.2f} ({row[g]['cm2']:.2f})" for g in (*GROUPS, "all")) + " |")
        out.append("")
    rows = [r for r in result["end_to_end"] if r["status"] == "ok"]
    if rows:
        mean = lambda f: np.mean([f(r) for r in rows])  # noqa: E731
        out += [f"| end to end ({len(rows)} test pictures) | surface Chamfer (cm) | mask IoU |", "|---|---|---|"]
        for key, label in (("template", "undeformed template"), ("ours", "reconstructed")):
            chamfer = mean(lambda r, key=key: r[key]["surface_chamfer_cm"])
            out.append(f"| {label} | {chamfer:.2f} | {mean(lambda r, key=key: r[key]['mask_iou']):.3f} |")
        out.append(f"\n{len(rows)} pictures; classified right {sum(r['predicted'] == r['category'] for r in rows)}; "
                   f"darts-sim stable {sum(r['sim']['stable'] for r in rows)}, max penetration "
                   f"{100 * max(r['sim']['max_penetration'] for r in rows):.2f} %")
    return "\n".join(out)


def figures(result: dict, folder: Path) -> None:
    from matplotlib.figure import Figure

    folder.mkdir(parents=True, exist_ok=True)
    figure = Figure(figsize=(12, 10.4))
    for k, (part, mode) in enumerate((p, m) for m in CLASSIFIER_INPUTS for p in PARTS):
        ax = figure.add_subplot(2, 2, k + 1)
        matrix = np.asarray(result["classifier"][part][mode]["confusion"])
        ax.imshow(matrix / np.maximum(matrix.sum(1, keepdims=True), 1), cmap="Blues", vmin=0, vmax=1)
        for (i, j), n in np.ndenumerate(matrix):
            if n:
                ax.text(j, i, str(n), ha="center", va="center", fontsize=7, color="white" if i == j else "black")
        ax.set_xticks(range(len(CATEGORY_IDS)), CATEGORY_IDS, rotation=70, fontsize=7)
        ax.set_yticks(range(len(CATEGORY_IDS)), CATEGORY_IDS if k % 2 == 0 else [], fontsize=7)
        ax.set_xlabel("predicted")
        ax.set_title(f"{part}, {CLASSIFIER_INPUTS[mode]}: {100 * result['classifier'][part][mode]['accuracy']:.2f} %",
                     fontsize=9)
    figure.tight_layout()
    figure.savefig(folder / "reconstruction_confusion.png", dpi=110)
    figure = Figure(figsize=(12, 3.6))
    for k, group in enumerate(GROUPS):
        ax = figure.add_subplot(1, 3, k + 1)
        creases = list(result["lines"]["test"]["ours"][group]["creases"])
        width = 0.8 / len(METHODS)
        for m, (key, label) in enumerate(METHODS.items()):
            values = [result["lines"]["test"][key][group]["creases"][c] for c in creases]
            ax.bar(np.arange(len(creases)) + (m - 1) * width, values, width, label=label)
        ax.set_xticks(range(len(creases)), creases)
        ax.set_title(group)
        ax.set_ylabel("Chamfer (cm)" if k == 0 else "")
        if k == 0:
            ax.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(folder / "reconstruction_creases.png", dpi=110)


if __name__ == "__main__":
    main()
