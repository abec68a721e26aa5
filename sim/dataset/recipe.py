"""What a dataset garment is, decided from (seed, index) alone: its split, category, body shape and
CRDL edits. Each random draw has its own generator seeded by (seed, index, purpose), so a sample
never depends on which other samples are made, in what order, or on which machine.

- **Category**: balanced; every block of ten consecutive indices holds each category once, in a
  shuffled order (restricted to ``categories`` when given).
- **Split** (by garment instance): 10 % test; of the rest, 10 % validation (the paper's 90/10),
  the others train. Test garments are rendered twice: once as training is (``test``) and once with
  appearance never used in training (``test_unseen``, ``sim.dataset.appearance``).
- **Body shape**: the first ``SHAPE_COUNT`` betas of the bundled body, each N(0, 1) (its PCA is
  scaled so) truncated to +-2; the others 0.
- **Edits** (``RECIPES[recipe]``, metres, uniform in each range; hem / sleeve: > 0 lengthens, the
  others widen): every edit of the category, so no two garments share their feature lines. The
  ranges keep categories apart (a lengthened short sleeve stops above the elbow, a shortened long
  sleeve below it; short pants and skirts stay above the knee, long ones below it). Waists of
  skirts and pants are not widened: a waistband 1.5 cm wider than the body slid 36 cm down the hips
  in the drape (measured), where a real one is elastic. Three versions (``--recipe``), measured on the
  default body (upper arm 27.5 cm, forearm 24.4 cm; the long sleeve's cuff 2 cm above the wrist,
  the short one's 15 cm below the shoulder; the knee 32.5 cm below the hip):

  - **1** (``EDIT_RANGES``, the default; what the shipped networks were trained on): a long sleeve
    ends 12.5 cm below the elbow or lower, a short one 7 cm above it or higher; short pants and
    skirts end 10 cm above the knee or higher, long skirts 8 cm below it and long pants 29 cm
    below it or lower: nothing is pictured near the boundaries, which real clothes reach (a
    sleeve rolled to the forearm, bermudas, capris, a knee-length skirt);
  - **2**: the lengths run up to the boundaries: a long sleeve down to 2.5 cm below the elbow
    (sleeve -0.20 m), a short one up to 2 cm above it (+0.13 m); short pants up to 3 cm above the
    knee (hem +0.17 m), short skirts 2.5 cm (+0.16 m); long skirts up to 2 cm below it (-0.16 m),
    long pants 14 cm (-0.25 m). Every other range as in 1.
  - **3**: recipe 2 with recipe 1's short sleeves: a short sleeve ends 7 cm above the elbow or
    higher, a long one down to 2.5 cm below it — a sleeve that reaches the elbow is long (rolled
    and three-quarter sleeves are long sleeves; ``darts.photo.rules`` says the same). Recipe 2
    draws short sleeves up to 2 cm above the elbow, which the read sleeve end cannot tell from a
    long sleeve rolled to it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.templates.categories import CATEGORIES

SPLITS = ("train", "val", "test", "test_unseen")
TEST_FRACTION = 0.10
VAL_FRACTION = 0.10  # of what is not test
SHAPE_COUNT = 8
SHAPE_LIMIT = 2.0
DRAPE_SECONDS = 0.5

_TOP = {"hem": (-0.08, 0.06), "neckline": (0.0, 0.04), "hem_width": (-0.01, 0.05)}
_DRESS = {"hem": (-0.12, 0.15), "neckline": (0.0, 0.05), "hem_width": (0.0, 0.15)}
_LONG_SLEEVE = {"sleeve": (-0.10, 0.0), "cuff_width": (0.0, 0.03)}
_SHORT_SLEEVE = {"sleeve": (-0.04, 0.08), "cuff_width": (0.0, 0.03)}
_ARMHOLE = {"cuff_width": (0.0, 0.02)}
#: recipe 1's edit ranges (module docstring)
EDIT_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "long-sleeve-top": {**_TOP, **_LONG_SLEEVE},
    "short-sleeve-top": {**_TOP, **_SHORT_SLEEVE},
    "sleeveless-top": {**_TOP, **_ARMHOLE},
    "long-sleeve-dress": {**_DRESS, **_LONG_SLEEVE},
    "short-sleeve-dress": {**_DRESS, **_SHORT_SLEEVE},
    "sleeveless-dress": {**_DRESS, **_ARMHOLE},
    "long-pants": {"hem": (-0.10, 0.02), "hem_width": (0.0, 0.05)},
    "short-pants": {"hem": (-0.06, 0.10), "hem_width": (0.0, 0.04)},
    "long-skirt": {"hem": (-0.10, 0.12), "hem_width": (0.0, 0.18)},
    "short-skirt": {"hem": (-0.05, 0.08), "hem_width": (0.0, 0.12)},
}
#: recipe 2's changes to recipe 1: lengths up to the elbow and the knee (module docstring)
_TO_THE_JOINTS = {"long-sleeve-top": {"sleeve": (-0.20, 0.0)}, "long-sleeve-dress": {"sleeve": (-0.20, 0.0)},
                  "short-sleeve-top": {"sleeve": (-0.04, 0.13)}, "short-sleeve-dress": {"sleeve": (-0.04, 0.13)},
                  "long-pants": {"hem": (-0.25, 0.02)}, "short-pants": {"hem": (-0.06, 0.17)},
                  "long-skirt": {"hem": (-0.16, 0.12)}, "short-skirt": {"hem": (-0.05, 0.16)}}
_RECIPE_2 = {category: {**ranges, **_TO_THE_JOINTS.get(category, {})} for category, ranges in EDIT_RANGES.items()}
#: the edit ranges of each recipe version (``--recipe``)
RECIPES: dict[int, dict[str, dict[str, tuple[float, float]]]] = {
    1: EDIT_RANGES,
    2: _RECIPE_2,
    3: {category: {**ranges, **(_SHORT_SLEEVE if category.startswith("short-sleeve") else {})}
        for category, ranges in _RECIPE_2.items()},
}


def within_recipe(category: str, edits: dict[str, float], recipe: int) -> bool:
    """Whether a garment of ``category`` with ``edits`` (name: metres) could be drawn by
    ``RECIPES[recipe]``: every edit inside its range (a dataset of a wider recipe, its pictures kept
    by this, is a sample of the narrower one)."""
    ranges = RECIPES[recipe][category]
    return set(edits) == set(ranges) and all(ranges[name][0] <= value <= ranges[name][1] for name, value in edits.items())
DEFAULT_RECIPE = 1
_CATEGORY, _SPLIT, _SHAPE, _EDITS, _LOOK = range(5)


def generator(seed: int, index: int, purpose: int, view: int = 0) -> np.random.Generator:
    """The generator of one random draw of garment ``index``."""
    return np.random.default_rng([seed, index, purpose, view])


@dataclass(frozen=True)
class GarmentRecipe:
    seed: int
    index: int
    category: str
    split: str  # train, val or test (a test garment also makes the test_unseen samples)
    betas: tuple[float, ...]
    edits: tuple[tuple[str, float], ...]
    recipe: int = DEFAULT_RECIPE

    @property
    def id(self) -> str:
        return f"g{self.index:05d}"

    def as_dict(self) -> dict:
        return {"seed": self.seed, "index": self.index, "id": self.id, "category": self.category, "split": self.split,
                "betas": list(self.betas), "edits": dict(self.edits), "recipe": self.recipe}


def garment_recipe(seed: int, index: int, categories: tuple[str, ...] = tuple(CATEGORIES),
                   recipe: int = DEFAULT_RECIPE) -> GarmentRecipe:
    """Garment ``index`` of the dataset with ``seed`` and edit ranges ``RECIPES[recipe]`` (module
    docstring); the versions draw the same numbers, so only the edits' values differ."""
    block, slot = divmod(index, len(categories))
    category = categories[int(generator(seed, block, _CATEGORY).permutation(len(categories))[slot])]
    u = generator(seed, index, _SPLIT).uniform()
    split = "test" if u < TEST_FRACTION else "val" if u < TEST_FRACTION + (1 - TEST_FRACTION) * VAL_FRACTION else "train"
    rng = generator(seed, index, _SHAPE)
    betas = np.clip(rng.normal(0.0, 1.0, SHAPE_COUNT), -SHAPE_LIMIT, SHAPE_LIMIT)
    rng = generator(seed, index, _EDITS)
    edits = tuple((name, round(float(rng.uniform(low, high)), 4)) for name, (low, high) in RECIPES[recipe][category].items())
    return GarmentRecipe(seed, index, category, split, tuple(round(float(b), 4) for b in betas), edits, recipe)


def recipe_garment(recipe: GarmentRecipe, body, template=None) -> tuple:
    """(the recipe's DART, the CRDL's report, {"template_s", "crdl_s"} seconds): its category's
    template made on the recipe's body shape at the dataset's edge length (or ``template``, a DART
    of that category on that shape), welded, then deformed by the CRDL to the recipe's edits with
    the default ease as clearance (``body``: the ``BodyModel``)."""
    import time

    from darts.crdl.deform import deform_dart, weld_garment
    from darts.crdl.targets import edit_targets
    from darts.dart.build import make_dart
    from darts.templates.defaults import DATASET_EASE, DATASET_EDGE_LENGTH, DEFAULT_EASE

    started = time.perf_counter()
    if template is None:
        template = make_dart(recipe.category, body, betas=np.asarray(recipe.betas), edge_length=DATASET_EDGE_LENGTH,
                             ease=DATASET_EASE)
    built = time.perf_counter()
    welded = weld_garment(template)
    targets = edit_targets(recipe.category, welded.vertices, welded.lines, list(recipe.edits))
    dart, report = deform_dart(template, body, targets, clearance=DEFAULT_EASE)
    return dart, report, {"template_s": round(built - started, 3), "crdl_s": round(time.perf_counter() - built, 3)}


def write_json(path, data: dict) -> None:
    """``data`` as indented JSON at ``path`` (a job's own folder: the job runner makes it whole)."""
    import json
    from pathlib import Path

    Path(path).write_text(json.dumps(data, indent=1))
