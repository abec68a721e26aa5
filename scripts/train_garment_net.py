"""Train the photograph front end's garment network (darts.photo.garment_net) on the posed dataset.

    python scripts/train_garment_net.py --data ~/.cache/darts/posed-s100 [--epochs 15] [--seed 0]
                                        [--out darts/photo/weights/garment_net.pt]

Data: every picture of the train and validation parts of a posed dataset (``darts dataset make
--posed``), each cropped around the person BlazePose finds in it (``find_person``: its mask gives
the crop and the fourth channel, as at run time; a picture without a person is left out) and
cached in ``~/.cache/darts/garment_net/<dataset>.npz`` (made once, then read). Targets: the
garment's mask (``mask.png``) in the crop and the category. Loss: binary cross-entropy plus soft
Dice on the mask, plus cross-entropy on the category. Augmentation: a mirror image half of the
time (categories are symmetric), brightness and contrast x0.8-1.2. Adam (lr 2e-3, cosine to 0),
batches of 32, two torch threads; the checkpoint kept is the epoch with the best validation mask
IoU, and its record holds the command, the data, the seed and the numbers.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import torch


def prepare(data: Path) -> dict[str, np.ndarray]:
    """The cached network inputs [N,4,S,S] (float16), masks [N,S,S] (bool), labels [N] and splits [N]."""
    from PIL import Image

    from darts.photo.garment_net import SIZE, network_input, person_crop
    from darts.photo.person import find_person
    from darts.regress.data import CATEGORY_IDS

    cache = Path.home() / ".cache" / "darts" / "garment_net" / f"{data.name}.npz"
    if cache.is_file():
        return dict(np.load(cache))
    inputs, masks, labels, splits = [], [], [], []
    for split in ("train", "val"):
        for folder in sorted((data / split).glob("g*-*")):
            image = np.asarray(Image.open(folder / "image.png").convert("RGB"))
            person = find_person(image)
            if person is None:
                continue
            crop = person_crop(person.mask)
            if crop is None:
                continue
            garment = (np.asarray(Image.open(folder / "mask.png")) > 127).astype(np.float32)
            inputs.append(network_input(crop, image, person.mask).numpy().astype(np.float16))
            target = network_input(crop, np.repeat((garment * 255).astype(np.uint8)[..., None], 3, 2), garment)[3]
            masks.append(target.numpy() > 0.5)
            labels.append(CATEGORY_IDS.index(json.loads((folder / "meta.json").read_text())["category"]))
            splits.append(split == "val")
    arrays = {"inputs": np.stack(inputs), "masks": np.stack(masks), "labels": np.array(labels), "val": np.array(splits)}
    cache.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(cache, **arrays)
    assert arrays["masks"].shape[1:] == (SIZE, SIZE)
    return arrays


def mask_iou(logits: torch.Tensor, masks: torch.Tensor) -> torch.Tensor:
    found = logits[:, 0] > 0
    return (found & masks).sum((1, 2)) / (found | masks).sum((1, 2)).clamp(min=1)


def main() -> None:
    from darts.checkpoint import save_checkpoint
    from darts.photo.garment_net import GarmentNet
    from darts.regress.data import CATEGORY_IDS
    from darts.regress.train import training_parser

    args = training_parser(__doc__.splitlines()[0], 15, "darts/photo/weights/garment_net.pt").parse_args()

    torch.manual_seed(args.seed)
    torch.set_num_threads(2)
    started = time.time()
    arrays = prepare(args.data)
    inputs = torch.from_numpy(arrays["inputs"].astype(np.float32))
    masks = torch.from_numpy(arrays["masks"])
    labels = torch.from_numpy(arrays["labels"]).long()
    val = torch.from_numpy(arrays["val"])
    train_index = torch.nonzero(~val)[:, 0]
    val_index = torch.nonzero(val)[:, 0]
    config = {"categories": len(CATEGORY_IDS), "width": 12}
    net = GarmentNet(**config)
    optimiser = torch.optim.Adam(net.parameters(), lr=2e-3)
    steps = args.epochs * int(np.ceil(len(train_index) / 32))
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, steps)
    generator = torch.Generator().manual_seed(args.seed)
    best, history = None, []
    for epoch in range(args.epochs):
        net.train()
        order = train_index[torch.randperm(len(train_index), generator=generator)]
        for start in range(0, len(order), 32):
            batch = order[start:start + 32]
            x, m, y = inputs[batch].clone(), masks[batch].float(), labels[batch]
            flip = torch.rand(len(batch), generator=generator) < 0.5
            x[flip], m[flip] = x[flip].flip(-1), m[flip].flip(-1)
            gain = 0.8 + 0.4 * torch.rand(len(batch), 1, 1, 1, generator=generator)
            mean = x[:, :3].mean((1, 2, 3), keepdim=True)
            contrast = 0.8 + 0.4 * torch.rand(len(batch), 1, 1, 1, generator=generator)
            x[:, :3] = ((x[:, :3] - mean) * contrast + mean * gain).clamp(0, 1)
            mask_logits, category_logits = net(x)
            probability = torch.sigmoid(mask_logits[:, 0])
            dice = 1 - (2 * (probability * m).sum((1, 2)) + 1) / (probability.sum((1, 2)) + m.sum((1, 2)) + 1)
            loss = (torch.nn.functional.binary_cross_entropy_with_logits(mask_logits[:, 0], m) + dice.mean()
                    + torch.nn.functional.cross_entropy(category_logits, y))
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            schedule.step()
        net.eval()
        with torch.no_grad():
            outputs = [net(inputs[val_index[k:k + 64]]) for k in range(0, len(val_index), 64)]
        mask_logits = torch.cat([o[0] for o in outputs])
        category_logits = torch.cat([o[1] for o in outputs])
        iou = float(mask_iou(mask_logits, masks[val_index]).mean())
        accuracy = float((category_logits.argmax(1) == labels[val_index]).float().mean())
        history.append({"epoch": epoch + 1, "val_mask_iou": round(iou, 4), "val_accuracy": round(accuracy, 4),
                        "minutes": round((time.time() - started) / 60, 2)})
        print(json.dumps(history[-1]), flush=True)
        if best is None or iou > best["val_mask_iou"]:
            best = history[-1]
            command = f"python scripts/train_garment_net.py --data {args.data} --epochs {args.epochs} --seed {args.seed}"
            record = {"command": command,
                      "data": json.loads((args.data / "summary.json").read_text())["command"],
                      "train_pictures": len(train_index), "val_pictures": len(val_index), "seed": args.seed,
                      "categories": list(CATEGORY_IDS), "best": best, "history": history}
            save_checkpoint(args.out, "garment", net, config, record)
    print(f"best: {json.dumps(best)}; wrote {args.out}")


if __name__ == "__main__":
    main()
