"""`darts dataset make`: a sample's lines land on its mask, samples repeat for a seed, bad input."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.ndimage import distance_transform_edt

from darts.camera import Camera
from darts.dart.io import load_dart
from darts.fileio import read_npz
from darts.geometry.loops import LINE_POINTS
from darts.jobs import run_one
from darts.templates.categories import CATEGORIES
from sim.dataset.cli import garment_jobs, sample_jobs
from sim.dataset.make import hidden_by, line_mask_distances, make_garment, render_sample
from sim.dataset.recipe import EDIT_RANGES, garment_recipe

SAMPLE_FILES = {"image.png", "mask.png", "body_mask.png", "camera.json", "lines.npz", "lines_px.npz", "garment.npz",
                "draped.npz", "meta.json", "result.json"}
TIMES = {"render_s", "times", "wall_seconds", "drape"}  # what may differ between two runs: wall times


def _first_index(category: str) -> int:
    return next(i for i in range(100) if garment_recipe(0, i).category == category)


def _make(out: Path, index: int) -> list[dict]:
    """Garment ``index`` of seed 0 and its samples, made in this process as the dataset's jobs are."""
    job = garment_jobs(index + 1, 1, 0, list(CATEGORIES))[index]
    row = run_one(make_garment, job, out / "garments")
    assert row["status"] == "ok", row
    return [run_one(render_sample, sample, out) for sample in sample_jobs([row], 1)]


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    out = tmp_path_factory.mktemp("dataset")
    return out, {name: _make(out, _first_index(name)) for name in ("short-pants", "sleeveless-top")}


def test_recipes_are_balanced_and_edit_every_line_the_category_has():
    recipes = [garment_recipe(0, i) for i in range(200)]
    counts = {c: sum(r.category == c for r in recipes) for c in CATEGORIES}
    assert set(counts.values()) == {20}
    assert 0.05 < np.mean([r.split == "test" for r in recipes]) < 0.15
    assert set(EDIT_RANGES) == set(CATEGORIES)
    for recipe in recipes[:10]:
        assert {name for name, _ in recipe.edits} == set(EDIT_RANGES[recipe.category])
        assert all(abs(b) <= 2.0 for b in recipe.betas) and len(recipe.betas) == 8
    assert garment_recipe(0, 7) == garment_recipe(0, 7) and garment_recipe(0, 7) != garment_recipe(1, 7)


@pytest.mark.slow
def test_sample_lines_land_on_the_garment_mask_boundary(made, body):
    out, rows = made
    for name, samples in rows.items():
        for row in samples:
            assert row["status"] == "ok", row
            folder = out / row["id"].split("-", 1)[0] / row["id"].split("-", 1)[1]
            assert SAMPLE_FILES <= {p.name for p in folder.iterdir()}
            camera = Camera.from_json(folder / "camera.json")
            mask = np.asarray(Image.open(folder / "mask.png")) > 127
            body_mask = np.asarray(Image.open(folder / "body_mask.png")) > 127
            assert mask.shape == (camera.height, camera.width) and np.asarray(Image.open(folder / "image.png")).shape[2] == 3
            lines = read_npz(folder / "lines.npz")
            assert sorted(lines) == sorted(CATEGORIES[name].line_names)
            assert all(points.shape == (LINE_POINTS, 3) for points in lines.values())
            points = np.concatenate(list(lines.values())).astype(np.float64)
            pixels, _ = camera.project(points)
            assert np.allclose(pixels, np.concatenate(list(read_npz(folder / "lines_px.npz").values())), atol=1e-3)
            to_boundary, to_mask = line_mask_distances(pixels, mask)
            meta = json.loads(folder.joinpath("meta.json").read_text())
            draped = read_npz(folder / "draped.npz")
            shaped = body.shaped(np.asarray(meta["betas"]))[0][0].double().numpy()
            behind_body = hidden_by(points, camera.centre, (shaped, body.faces), (draped["vertices"], draped["faces"])) == 0
            # On the mask's edge; where a loop runs behind the garment it falls inside the mask, and
            # where it runs behind the body (the back of a neckline, an armhole) the body is seen
            # there, within 2 px of the body's mask (as the line is within 2 px of the garment's: a
            # point on the body's silhouette falls on either side of it as the drape's last bits vary,
            # e.g. with torch's thread count: 27 and 28 of one sample's 31 points on the mask itself)
            assert np.median(to_boundary) <= 2.0, (folder, np.median(to_boundary))
            assert to_mask[~behind_body].max() <= 4.0, (folder, to_mask[~behind_body].max())
            col, row_ = np.floor(pixels[behind_body]).astype(int).T
            off_body = distance_transform_edt(~body_mask)
            assert (off_body[row_, col] <= 2.0).mean() >= 0.9
            assert row["line_boundary_median_px"] == pytest.approx(float(np.median(to_boundary)))


@pytest.mark.slow
def test_a_sample_is_made_again_the_same_from_its_seed(made, tmp_path):
    out, rows = made
    again = _make(tmp_path, _first_index("short-pants"))
    for row in again:
        split, name = row["id"].split("-", 1)
        first, second = out / split / name, tmp_path / split / name
        for path in sorted(first.iterdir()):
            other = second / path.name
            if path.suffix == ".png":
                assert np.array_equal(np.asarray(Image.open(path)), np.asarray(Image.open(other))), path.name
            elif path.suffix == ".npz":
                a, b = read_npz(path), read_npz(other)
                assert sorted(a) == sorted(b) and all(np.array_equal(a[k], b[k]) for k in a), path.name
            else:
                a, b = json.loads(path.read_text()), json.loads(other.read_text())
                assert {k: v for k, v in a.items() if k not in TIMES} == {k: v for k, v in b.items() if k not in TIMES}
    assert load_dart(first / "garment.npz").category == "short-pants"


@pytest.mark.parametrize("args, problem", [
    (["--count", "4", "--categories", "poncho"], "unknown category poncho"),
    (["--count", "-3"], "--count must be >= 1"),
    (["--count", "4", "--address", "127.0.0.1:9"], "cannot reach a Ray cluster at 127.0.0.1:9"),
    (["--count", "4", "--views", "0"], "--views must be >= 1"),
])
def test_bad_dataset_input_is_one_line_exit_2_and_no_output(args, problem, tmp_path, run_darts):
    code, out, err = run_darts("dataset", "make", tmp_path / "out", *args)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and problem in err, err
    assert not (tmp_path / "out").exists()


def test_dataset_into_a_file_is_refused(tmp_path, run_darts):
    target = tmp_path / "taken"
    target.write_text("")
    code, _, err = run_darts("dataset", "make", target, "--count", "2")
    assert code == 2 and "exists and is not a directory" in err and target.read_text() == ""


def test_darts_deform_runs_on_a_sample(made, run_darts, tmp_path):
    out, rows = made
    split, name = rows["short-pants"][0]["id"].split("-", 1)
    sample = out / split / name
    code, _, err = run_darts("deform", sample / "garment.npz", "--lines", sample / "lines.npz", "--mask", sample / "mask.png",
                             "--camera", sample / "camera.json", "-o", tmp_path / "fitted.npz", "--report", tmp_path / "r.json")
    assert code == 0, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["handle_rmse"] < 0.005 and report["penetration"] <= 0.01


def test_garments_draped_together_as_worlds_come_out_as_draped_alone(tmp_path):
    """``darts dataset make --worlds``: two tops' drapes stepped as worlds of one solver give the
    garments, lines and rows the jobs give alone (the same drape to a millimetre)."""
    from darts.jobs import run_group
    from sim.dataset.make import make_garments

    tops = [i for i in range(40) if CATEGORIES[garment_recipe(0, i).category].family == "top"][:2]
    jobs = [garment_jobs(tops[-1] + 1, 1, 0, list(CATEGORIES))[i] for i in tops]
    together = run_group(make_garments, make_garment, jobs, tmp_path / "together")
    alone = [run_one(make_garment, job, tmp_path / "alone") for job in jobs]
    for job, a, b in zip(jobs, together, alone):
        assert a["status"] == b["status"] == "ok" and a["vertices"] == b["vertices"]
        assert a["drape_penetration"] == pytest.approx(b["drape_penetration"], abs=0.002)
        draped = [read_npz(tmp_path / where / job.path / "draped.npz")["vertices"] for where in ("together", "alone")]
        assert np.linalg.norm(draped[0] - draped[1], axis=1).mean() < 1e-3


def _joint(body, name: str) -> np.ndarray:
    joints = np.asarray(body.J_regressor) @ np.asarray(body.v_template)
    return joints[list(body.joint_names).index(name)]


@pytest.mark.parametrize("category", ["long-sleeve-top", "short-sleeve-top", "long-pants", "short-pants",
                                      "long-skirt", "short-skirt"])
def test_recipe_two_runs_lengths_up_to_the_elbow_and_the_knee_without_crossing(category, body):
    """Recipe 2's length edits at both ends of their range (the CRDL's target lines on the default
    body's template): a long sleeve's cuff ends 0-4 cm below the elbow at its shortest, a short
    one's 0-4 cm above it at its longest; the legs' hems the same about the knee (long pants: 10-16
    cm below it). Recipe 1 draws the same garments, only its ranges narrower."""
    from darts.crdl.deform import weld_garment
    from darts.crdl.targets import edit_targets
    from darts.dart.build import make_dart
    from darts.templates.defaults import DATASET_EASE, DATASET_EDGE_LENGTH
    from sim.dataset.recipe import RECIPES

    welded = weld_garment(make_dart(category, body, edge_length=DATASET_EDGE_LENGTH, ease=DATASET_EASE))
    sleeve = "sleeve" in category
    edit = "sleeve" if sleeve else "hem"
    low, high = RECIPES[2][category][edit]
    shortest = edit_targets(category, welded.vertices, welded.lines, [(edit, low if category.startswith("long") else high)])
    line = ("left_cuff" if sleeve else "left_hem" if "pants" in category else "hem")
    end = shortest[line].mean(0)
    if sleeve:
        shoulder, elbow, wrist = (_joint(body, f"left_{j}") for j in ("shoulder", "elbow", "wrist"))
        axis = (wrist - shoulder) / np.linalg.norm(wrist - shoulder)
        beyond = float(np.dot(end - elbow, axis))  # > 0: towards the wrist
    else:
        beyond = float(_joint(body, "left_knee")[1] - end[1])  # > 0: below the knee
    long = category.startswith("long")
    expected = {"long-pants": (0.10, 0.16)}.get(category, (0.0, 0.04) if long else (-0.04, 0.0))
    assert expected[0] < beyond < expected[1], beyond
    kept = 1 if long else 0  # the end away from the boundary is recipe 1's
    assert RECIPES[1][category][edit][kept] == (low, high)[kept]
    one, two = garment_recipe(0, 3, recipe=1), garment_recipe(0, 3, recipe=2)
    assert (one.category, one.split, one.betas) == (two.category, two.split, two.betas) and one == garment_recipe(0, 3)


def test_finishing_a_dataset_with_another_seed_or_recipe_is_refused(tmp_path, run_darts):
    """A dataset made with --seed 5 (recipe 1) is not finished with --recipe 2 or --seed 6: one line,
    exit 2, its manifest as it was."""
    manifest = tmp_path / "out" / "garments" / "manifest.jsonl"
    manifest.parent.mkdir(parents=True)
    manifest.write_text(json.dumps({"id": "g00000", "seed": 5, "index": 0, "status": "ok"}) + "\n")
    before = manifest.read_text()
    for args in (["--seed", "5", "--recipe", "2"], ["--seed", "6"]):
        code, out, err = run_darts("dataset", "make", tmp_path / "out", "--count", "2", *args)
        assert code == 2 and len(err.strip().splitlines()) == 1 and "was made with --seed 5 --recipe 1" in err, err
    assert manifest.read_text() == before and sorted(p.name for p in (tmp_path / "out").iterdir()) == ["garments"]


def test_recipe_ends_give_the_gap_between_categories_per_recipe():
    """``scripts/recipe_ends.py``: the gap per recipe is the shortest long end less the longest short
    one, over the garments that recipe could draw (a short sleeve lengthened by 0.10 m is recipe 2's,
    not 3's)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("recipe_ends", Path(__file__).parents[1] / "scripts" / "recipe_ends.py")
    recipe_ends = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(recipe_ends)
    short_edits = {name: low for name, (low, _) in EDIT_RANGES["short-sleeve-top"].items()}
    long_edits = {name: low for name, (low, _) in EDIT_RANGES["long-sleeve-top"].items()}
    rows = [{"category": "short-sleeve-top", "edits": short_edits, "end": 0.30},
            {"category": "short-sleeve-top", "edits": short_edits | {"sleeve": 0.10}, "end": 0.52},
            {"category": "long-sleeve-top", "edits": long_edits, "end": 0.80},
            {"category": "long-sleeve-top", "edits": long_edits | {"sleeve": -0.15}, "end": 0.47}]
    gaps = recipe_ends.summarise(rows)["gaps"]["sleeve"]
    assert gaps["1"]["gap"] == pytest.approx(0.50) and gaps["2"]["gap"] == pytest.approx(-0.05)
    assert gaps["3"] == {"longest_short": 0.30, "shortest_long": 0.47, "gap": 0.17}


@pytest.mark.parametrize("category", ["short-pants", "short-sleeve-top"])
def test_recipe_four_puts_each_garment_end_where_it_was_drawn_along_its_limb(body, category):
    """Recipe 4 draws a length as the garment's end along its own body's limb (s): the garment
    made from the recipe ends there (``garment_end``, within 0.01), its other edits are recipe 2's,
    and every limb keeps a gap between its short and long categories."""
    from sim.dataset.recipe import END_RANGES, END_SUFFIX, RECIPES, garment_end, recipe_garment

    index = next(i for i in range(100) if garment_recipe(0, i, recipe=4).category == category)
    recipe = garment_recipe(0, index, recipe=4)
    drawn = dict(recipe.edits)
    (name, end), = [(n, v) for n, v in drawn.items() if n.endswith(END_SUFFIX)]
    low, high = RECIPES[4][category][name]
    assert low <= end <= high and {n.removesuffix(END_SUFFIX) for n in drawn} == set(RECIPES[2][category])
    dart, _, _ = recipe_garment(recipe, body)
    assert garment_end(dart, body, recipe.betas) == pytest.approx(end, abs=0.01)
    for kind in ("sleeve", "pants", "skirt"):
        (_, short), (_, long) = END_RANGES[f"short-{kind}"], END_RANGES[f"long-{kind}"]
        assert long[0] - short[1] > 0.049
