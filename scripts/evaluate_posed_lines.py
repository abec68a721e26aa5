"""The posed line regressor (``darts.regress.posed_lines``) on held-out posed renders, given the truth
(the garment's mask, the body's pose and shape, the camera): how close its lines come to the
garment's rest lines, against the category's template on the same body.

    python scripts/evaluate_posed_lines.py --data ~/.cache/darts/posed-s101 [--weights lines_posed.pt]
        [--out docs/data/posed_lines_eval.json]

Every split of the dataset (made with a seed nobody trained on). Per picture, Chamfer distance (cm,
unsquared, the two directions averaged, each line resampled to 64 points, the mean over the lines):
- **posed**: the regressor's posed lines against the truth posed the same way (the frame it works in);
  its starting point (the template's lines posed) likewise;
- **rest**: its lines taken back to the rest pose against the garment's rest lines (the DART's), and
  its starting point, the lines of the category's template built on the true body shape (what the
  pipeline deforms), against the same.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

from darts.body.io import load_body
from darts.regress.data import CATEGORY_IDS
from darts.regress.losses import chamfer_per_line
from darts.regress.posed_lines import load_posed_split, unposed
from darts.regress.train import load_checkpoint, regress
from darts.templates.categories import CATEGORIES


def line_chamfer_cm(a: np.ndarray, b: np.ndarray) -> float:
    """Unsquared Chamfer (cm) between lines a and b [L,K,3], the mean over lines."""
    return float(chamfer_per_line(torch.as_tensor(a)[None], torch.as_tensor(b)[None], squared=False).mean())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, required=True)
    parser.add_argument("--weights", type=Path, default=Path("darts/regress/weights/lines_posed.pt"))
    parser.add_argument("--out", type=Path, default=Path("docs/data/posed_lines_eval.json"))
    args = parser.parse_args()
    torch.set_num_threads(1)
    body = load_body()
    model, record = load_checkpoint(args.weights, "lines")
    rows, garments = [], {}
    for split in sorted(p.name for p in args.data.iterdir() if p.is_dir() and p.name != "garments"):
        samples = load_posed_split(args.data, split, body, garments=garments)
        predicted = regress(model, samples).double().numpy()
        for k, folder in enumerate(samples.folders):
            meta = json.loads((folder / "meta.json").read_text())
            category, key = meta["category"], meta["garment_folder"]
            garment, n = garments[key], len(CATEGORIES[category].line_names)
            rest = unposed(body, garment.pose, garment.betas, garment.posing, predicted[k, :n])
            rows.append({"id": samples.ids[k], "split": split, "category": category,
                         "posed_cm": line_chamfer_cm(predicted[k, :n], garment.truth),
                         "posed_initial_cm": line_chamfer_cm(garment.initial, garment.truth),
                         "rest_cm": line_chamfer_cm(rest, garment.rest),
                         "rest_template_cm": line_chamfer_cm(garment.start, garment.rest)})
        print(f"{split}: {len(samples)} pictures", flush=True)
    keys = ("posed_cm", "posed_initial_cm", "rest_cm", "rest_template_cm")
    summary = {"pictures": len(rows), "garments": len(garments), "weights": str(args.weights),
               "weights_command": record.get("command"),
               **{f"{k}_mean": float(np.mean([r[k] for r in rows])) for k in keys},
               **{f"{k}_median": float(np.median([r[k] for r in rows])) for k in keys},
               "rest_better_than_template": int(sum(r["rest_cm"] < r["rest_template_cm"] for r in rows)),
               "per_category": {c: {k: float(np.mean([r[k] for r in rows if r["category"] == c])) for k in keys}
                                for c in CATEGORY_IDS if any(r["category"] == c for r in rows)}}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1))
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
