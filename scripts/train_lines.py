"""Train a feature-line regressor (ours, or an ablation of Table 1) and write its checkpoint.

    python scripts/train_lines.py --data ~/.cache/darts/dataset-s0 --variant ours|im-stm|p2m-gcn
        [--encoder darts/regress/weights/classifier.pt] [--epochs 40] [--seed 0] [--out ...]
    python scripts/train_lines.py --posed --data ~/.cache/darts/posed-s100 [--epochs 40] [--seed 0] [--out ...]

With ``--encoder`` (the default) the classifier's trained ResNet encoder is shared and frozen: its
feature maps of three augmented copies of every training picture are computed once, so the three
variants differ only in what the paper compares (the spatial transformers) and each trains in
minutes. The last epoch's weights are kept; the validation Chamfer of every epoch is recorded.

``--posed``: the regressor of pictures of posed bodies (``darts.regress.posed_lines``), on a posed
dataset (``darts dataset make --posed``), written to ``lines_posed.pt``; its validation Chamfer is
measured in the posed frame it works in.
"""
from __future__ import annotations

import shlex
import sys
from pathlib import Path

import torch

from darts.checkpoint import save_checkpoint
from darts.regress.data import load_split
from darts.regress.lines import VARIANTS
from darts.regress.posed_lines import load_posed_split
from darts.regress.train import dataset_record, load_checkpoint, train_regressor, training_parser


def main() -> None:
    parser = training_parser(__doc__.splitlines()[0], 40, None)
    parser.add_argument("--variant", choices=VARIANTS, default="ours")
    parser.add_argument("--posed", action="store_true", help="train the posed regressor on a posed dataset")
    parser.add_argument("--encoder", type=Path, default=Path("darts/regress/weights/classifier.pt"),
                        help="a classifier checkpoint whose encoder is shared, frozen ('none': train one end to end)")
    args = parser.parse_args()
    torch.set_num_threads(2)
    out = args.out or Path(f"darts/regress/weights/lines_{'posed' if args.posed else args.variant}.pt")
    if args.posed:
        from darts.body.io import load_body

        body = load_body()
        train, val = load_posed_split(args.data, "train", body), load_posed_split(args.data, "val", body)
    else:
        train, val = load_split(args.data, "train"), load_split(args.data, "val")
    encoder = None if str(args.encoder) == "none" else load_checkpoint(args.encoder, "classifier")[0].encoder
    model, history = train_regressor(args.variant, train, val, args.epochs, args.seed, encoder=encoder)
    record = {"command": "python " + shlex.join(sys.argv), "seed": args.seed, "epochs": args.epochs,
              "encoder": "frozen, from " + str(args.encoder) if encoder is not None else "trained end to end",
              "dataset": dataset_record(args.data), "train_samples": len(train), "val_samples": len(val),
              "loss": history.loss, "val_chamfer_cm": history.validation, "train_seconds": round(history.seconds, 1)}
    if args.posed:
        record["frame"] = "posed root-free (darts.regress.posed_lines); crops around the garment's mask, grey off it"
    save_checkpoint(out, "lines", model, {"variant": args.variant}, record)
    print(f"wrote {out}: validation Chamfer {history.validation[-1]:.3f} cm after {history.seconds / 60:.1f} min")


if __name__ == "__main__":
    main()
