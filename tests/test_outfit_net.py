"""The network that decides a photograph's garments from the parsing (``darts.photo.outfit_net``) and
its training script: inputs, mirror symmetry, targets, and a tiny network that learns."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
import torch

from darts.body.segmentation import PART_INDEX
from darts.photo import outfit_net
from darts.photo.parsing import LOWER, SIZE, SKIN, UPPER

_spec = importlib.util.spec_from_file_location("train_outfit_net", Path(__file__).parents[1] / "scripts" / "train_outfit_net.py")
train_outfit_net = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(train_outfit_net)


def test_maps_hold_each_blocks_share_of_each_label_and_body_zone():
    labels = np.zeros((SIZE, SIZE), np.uint8)
    labels[:64] = UPPER  # the top quarter
    labels[64:96, :128] = LOWER  # an eighth, the left half of it
    labels[96:100] = SKIN
    body = np.full((SIZE, SIZE), -1)
    body[:, :32] = PART_INDEX["left_thigh"]
    body[:, 32:64] = PART_INDEX["right_thigh"]
    inside = np.ones((SIZE, SIZE), bool)
    inside[-16:] = False
    points = np.zeros((33, 2))
    points[[23, 24]] = [[100.0, 100.0], [140.0, 100.0]]  # the hips, the knees 60 pixels below
    points[[25, 26]] = [[100.0, 160.0], [140.0, 160.0]]
    maps, thighs = outfit_net.maps(labels, body, inside, points)
    assert maps.shape == (outfit_net.CHANNELS, outfit_net.MAP_SIZE, outfit_net.MAP_SIZE)
    assert thighs.shape == (outfit_net.CHANNELS, outfit_net.THIGH_SIZE, outfit_net.THIGH_SIZE)
    means = maps.mean((1, 2))
    assert means[0] == pytest.approx(0.25) and means[1] == pytest.approx(1 / 16) and means[2] == pytest.approx(4 / 256)
    thigh = len(outfit_net.LABELS) + [k for k, zone in enumerate(outfit_net.ZONES) if "thigh" in zone][0]
    assert means[thigh] == pytest.approx(0.25)  # both thighs, one zone
    assert means[-1] == pytest.approx(16 / 256)  # outside the picture
    # the thighs' map: a square of 2.4 x 60 pixels centred at (120, 130): rows 58..202, columns 48..192
    span = outfit_net.THIGH_SPAN * 60
    rows = 130 - span / 2 + (np.arange(outfit_net.THIGH_SIZE) + 0.5) * span / outfit_net.THIGH_SIZE
    # the top quarter is upper cloth: pixel rows 0..63, whose centres lie under 64
    np.testing.assert_allclose(thighs[0][rows <= 63.5], 1.0)
    assert thighs[0][rows >= 64.5].max() == 0.0


def test_scalars_follow_their_names_and_mark_what_was_not_measured():
    top = {"sleeve_end": 0.3, "sleeve_beyond_picture": False, "top_hem_end": 0.5,
           "arms": {"left": {"end": 0.35}, "right": {"end": 0.3}}}
    lower = {"hem_end": 0.9, "hem_beyond_picture": True, "between_legs_fill": None, "off_the_legs": 0.1}
    visibility = np.linspace(0, 1, 33)
    values = dict(zip(outfit_net.SCALAR_NAMES, outfit_net.scalars(top, lower, None, {"lower_by_upper_nats": 20.0},
                                                                   visibility)))
    assert len(values) == outfit_net.SCALARS
    assert values["top_sleeve_end"] == pytest.approx(0.3) and values["top_longer_arm_end"] == pytest.approx(0.35)
    assert values["dress_sleeve_unread"] == 1.0 and values["dress_sleeve_end"] == -1.0
    assert values["lower_hem_beyond_picture"] == 1.0 and values["lower_between_legs_fill"] == -1.0
    assert values["lower_by_upper_nats"] == pytest.approx(np.log(21.0)) and values["upper_by_lower_nats"] == 0.0
    assert values["knee_visibility"] == pytest.approx(min(visibility[25], visibility[26]))


def test_a_picture_and_its_mirror_image_get_the_same_probabilities():
    torch.manual_seed(0)
    network = outfit_net.OutfitNet(8)
    maps = np.random.default_rng(0).random((3, outfit_net.CHANNELS, outfit_net.MAP_SIZE, outfit_net.MAP_SIZE), np.float32)
    thighs = np.random.default_rng(2).random((3, outfit_net.CHANNELS, outfit_net.THIGH_SIZE, outfit_net.THIGH_SIZE),
                                             np.float32)
    scalars = np.random.default_rng(1).random((3, outfit_net.SCALARS), np.float32)
    straight = outfit_net.probabilities_of(network, maps, thighs, scalars)
    mirrored = outfit_net.probabilities_of(network, maps[..., ::-1].copy(), thighs[..., ::-1].copy(), scalars)
    for name, classes in outfit_net.HEADS.items():
        assert straight[name].shape == (3, len(classes))
        np.testing.assert_allclose(straight[name].sum(1), 1.0, rtol=1e-6)
        np.testing.assert_allclose(straight[name], mirrored[name], rtol=1e-5)


def test_the_ensemble_answers_its_members_mean_probability():
    torch.manual_seed(0)
    members = [outfit_net.OutfitNet(4) for _ in range(3)]
    generator = np.random.default_rng(3)
    maps = generator.random((2, outfit_net.CHANNELS, outfit_net.MAP_SIZE, outfit_net.MAP_SIZE), np.float32)
    thighs = generator.random((2, outfit_net.CHANNELS, outfit_net.THIGH_SIZE, outfit_net.THIGH_SIZE), np.float32)
    scalars = generator.random((2, outfit_net.SCALARS), np.float32)
    each = [outfit_net.probabilities_of(member, maps, thighs, scalars) for member in members]
    together = outfit_net.probabilities_of(outfit_net.OutfitEnsemble(members), maps, thighs, scalars)
    saved = outfit_net.ensemble_of({"width": 4, "members": [member.state_dict() for member in members]})
    again = outfit_net.probabilities_of(saved, maps, thighs, scalars)
    for name in outfit_net.HEADS:
        assert not np.allclose(each[0][name], each[1][name], atol=1e-3)  # the members differ
        np.testing.assert_allclose(together[name], np.mean([e[name] for e in each], 0), rtol=1e-5)
        np.testing.assert_allclose(again[name], together[name], rtol=1e-6)


def test_targets_of_an_outfit():
    assert train_outfit_net.targets(["short-skirt", "long-sleeve-top"]) == {"one_piece": 0, "sleeves": 2, "long": 0,
                                                                              "skirt": 1}
    assert train_outfit_net.targets(["sleeveless-dress"]) == {"one_piece": 1, "sleeves": 0, "long": -1, "skirt": -1}


@pytest.mark.slow
def test_a_tiny_network_learns_outfits_from_their_evidence():
    """Ninety-six outfits whose scalars carry their classes (the maps blank): the training loop
    fits them, every garment right, and keeps the best epoch."""
    generator = np.random.default_rng(0)
    count = 96
    outfits = [["long-pants", "short-sleeve-top"], ["short-skirt", "sleeveless-top"], ["long-sleeve-dress"],
               ["short-pants", "long-sleeve-top"]]
    chosen = [outfits[k % 4] for k in range(count)]
    heads = [train_outfit_net.targets(o) for o in chosen]
    scalars = generator.normal(0, 0.1, (count, outfit_net.SCALARS)).astype(np.float32)
    for row, head in enumerate(heads):
        for column, name in enumerate(outfit_net.HEADS):
            scalars[row, column] += 2.0 * head[name]
    arrays = {"maps": np.zeros((count, outfit_net.CHANNELS, outfit_net.MAP_SIZE, outfit_net.MAP_SIZE), np.float16),
              "thighs": np.zeros((count, outfit_net.CHANNELS, outfit_net.THIGH_SIZE, outfit_net.THIGH_SIZE), np.float16),
              "scalars": scalars, "val": np.arange(count) % 3 == 0,
              **{name: np.array([h[name] for h in heads]) for name in outfit_net.HEADS}}
    logged = []
    network, epoch, score = train_outfit_net.train(arrays, epochs=80, seed=0, width=4, log=logged.append)
    assert len(logged) == 80 and 1 <= epoch <= 80
    probabilities = outfit_net.probabilities_of(network, arrays["maps"].astype(np.float32),
                                                arrays["thighs"].astype(np.float32), arrays["scalars"])
    assert train_outfit_net.garment_score(probabilities, arrays) == 1.0 and score == 1.0


def test_the_two_experts_combine_as_a_weighted_geometric_mean():
    from darts.photo.attributes import combine

    rules = {"skirt": {"pants": 0.9, "skirt": 0.1}}
    network = {"skirt": {"pants": 0.2, "skirt": 0.8}}
    assert combine(rules, network, {"skirt": 1.0})["skirt"]["pants"] == pytest.approx(0.9)
    assert combine(rules, network, {"skirt": 0.0})["skirt"]["pants"] == pytest.approx(0.2)
    half = combine(rules, network, {"skirt": 0.5})["skirt"]
    assert half["pants"] == pytest.approx(np.sqrt(0.18) / (np.sqrt(0.18) + np.sqrt(0.08)))
    assert sum(half.values()) == pytest.approx(1.0)


def test_cloth_running_out_of_the_picture_is_at_least_as_long_as_seen():
    from types import SimpleNamespace

    from darts.photo.rules import within_picture_bounds

    decided = {"one_piece": {"two": 0.9, "one": 0.1}, "sleeves": {"none": 0.1, "short": 0.8, "long": 0.1},
               "long": {"short": 0.9, "long": 0.1}, "skirt": {"pants": 0.5, "skirt": 0.5}}
    top = {"sleeve_end": 0.4, "sleeve_beyond_picture": True}
    lower = {"hem_end": 0.4, "hem_beyond_picture": True}
    bounded = within_picture_bounds(decided, SimpleNamespace(top=top, lower=lower, dress=None))
    assert bounded["sleeves"]["long"] == 0.6 and bounded["sleeves"]["none"] == 0.0 and bounded["long"]["long"] == 0.6
    assert bounded["skirt"] == decided["skirt"]
    inside = within_picture_bounds(decided, SimpleNamespace(top={**top, "sleeve_beyond_picture": False},
                                                            lower={**lower, "hem_beyond_picture": False}, dress=None))
    assert inside == decided


def test_the_weight_sweep_scores_the_validation_part_only():
    """Rules right on every validation picture and wrong on every training one: the rules alone
    (w = 1) score 1 on each decision, whatever the shipped network says; the training part never counts."""
    count = 12
    generator = np.random.default_rng(3)
    truth = {"one_piece": np.r_[[0, 1] * 6], "sleeves": np.arange(count) % 3,
             "long": np.where(np.arange(count) % 2 == 0, np.arange(count) // 2 % 2, -1),
             "skirt": np.where(np.arange(count) % 2 == 0, np.arange(count) // 4 % 2, -1)}
    val = np.arange(count) < 8
    arrays = {"maps": generator.random((count, outfit_net.CHANNELS, outfit_net.MAP_SIZE, outfit_net.MAP_SIZE),
                                       np.float32).astype(np.float16),
              "thighs": generator.random((count, outfit_net.CHANNELS, outfit_net.THIGH_SIZE, outfit_net.THIGH_SIZE),
                                         np.float32).astype(np.float16),
              "scalars": generator.random((count, outfit_net.SCALARS), np.float32), "val": val, **truth}
    for name, classes in outfit_net.HEADS.items():
        right = np.eye(len(classes))[np.maximum(truth[name], 0)]
        arrays[f"rules_{name}"] = np.where(val[:, None], right, np.roll(right, 1, axis=1))
    sweep = train_outfit_net.weight_sweep(arrays)
    for name in outfit_net.HEADS:
        assert sweep[name]["pictures"] == int((truth[name][val] >= 0).sum())
        assert sweep[name]["1.0"] == 1.0
        assert set(sweep[name]) == {"pictures", *(str(w) for w in train_outfit_net.SWEPT_WEIGHTS)}


def test_misalign_shifts_the_parsing_against_the_body_zones_and_nothing_else():
    """The training augmentation: each picture's label channels move by one whole-pixel offset of
    at most the given size; the body's zones and the crop's outside stay where they were."""
    generator = np.random.default_rng(3)
    batch = torch.zeros(8, outfit_net.CHANNELS, 16, 16)
    batch[:, :, 6:10, 6:10] = 1.0  # a square in every channel
    moved = train_outfit_net.misalign(batch, 2, generator)
    labels = len(outfit_net.LABELS)
    assert torch.equal(moved[:, labels:], batch[:, labels:])
    offsets = set()
    for picture in moved:
        rows, columns = np.nonzero(picture[0].numpy())
        dy, dx = int(rows.min()) - 6, int(columns.min()) - 6
        assert max(abs(dy), abs(dx)) <= 2 and picture[0].sum() == 16
        assert all(torch.equal(picture[k], picture[0]) for k in range(labels))  # one offset for all labels
        offsets.add((dy, dx))
    assert len(offsets) > 1
    assert train_outfit_net.misalign(batch, 0, generator) is batch


def test_within_recipe_keeps_the_pictures_a_narrower_recipe_could_draw(tmp_path):
    """Recipe 3 is recipe 2 with recipe 1's short sleeves: a short sleeve lengthened by 0.10 m (2
    drew it, 3 cannot) is left out, a long sleeve shortened by 0.15 m (2 and 3) and recipe 1's
    garments stay; a garment missing an edit of its category is never a recipe's."""
    import json

    from sim.dataset.recipe import RECIPES, within_recipe

    for category, ranges in RECIPES[3].items():
        short_sleeve = {"sleeve": RECIPES[1][category]["sleeve"]} if category.startswith("short-sleeve") else {}
        assert ranges == RECIPES[2][category] | short_sleeve
        assert RECIPES[2][category] != RECIPES[1][category] or "sleeveless" in category
    garments = {"train/g00000-0": ("short-sleeve-top", {"sleeve": 0.10}),
                "train/g00001-0": ("long-sleeve-dress", {"sleeve": -0.15}),
                "val/g00002-1": ("short-sleeve-top", {"sleeve": 0.05}),
                "val/g00003-0": ("long-pants", {"hem": -0.05}),
                "val/g00004-0": ("long-pants", {"hem": -0.05})}
    for folder, (category, edits) in garments.items():
        full = {name: low for name, (low, _) in RECIPES[1][category].items()} | edits
        if folder.endswith("4-0"):
            full.pop("hem_width")
        (tmp_path / folder).mkdir(parents=True)
        (tmp_path / folder / "meta.json").write_text(json.dumps({"category": category, "edits": full}))
    samples = np.array([folder.replace("/", "__") for folder in garments])
    assert train_outfit_net.within(tmp_path, samples, 3).tolist() == [False, True, True, True, False]
    assert train_outfit_net.within(tmp_path, samples, 2).tolist() == [True, True, True, True, False]
    assert train_outfit_net.within(tmp_path, samples, 1).tolist() == [False, False, True, True, False]
    at_the_ends = {name: high for name, (_, high) in RECIPES[3]["short-sleeve-top"].items()}
    assert at_the_ends["sleeve"] == 0.08 and within_recipe("short-sleeve-top", at_the_ends, 3)
