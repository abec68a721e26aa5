"""Train the network that decides a photograph's garments from the parsing (darts.photo.outfit_net).

    python scripts/train_outfit_net.py --data ~/.cache/darts/posed-s100x6 [~/.cache/darts/posed-s102x4 ...]
                                       [--epochs 40] [--seeds 0 1 2 3 4 5] [--width 16] [--workers 2] [--misalign 0]
                                       [--within-recipe R]
                                       [--out darts/photo/weights/outfit_net.pt]
    python scripts/train_outfit_net.py --data ~/.cache/darts/posed-s101 --evaluate
    python scripts/train_outfit_net.py --data ~/.cache/darts/posed-s100x6 ~/.cache/darts/posed-s102x4 --weights

Several ``--data`` folders are one dataset: their train parts train, their validation and test
parts (garments never trained on) validate.

Data: every picture of the posed datasets (shipped: ``darts dataset make DIR --count 2400 --seed 100
--posed --views 6``, ``--count 2400 --seed 102 --posed --views 4``, the same with ``--seed 103`` and
with ``--seed 105 --recipe 2``, ``--within-recipe`` not given: the garment worn and
``meta.json``'s ``other`` garment with it, posed bodies, free cameras, clutter), read as a
photograph is: BlazePose's person, the body fitted to it (``darts.photo.fit``), the parsing
(``darts.photo.parsing``) and its measurements both ways (``darts.photo.attributes.measure``),
which give the network's inputs. A picture without a person is left out. The person and the fit
(about 1 s a picture) are cached per picture in
``~/.cache/darts/outfit_net/<dataset>/fits/`` (resumable, ``--workers`` processes of one torch
thread), the inputs in ``inputs.npz`` beside them (``--rebuild-inputs`` after a change to the
parsing or the measurements).

Targets, from the outfit worn: one piece (a dress) or two; the sleeves of the top or the dress;
the lower garment long or short, skirt or trousers (a dress has no lower-garment targets).
Loss: the sum of the heads' cross-entropies over the targets a picture has. Augmentation: the
mirror image half of the time (both maps); with ``--misalign P`` also each picture's parsing shifted
by up to P map pixels against the fitted body's zones (``misalign``: a body fit a little off the
person, as on real photographs; not in the shipped network's recipe yet: on the three datasets
s100x6, s102x4 and s103x4 with P = 2 five of six seeds' validation scores rose 0.7-1.7 points (one
fell 0.1), the six seeds' 89.5 -> 90.4 %, but the held-out renders and the development photographs did not follow,
``docs/reconstruction.md``). AdamW (lr 2e-3, weight decay 1e-3, cosine to 0), batches of 32;
each seed's network is kept at its epoch with the best validation score (the share of the
validation part's garments, both of each picture, whose category is right); the networks of all
``--seeds`` ship together (``darts.photo.outfit_net.OutfitEnsemble``: their probabilities
averaged), and the record holds the command, the data, each seed's numbers and the ensemble's.
"""
from __future__ import annotations

import argparse
import json
import pickle
import sys
import time
from pathlib import Path

import numpy as np

#: each category's targets: (kind, sleeves) or ("lower", (long, skirt))
TARGETS = {"long-sleeve-top": ("upper", 2), "short-sleeve-top": ("upper", 1), "sleeveless-top": ("upper", 0),
           "long-sleeve-dress": ("dress", 2), "short-sleeve-dress": ("dress", 1), "sleeveless-dress": ("dress", 0),
           "long-pants": ("lower", (1, 0)), "short-pants": ("lower", (0, 0)), "long-skirt": ("lower", (1, 1)),
           "short-skirt": ("lower", (0, 1))}


def targets(categories: list[str]) -> dict[str, int]:
    """Per head (``outfit_net.HEADS``) the class of the outfit of ``categories``; -1: none."""
    out = {"one_piece": -1, "sleeves": -1, "long": -1, "skirt": -1}
    for category in categories:
        kind, value = TARGETS[category]
        if kind == "lower":
            out["one_piece"] = 0
            out["long"], out["skirt"] = value
        else:
            out["one_piece"], out["sleeves"] = int(kind == "dress"), value
    return out


def _fit_pictures(job: tuple[list[Path], Path]) -> int:
    """Cache BlazePose's person and the body fit of each picture folder (one process)."""
    import torch
    from PIL import Image

    from darts.body.io import load_body
    from darts.photo.fit import fit_body
    from darts.photo.person import find_person

    torch.set_num_threads(1)
    folders, cache = job
    body = load_body(None)
    for folder in folders:
        target = cache / f"{folder.parent.name}__{folder.name}.pkl"
        if target.exists():
            continue
        image = np.asarray(Image.open(folder / "image.png").convert("RGB"))
        person = find_person(image)
        fit = fit_body(person, body, image.shape[1], image.shape[0]) if person is not None else None
        meta = json.loads((folder / "meta.json").read_text())
        temporary = target.with_suffix(".tmp")
        temporary.write_bytes(pickle.dumps({"folder": str(folder), "meta": meta, "person": person, "fit": fit}))
        temporary.rename(target)
    return len(folders)


def fit_all(data: Path, cache: Path, workers: int) -> None:
    """Every picture of ``data`` fitted into ``cache`` (resumable)."""
    from multiprocessing import get_context

    cache.mkdir(parents=True, exist_ok=True)
    folders = sorted(p.parent for p in data.glob("*/g*-*/image.png"))
    todo = [f for f in folders if not (cache / f"{f.parent.name}__{f.name}.pkl").exists()]
    print(f"{len(folders)} pictures, {len(todo)} to fit", flush=True)
    if todo:
        with get_context("spawn").Pool(workers) as pool:
            pool.map(_fit_pictures, [(todo[k::workers], cache) for k in range(workers)])


def build_inputs(cache: Path) -> dict[str, np.ndarray]:
    """The network's inputs and targets of every cached fit with a person: ``maps`` [N,C,M,M] and
    ``thighs`` [N,C,T,T] float16, ``scalars`` [N,S], a target per head [N], the rules' probabilities
    per head (``rules_<head>`` [N,classes]), ``val`` [N] bool, ``samples``, ``outfits``."""
    from PIL import Image

    from darts.body.io import load_body
    from darts.body.segmentation import body_segmentation
    from darts.photo.attributes import measure
    from darts.photo.outfit_net import HEADS
    from darts.photo.parsing import parse_person
    from darts.photo.rules import rule_probabilities

    body = load_body(None)
    parts = body_segmentation(body)
    arrays = {"maps": [], "thighs": [], "scalars": [], "val": [], "samples": [], "outfits": []}
    heads = {name: [] for name in targets([])}
    rules = {name: [] for name in HEADS}
    for path in sorted(cache.glob("*.pkl")):
        record = pickle.loads(path.read_bytes())
        person, fit, meta = record["person"], record["fit"], record["meta"]
        if person is None:
            continue
        image = np.asarray(Image.open(Path(record["folder"]) / "image.png").convert("RGB"))
        parsing = parse_person(image, person.mask, person.landmarks, person.visibility, fit.vertices,
                               np.asarray(body.faces), parts, fit.posed_camera)
        if parsing is None:
            continue
        measured = measure(parsing, person.landmarks, person.visibility)
        maps, thighs, scalars = measured.network_inputs()
        for name, probabilities in rule_probabilities(measured).items():
            rules[name].append([probabilities[c] for c in HEADS[name]])
        outfit = [meta["category"]] + ([meta["other"]] if meta.get("other") else [])
        for name, value in targets(outfit).items():
            heads[name].append(value)
        arrays["maps"].append(maps.astype(np.float16))
        arrays["thighs"].append(thighs.astype(np.float16))
        arrays["scalars"].append(scalars)
        arrays["val"].append(meta["split"] != "train")
        arrays["samples"].append(path.stem)
        arrays["outfits"].append(",".join(outfit))
    return {**{k: np.array(v) for k, v in arrays.items()}, **{k: np.array(v) for k, v in heads.items()},
            **{f"rules_{k}": np.array(v) for k, v in rules.items()}}


def outfit_right(probabilities: dict[str, np.ndarray], arrays: dict[str, np.ndarray]) -> np.ndarray:
    """[N,2] per picture, whether each garment's category follows right (the second: no second
    garment counts as right) from the heads' ``probabilities``."""
    one = probabilities["one_piece"].argmax(1) == 1
    truth_one = arrays["one_piece"] == 1
    sleeves = probabilities["sleeves"].argmax(1) == arrays["sleeves"]
    lower = (probabilities["long"].argmax(1) == arrays["long"]) & (probabilities["skirt"].argmax(1) == arrays["skirt"])
    upper_right = (one == truth_one) & sleeves
    lower_right = np.where(truth_one, True, ~one & lower)
    return np.stack([upper_right, lower_right], 1)


def garment_score(probabilities: dict[str, np.ndarray], arrays: dict[str, np.ndarray]) -> float:
    """The share of garments (a dress, or a top and a lower garment) whose category is right."""
    right = outfit_right(probabilities, arrays)
    garments = np.where(arrays["one_piece"] == 1, 1, 2)
    return float(np.where(garments == 1, right[:, 0], right.sum(1)).sum() / garments.sum())


def misalign(batch, pixels: int, generator: np.random.Generator):
    """``batch`` [B,CHANNELS,S,S] with each picture's parsing channels (the first ``len(LABELS)``)
    shifted by its own whole-pixel offset (dx, dy), each uniform in [-pixels, pixels], against the
    body's zones: a body fit that sits a little off the person, as on real photographs."""
    import torch

    from darts.photo.outfit_net import LABELS

    if pixels <= 0:
        return batch
    out = batch.clone()
    for k, (dy, dx) in enumerate(generator.integers(-pixels, pixels + 1, (len(batch), 2))):
        out[k, :len(LABELS)] = torch.roll(batch[k, :len(LABELS)], (int(dy), int(dx)), (1, 2))
    return out


def train(arrays: dict[str, np.ndarray], epochs: int, seed: int, width: int, misalign_pixels: int = 0, log=print):
    """(the best network by validation score, its epoch, the score) trained on ``arrays``."""
    import copy

    import torch

    from darts.photo.outfit_net import HEADS, OutfitNet, probabilities_of

    torch.manual_seed(seed)
    generator = np.random.default_rng(seed)
    train_rows, val_rows = np.flatnonzero(~arrays["val"]), np.flatnonzero(arrays["val"])
    maps = torch.tensor(arrays["maps"].astype(np.float32))
    thighs = torch.tensor(arrays["thighs"].astype(np.float32))
    scalars = torch.tensor(arrays["scalars"])
    truth = {name: torch.tensor(arrays[name]) for name in HEADS}
    network = OutfitNet(width)
    optimiser = torch.optim.AdamW(network.parameters(), 2e-3, weight_decay=1e-3)
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, epochs)
    validation = {k: v[val_rows] for k, v in arrays.items()}
    best = (None, -1, -1.0)
    for epoch in range(epochs):
        network.train()
        order = generator.permutation(train_rows)
        for start in range(0, len(order), 32):
            rows = torch.tensor(order[start:start + 32])
            mirror = (torch.rand(len(rows)) < 0.5)[:, None, None, None]
            batch = misalign(maps[rows], misalign_pixels, generator)
            thigh_batch = misalign(thighs[rows], misalign_pixels, generator)
            out = network(torch.where(mirror, batch.flip(3), batch), torch.where(mirror, thigh_batch.flip(3), thigh_batch),
                          scalars[rows])
            loss = sum(torch.nn.functional.cross_entropy(out[name][truth[name][rows] >= 0],
                                                         truth[name][rows][truth[name][rows] >= 0])
                       for name in HEADS if (truth[name][rows] >= 0).any())
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
        schedule.step()
        score = garment_score(probabilities_of(network, maps[val_rows].numpy(), thighs[val_rows].numpy(),
                                               scalars[val_rows].numpy()), validation)
        log(f"epoch {epoch + 1}: loss {loss.item():.3f}, validation garments right {score:.3f}")
        if score >= best[2]:
            best = (copy.deepcopy(network.state_dict()), epoch + 1, score)
    network.load_state_dict(best[0])
    return network.eval(), best[1], best[2]


def evaluate(arrays: dict[str, np.ndarray], pictures: int, ensemble=None) -> dict:
    """The shipped network (or ``ensemble``), the rules and the two combined (``darts.photo.attributes.combine`` with
    ``RULE_WEIGHTS``; the picture's bounds on cloth running out of it not applied) on ``arrays``:
    per decision the share right, and the share of ``pictures`` (those without a person count as
    wrong) whose garment of the picture's kind (the first of each outfit) is right."""
    from darts.photo.attributes import RULE_WEIGHTS, geometric_mix
    from darts.photo.outfit_net import HEADS, probabilities_of, shipped_network

    network = probabilities_of(ensemble or shipped_network(), arrays["maps"].astype(np.float32),
                               arrays["thighs"].astype(np.float32), arrays["scalars"])
    rules = {name: arrays[f"rules_{name}"] for name in HEADS}
    combined = {name: geometric_mix(rules[name], network[name], RULE_WEIGHTS[name]) for name in HEADS}
    first_is_lower = np.array([TARGETS[o.split(",")[0]][0] == "lower" for o in arrays["outfits"]])
    out = {}
    for label, probabilities in (("network", network), ("rules", rules), ("combined", combined)):
        right = outfit_right(probabilities, arrays)
        kind_right = np.where(first_is_lower, right[:, 1], right[:, 0])
        out[label] = {"picture_kind_right": round(float(kind_right.sum() / pictures), 4),
                      "garments_right": round(garment_score(probabilities, arrays), 4),
                      **{name: round(float((probabilities[name].argmax(1) == arrays[name])[arrays[name] >= 0].mean()), 4)
                         for name in HEADS}}
    return out


#: the rule weights ``--weights`` measures
SWEPT_WEIGHTS = tuple(round(0.1 * k, 1) for k in range(11))


def weight_sweep(arrays: dict[str, np.ndarray], weights=SWEPT_WEIGHTS, ensemble=None) -> dict:
    """Per decision and rule weight w (``darts.photo.attributes.combine``), the share of the
    validation part's pictures (garments never trained on) with that decision right: how
    ``RULE_WEIGHTS`` are chosen."""
    from darts.photo.attributes import geometric_mix
    from darts.photo.outfit_net import HEADS, probabilities_of, shipped_network

    rows = np.flatnonzero(arrays["val"])
    network = probabilities_of(ensemble or shipped_network(), arrays["maps"][rows].astype(np.float32),
                               arrays["thighs"][rows].astype(np.float32), arrays["scalars"][rows])
    out = {}
    for name in HEADS:
        truth, known = arrays[name][rows], arrays[name][rows] >= 0
        rules = arrays[f"rules_{name}"][rows]
        out[name] = {"pictures": int(known.sum()), **{
            str(w): round(float((geometric_mix(rules, network[name], w).argmax(1) == truth)[known].mean()), 4)
            for w in weights}}
    return out


def _cache(data: Path) -> Path:
    return Path.home() / ".cache" / "darts" / "outfit_net" / data.name


def within(data: Path, samples: np.ndarray, recipe: int) -> np.ndarray:
    """[N] bool: which ``samples`` (``<split>__<picture>`` of dataset ``data``) show a garment that
    ``RECIPES[recipe]`` could draw (``sim.dataset.recipe.within_recipe``, on its ``meta.json``)."""
    from sim.dataset.recipe import within_recipe

    def drawn(sample: str) -> bool:
        meta = json.loads((data / sample.replace("__", "/", 1) / "meta.json").read_text())
        return within_recipe(meta["category"], meta["edits"], recipe)

    return np.array([drawn(str(sample)) for sample in samples], dtype=bool)


def load_inputs(datasets: list[Path], workers: int, rebuild: bool, recipe: int | None = None) -> dict[str, np.ndarray]:
    """The inputs of every picture of ``datasets`` (each fitted and built if not cached,
    ``build_inputs``), one array per key in the order given; with ``recipe``, only the pictures
    whose garment that recipe could draw (``within``)."""
    parts = []
    for data in datasets:
        cache = _cache(data)
        fit_all(data, cache / "fits", workers)
        inputs = cache / "inputs.npz"
        if rebuild or not inputs.is_file():
            started = time.process_time()
            arrays = build_inputs(cache / "fits")
            np.savez_compressed(inputs, **arrays)
            print(f"{data}: inputs of {len(arrays['maps'])} pictures in {time.process_time() - started:.0f} s", flush=True)
        part = dict(np.load(inputs))
        if recipe is not None:
            kept = within(data, part["samples"], recipe)
            print(f"{data}: {kept.sum()} of {len(kept)} pictures within recipe {recipe}", flush=True)
            part = {key: value[kept] for key, value in part.items()}
        parts.append(part)
    return {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, nargs="+", required=True)
    parser.add_argument("--epochs", type=int, default=40)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4, 5])
    parser.add_argument("--width", type=int, default=16)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--misalign", type=int, default=0, metavar="PIXELS",
                        help="shift each training picture's parsing against the body's zones by up to PIXELS (map pixels)")
    parser.add_argument("--within-recipe", type=int, metavar="R",
                        help="only the pictures whose garment dataset recipe R could draw (a narrower recipe than --data's)")
    parser.add_argument("--rebuild-inputs", action="store_true")
    parser.add_argument("--out", type=Path, default=Path("darts/photo/weights/outfit_net.pt"))
    parser.add_argument("--network", type=Path, help="--evaluate or --weights this checkpoint, not the shipped one")
    parser.add_argument("--evaluate", action="store_true",
                        help="instead of training, measure the shipped network, the rules and both on every picture of --data")
    parser.add_argument("--weights", action="store_true",
                        help="instead of training, each decision's accuracy on --data's validation part for rule weights "
                             "0, 0.1, ..., 1 (how RULE_WEIGHTS are chosen), and --evaluate's measures there")
    args = parser.parse_args()
    import torch

    torch.set_num_threads(2)
    arrays = load_inputs(args.data, args.workers, args.rebuild_inputs, args.within_recipe)
    data = " ".join(str(folder) for folder in args.data)
    from darts.photo.outfit_net import ensemble_of

    chosen = ensemble_of(torch.load(args.network, map_location="cpu", weights_only=True)) if args.network else None
    validation = {k: v[arrays["val"]] for k, v in arrays.items()}
    if args.weights:
        print(json.dumps({"data": data, "validation": weight_sweep(arrays, ensemble=chosen),
                          "validation_with_rule_weights": evaluate(validation, int(arrays["val"].sum()), chosen)}, indent=1))
        return
    if args.evaluate:
        pictures = sum(len(list((_cache(folder) / "fits").glob("*.pkl"))) for folder in args.data)
        print(json.dumps({"data": data, "pictures": pictures, **evaluate(arrays, pictures, chosen)}, indent=1))
        return
    from darts.photo.outfit_net import OutfitEnsemble, probabilities_of

    started, members, seeds = time.time(), [], []
    for seed in args.seeds:
        network, epoch, score = train(arrays, args.epochs, seed, args.width, args.misalign)
        members.append(network)
        seeds.append({"seed": seed, "best_epoch": epoch, "validation_garments_right": round(score, 4)})
        print(json.dumps(seeds[-1]), flush=True)
    ensemble = probabilities_of(OutfitEnsemble(members), validation["maps"].astype(np.float32),
                                validation["thighs"].astype(np.float32), validation["scalars"])
    record = {"command": " ".join(["python"] + sys.argv), "data": data, "epochs": args.epochs, "width": args.width,
              "misalign": args.misalign, "within_recipe": args.within_recipe,
              "seeds": seeds, "validation_garments_right": round(garment_score(ensemble, validation), 4),
              "train_pictures": int((~arrays["val"]).sum()), "validation_pictures": int(arrays["val"].sum()),
              "minutes": round((time.time() - started) / 60, 1)}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    torch.save({"width": args.width, "members": [member.state_dict() for member in members], "record": record}, args.out)
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
