"""Train the garment classifier on a dataset made by `darts dataset make` and write its checkpoint.

    python scripts/train_classifier.py --data ~/.cache/darts/dataset-s0 [--epochs 15] [--seed 0]
        [--out darts/regress/weights/classifier.pt]

Trains on the train part, picks nothing by the test parts: the validation accuracy of every epoch
is recorded, the last epoch's weights are kept. Torch uses both cores (torch.set_num_threads(2)).
"""
from __future__ import annotations

import shlex
import sys

import torch

from darts.checkpoint import save_checkpoint
from darts.regress.data import load_split
from darts.regress.train import dataset_record, train_classifier, training_parser


def main() -> None:
    args = training_parser(__doc__.splitlines()[0], 15, "darts/regress/weights/classifier.pt").parse_args()
    torch.set_num_threads(2)
    train, val = load_split(args.data, "train"), load_split(args.data, "val")
    model, history = train_classifier(train, val, args.epochs, args.seed)
    record = {"command": "python " + shlex.join(sys.argv), "seed": args.seed, "epochs": args.epochs,
              "dataset": dataset_record(args.data), "train_samples": len(train), "val_samples": len(val),
              "loss": history.loss, "val_accuracy": history.validation,
              "val_accuracy_garment_alone": history.validation_alone, "train_seconds": round(history.seconds, 1)}
    save_checkpoint(args.out, "classifier", model, {"classes": 10}, record)
    print(f"wrote {args.out}: validation accuracy {100 * history.validation[-1]:.2f} % after {history.seconds / 60:.1f} min")


if __name__ == "__main__":
    main()
