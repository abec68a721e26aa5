"""Where a photograph's garment ends, against the truth: the lengths read (``darts.photo.lengths``),
the posed line regressor's lines and the template's, each against the true garment's feature lines,
on the posed held-out renders (issue 44: why ``--lengths`` is off by default, and what bounds the
line Chamfer).

    python scripts/evaluate_lengths.py --data ~/.cache/darts/posed-s101 [--out docs/data/photo_lengths_eval.json]

Per picture in which a person is found (BlazePose and the body fit cached as
``scripts/train_outfit_net.py`` caches them, ``~/.cache/darts/outfit_net/<dataset>/fits/``): the
parsing's garment of the picture's kind, read with its category taken as the true one; for each of
the true garment's lines whose end the picture gives (cuffs, a top's hem, a skirt's or dress's hem,
trouser legs), the signed distance (cm) along the true line's axis (``darts.crdl.targets.loop_frame``,
pointing away from the garment: positive = too long) from the true line's centre (the DART before
its run, rest pose on the true body, canonical frame) to
- **read, true body**: the end read (s along the limb) placed on the true body's rest landmarks;
- **read, fitted body**: the same s placed on the fitted body's (what ``--lengths`` targets);
- **regressor**: the posed line regressor's line (``darts.regress.posed_lines``, on the fitted body,
  from the parsed mask: what the reconstruction starts from without ``--lengths``);
- **template, fitted / true body**: the template of the true category on either body.
And per picture the fitted body's rest height, leg (hip to ankle landmark) and arm (shoulder to
wrist) against the true body's. Medians of |e| and of e per kind of line; one core.
"""
from __future__ import annotations

import argparse
import json
import pickle
import sys
from pathlib import Path

import numpy as np

#: the truth's line kinds, as the table groups them
KINDS = ("sleeve cuff", "dress cuff", "top hem", "skirt or dress hem", "long trousers' leg", "shorts' leg")
ESTIMATES = ("read_true_body", "read_fitted_body", "regressor", "template_fitted_body", "template_true_body")


def line_kind(name: str, category: str) -> str:
    if "cuff" in name:
        return "dress cuff" if "dress" in category else "sleeve cuff"
    if name == "hem":
        return "top hem" if category.endswith("top") else "skirt or dress hem"
    return "shorts' leg" if category.startswith("short") else "long trousers' leg"


def measure(record: dict, body) -> dict | None:
    """One cached picture's lines (module docstring), or None without a person or its garment."""
    import torch
    from PIL import Image

    from darts.crdl.targets import loop_frame
    from darts.dart.build import make_dart
    from darts.dart.io import load_dart
    from darts.geometry.loops import feature_lines
    from darts.photo.attributes import ARM, LEG, chain
    from darts.photo.lengths import length_targets, rest_landmarks
    from darts.photo.outfit import KIND_OF, read_outfit
    from darts.regress.posed_lines import regress_posed_lines, template_lines
    from darts.templates.categories import CATEGORIES
    from darts.templates.defaults import DATASET_EASE, DATASET_EDGE_LENGTH

    fit, meta, folder = record["fit"], record["meta"], Path(record["folder"])
    if fit is None:
        return None
    image = np.asarray(Image.open(folder / "image.png").convert("RGB"))
    outfit = read_outfit(image, record["person"], fit, body)
    kind = KIND_OF[meta["category"]]
    garment = outfit.garment(kind) if outfit else None
    if garment is None:
        return None
    truth = load_dart(folder.parent.parent / meta["garment_folder"] / "garment.npz")
    category, names = truth.category, CATEGORIES[truth.category].line_names
    true_lines = feature_lines(truth, truth.vertices)
    centre = np.asarray(truth.vertices, np.float64).mean(0)
    betas = {"true": np.asarray(truth.body_betas, np.float64), "fitted": np.asarray(fit.betas, np.float64)}
    read = {which: length_targets(category, garment.attributes, body, b) for which, b in betas.items()}
    templates = {which: dict(zip(names, template_lines(make_dart(category, body, betas=b, edge_length=DATASET_EDGE_LENGTH,
                                                                 ease=DATASET_EASE), category)))
                 for which, b in betas.items()}
    regressed = regress_posed_lines(image, outfit.mask(kind), fit.camera, body, fit.pose, betas["fitted"].tolist(),
                                    category, np.stack([templates["fitted"][n] for n in names]))
    row = {"sample": f"{folder.parent.name}/{folder.name}", "category": category, "read_category": garment.category,
           "motion": meta.get("motion"), "lines": {}}
    for name, target in read["true"].items():
        if name not in true_lines:
            continue
        c, axis = loop_frame(np.asarray(true_lines[name], np.float64), centre)

        def along(point: np.ndarray, c=c, axis=axis) -> float:
            return round(100 * float((point - c) @ axis), 2)

        row["lines"][name] = {"kind": line_kind(name, category), "s": target["s"],
                              "beyond_picture": target["beyond_picture"],
                              "read_true_body": along(target["point"]), "read_fitted_body": along(read["fitted"][name]["point"]),
                              "regressor": along(regressed[name].mean(0)),
                              "template_fitted_body": along(templates["fitted"][name].mean(0)),
                              "template_true_body": along(templates["true"][name].mean(0))}
    shape = {}
    for which, b in betas.items():
        vertices = body.shaped(None if len(b) == 0 else torch.as_tensor(b, dtype=body.dtype)[None])[0][0]
        points = rest_landmarks(body, b)
        shape[which] = {"height": float(np.ptp(vertices.double().numpy()[:, 1])),
                        "leg": float(np.linalg.norm(np.diff(chain(points, "left", LEG), axis=0), axis=1).sum()),
                        "arm": float(np.linalg.norm(np.diff(chain(points, "left", ARM), axis=0), axis=1).sum())}
    row["body_cm"] = {k: round(100 * (shape["fitted"][k] - shape["true"][k]), 2) for k in shape["true"]}
    row["true_height_m"] = round(shape["true"]["height"], 3)
    return row


def summarise(rows: list[dict]) -> dict:
    """Per kind of line and estimate: count, median |e| and median e (cm); the body's errors."""
    kinds = {}
    for row in rows:
        for entry in row["lines"].values():
            kinds.setdefault(entry["kind"], []).append(entry)
    lines = {}
    for kind in KINDS:
        entries = kinds.get(kind, [])
        if entries:
            lines[kind] = {"lines": len(entries), **{
                estimate: {"median_abs_cm": round(float(np.median(np.abs([e[estimate] for e in entries]))), 2),
                           "median_cm": round(float(np.median([e[estimate] for e in entries])), 2)}
                for estimate in ESTIMATES}}
    body = {k: {"median_abs_cm": round(float(np.median(np.abs([r["body_cm"][k] for r in rows]))), 2),
                "median_cm": round(float(np.median([r["body_cm"][k] for r in rows])), 2),
                "p10_p90_cm": [round(float(v), 1) for v in np.percentile([r["body_cm"][k] for r in rows], [10, 90])]}
            for k in ("height", "leg", "arm")}
    heights = [r["true_height_m"] for r in rows]
    return {"pictures": len(rows), "lines": lines, "body": body,
            "true_height_p10_p50_p90_m": [round(float(v), 3) for v in np.percentile(heights, [10, 50, 90])]}


def table(data: dict) -> list[str]:
    """The docs' table of ``summarise``'s numbers."""
    out = ["| line (lines measured) | read, true body | read, fitted body (`--lengths`) | regressor (default) | "
           "template, fitted body | template, true body |", "|---|---|---|---|---|---|"]
    for kind, entry in data["summary"]["lines"].items():
        cells = [f"{entry[e]['median_abs_cm']:.1f} ({entry[e]['median_cm']:+.1f})" for e in ESTIMATES]
        out.append(f"| {kind} ({entry['lines']}) | " + " | ".join(cells) + " |")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--out", type=Path, default=Path("docs/data/photo_lengths_eval.json"))
    parser.add_argument("--workers", type=int, default=2, help="processes fitting the pictures not yet cached")
    args = parser.parse_args()
    import torch
    from train_outfit_net import fit_all  # scripts/, beside this one

    from darts.body.io import load_body

    torch.set_num_threads(1)
    fits = Path.home() / ".cache" / "darts" / "outfit_net" / args.data.name / "fits"
    fit_all(args.data, fits, args.workers)
    body = load_body(None)
    rows = []
    for path in sorted(fits.glob("*.pkl")):
        row = measure(pickle.loads(path.read_bytes()), body)
        if row is not None:
            rows.append(row)
            print(json.dumps(row), flush=True)
    data = {"command": " ".join(["python", *sys.argv]), "data": str(args.data), "summary": summarise(rows), "rows": rows}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    temporary = args.out.with_suffix(".tmp")
    temporary.write_text(json.dumps(data, indent=1) + "\n")
    temporary.rename(args.out)
    print(json.dumps(data["summary"], indent=1))
    print("\n".join(table(data)))


if __name__ == "__main__":
    main()
