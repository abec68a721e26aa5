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
- **Edits** (``RECIPES[recipe]``, metres (recipe 4's ends: s), uniform in each range; hem / sleeve: > 0 lengthens, the
  others widen): every edit of the category, so no two garments share their feature lines. The
  ranges keep categories apart (a lengthened short sleeve stops above the elbow, a shortened long
  sleeve below it; short pants and skirts stay above the knee, long ones below it). Waists of
  skirts and pants are not widened: a waistband 1.5 cm wider than the body slid 36 cm down the hips
  in the drape (measured), where a real one is elastic. Four versions (``--recipe``), measured on the
  default body (upper arm 27.5 cm, forearm 24.4 cm; the long sleeve's cuff 2 cm above the wrist,
  the short one's 15 cm below the shoulder; the knee 32.5 cm below the hip):

  - **1** (``EDIT_RANGES``, the default; most of the shipped networks' data): a long sleeve
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
    and three-quarter sleeves are long sleeves; ``darts.photo.rules`` says the same). Recipe 2's
    short sleeves, 2 cm above the elbow at their longest on the default body, pass it on others.
  - **4**: recipe 2 with each length — sleeves, trouser legs, skirts — drawn as where the garment
    ends along its own body's limb (``END_RANGES``: s, 0.5 at the elbow or knee,
    ``darts.photo.attributes``' convention) and turned into that body's length edit in metres
    (``metres_edits``): short sleeves end at s = 0.17-0.42, long ones 0.47-0.93 (a sleeve that
    reaches the elbow is long); short pants 0.16-0.44, long 0.60-0.97 (capris are long); short
    skirts 0.18-0.44, long 0.56-0.90. Lengths in metres, set on the default body, end elsewhere on
    other body shapes: recipe 2's short and long sleeves, legs and skirts overlap along the limb
    (``scripts/recipe_ends.py``), so pictures there carry both labels; ends in s keep every
    boundary's gap on every body. The meta's edits hold ``sleeve_end`` / ``hem_end`` (s).
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
#: recipe 4's lengths (module docstring): per category prefix, the length edit and the s range of
#: the garment's end along its own body's limb (``darts.photo.attributes``: 0.5 at the elbow or knee)
END_RANGES = {"long-sleeve": ("sleeve", (0.47, 0.93)), "short-sleeve": ("sleeve", (0.17, 0.42)),
              "long-pants": ("hem", (0.60, 0.97)), "short-pants": ("hem", (0.16, 0.44)),
              "long-skirt": ("hem", (0.56, 0.90)), "short-skirt": ("hem", (0.18, 0.44))}
END_SUFFIX = "_end"


def _recipe_four() -> dict[str, dict[str, tuple[float, float]]]:
    """Recipe 2's ranges with each category's length edit of ``END_RANGES`` drawn as its end (s)."""
    four = {}
    for category, ranges in _RECIPE_2.items():
        length = next((value for prefix, value in END_RANGES.items() if category.startswith(prefix)), None)
        four[category] = dict(ranges) if length is None else {
            (name + END_SUFFIX if name == length[0] else name): (length[1] if name == length[0] else bounds)
            for name, bounds in ranges.items()}
    return four


#: the edit ranges of each recipe version (``--recipe``)
RECIPES: dict[int, dict[str, dict[str, tuple[float, float]]]] = {
    1: EDIT_RANGES,
    2: _RECIPE_2,
    3: {category: {**ranges, **(_SHORT_SLEEVE if category.startswith("short-sleeve") else {})}
        for category, ranges in _RECIPE_2.items()},
    4: _recipe_four(),
}
DEFAULT_RECIPE = 1
_CATEGORY, _SPLIT, _SHAPE, _EDITS, _LOOK = range(5)


def within_recipe(category: str, edits: dict[str, float], recipe: int) -> bool:
    """Whether a garment of ``category`` with ``edits`` (name: metres, or s for an end) could be drawn by
    ``RECIPES[recipe]``: every edit inside its range (a dataset of a wider recipe, its pictures kept
    by this, is a sample of the narrower one)."""
    ranges = RECIPES[recipe][category]
    return set(edits) == set(ranges) and all(ranges[name][0] <= value <= ranges[name][1] for name, value in edits.items())


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
    edits = metres_edits(recipe.category, welded, body, recipe.betas, list(recipe.edits))
    targets = edit_targets(recipe.category, welded.vertices, welded.lines, edits)
    dart, report = deform_dart(template, body, targets, clearance=DEFAULT_EASE)
    return dart, report, {"template_s": round(built - started, 3), "crdl_s": round(time.perf_counter() - built, 3)}


def metres_edits(category: str, welded, body, betas, edits: list[tuple[str, float]]) -> list[tuple[str, float]]:
    """``edits`` with each end (``sleeve_end``, ``hem_end``: s along the limb, recipe 4) made the
    length edit (``sleeve``, ``hem``: metres along the line's axis) that takes the ``welded``
    template's lines there: the mean over the lines it moves of (T - c) . n, with T the point at s on
    the body's rest limb (``darts.photo.lengths.length_targets``, as a photograph's read end is
    placed) and c, n the template line's centre and axis (``darts.crdl.targets.loop_frame``)."""
    from darts.crdl.targets import loop_frame
    from darts.photo.lengths import length_targets

    centre = welded.vertices.mean(0)
    out = []
    for name, value in edits:
        if not name.endswith(END_SUFFIX):
            out.append((name, value))
            continue
        targets = length_targets(category, {name: value}, body, np.asarray(betas))
        moves = [np.dot(target["point"] - frame[0], frame[1]) for line, target in targets.items() if line in welded.lines
                 for frame in [loop_frame(welded.vertices[welded.lines[line]].astype(np.float64), centre)]]
        out.append((name.removesuffix(END_SUFFIX), round(float(np.mean(moves)), 4)))
    return out


def garment_end(dart, body, betas) -> float | None:
    """Where ``dart`` ends along its body's limb (shape ``betas``, rest pose, canonical frame): of
    its cuffs (a sleeved garment) or its legs' hems (pants, skirts) the shorter end, each the s
    (``darts.photo.attributes``' convention) at which the limb's polyline crosses the plane of the
    line (its centre and axis, ``darts.crdl.targets.loop_frame``) — what a photograph's
    ``sleeve_end`` or ``hem_end`` measures, without the picture; ``None`` for a garment without such
    an end (sleeveless tops and dresses)."""
    from darts.crdl.targets import loop_frame
    from darts.geometry.loops import feature_lines
    from darts.photo.attributes import ARM, LEG, chain, point_at
    from darts.photo.lengths import rest_landmarks

    category = dart.category
    if "sleeveless" in category or not ("sleeve" in category or "pants" in category or "skirt" in category):
        return None
    lines = feature_lines(dart, dart.vertices)
    centre = np.asarray(dart.vertices, np.float64).mean(0)
    points = rest_landmarks(body, np.asarray(betas))
    s = np.linspace(0.0, 1.0, 2001)
    ends = []
    for side in ("left", "right"):
        if "sleeve" in category:
            name, polyline = f"{side}_cuff", chain(points, side, ARM)
        elif "pants" in category:
            name, polyline = f"{side}_hem", chain(points, side, LEG)
        else:
            name, polyline = "hem", 0.5 * (chain(points, "left", LEG) + chain(points, "right", LEG))
        middle, axis = loop_frame(np.asarray(lines[name], np.float64), centre)
        level = np.array([np.dot(point_at(polyline, value) - middle, axis) for value in s])
        ends.append(float(s[np.argmin(np.abs(level))]))
    return min(ends)


def write_json(path, data: dict) -> None:
    """``data`` as indented JSON at ``path`` (a job's own folder: the job runner makes it whole)."""
    import json
    from pathlib import Path

    Path(path).write_text(json.dumps(data, indent=1))
