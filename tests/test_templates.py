"""Garment templates, feature lines, panels and seams, accessories, and the DART file."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh

from darts.dart.build import make_dart
from darts.dart.io import dart_arrays, load_dart, save_dart
from darts.dart.model import REGIMES, welded
from darts.errors import DartsInputError
from darts.fileio import read_npz, save_npz
from darts.geometry.distance import SurfaceDistance
from darts.geometry.mesh import boundary_loops, edge_manifold, loop_length, unique_edges
from darts.templates.build import build_template, ease_profile
from darts.templates.categories import CATEGORIES
from darts.templates.defaults import CROTCH_EASE_TAPER, DEFAULT_EASE, SEAT_EASE, SEAT_EASE_TAPER, WEARING_EASE

GARMENTS = Path(__file__).parents[1] / "scenes" / "garments"
SHIPPED = sorted(p.stem for p in GARMENTS.glob("*.npz"))


def short_edges_and_lone_seam_corners(dart) -> tuple[int, int]:
    """Edges shorter than 0.3 x the median edge, and seam particles (panel corners on a seam)
    with fewer than three neighbours: what issue 30 asks the builder to leave none of."""
    faces = np.asarray(dart.faces, np.int64)
    edges = unique_edges(faces)
    lengths = np.linalg.norm(dart.vertices[edges[:, 0]] - dart.vertices[edges[:, 1]], axis=1)
    degree = np.bincount(edges.reshape(-1), minlength=len(dart.vertices))
    return int((lengths < 0.3 * np.median(lengths)).sum()), int((degree[np.unique(dart.pairs)] < 3).sum())


@pytest.fixture(scope="module")
def body_distance(body):
    return SurfaceDistance(body.v_template.double().numpy(), body.faces)


@pytest.fixture(scope="module")
def darts_by_name():
    return {name: load_dart(GARMENTS / f"{name}.npz") for name in SHIPPED}


def test_every_category_is_shipped_and_listed(run_darts):
    assert set(CATEGORIES) <= set(SHIPPED) and "tshirt-collar-tie" in SHIPPED
    code, out, _ = run_darts("template", "--list")
    assert code == 0 and out.split() == list(CATEGORIES)


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_dart_geometry(name, darts_by_name, body_distance):
    dart = darts_by_name[name]
    family = CATEGORIES[dart.category].family
    vertices, faces, _ = welded(dart)
    # Edge-manifold as one surface and panel by panel.
    assert edge_manifold(faces) and edge_manifold(dart.faces)
    # Every feature line is a closed loop on the welded surface: each vertex has two loop neighbours.
    _, _, index = welded(dart)
    for line, loop in dart.lines.items():
        merged = index[loop]
        merged = merged[np.r_[True, merged[1:] != merged[:-1]]]
        if merged[0] == merged[-1]:
            merged = merged[:-1]
        assert len(np.unique(merged)) == len(merged) >= 8, line
    assert sorted(dart.lines) == sorted(CATEGORIES[dart.category].line_names)
    # The welded boundary is exactly the feature lines; a tie adds its outline, and a collar
    # closes the neckline while adding its outer edge.
    loops = boundary_loops(faces)
    assert len(loops) == len(dart.lines) + ("tie" in dart.accessories)
    # At rest no vertex is inside the body, seam pairs coincide, there are several panels.
    signed, _, _ = body_distance.query(dart.vertices)
    assert signed.min() >= 0.0, f"{(signed < 0).sum()} vertices inside the body"
    gaps = np.linalg.norm(dart.vertices[dart.pairs[:, 0]] - dart.vertices[dart.pairs[:, 1]], axis=1)
    assert gaps.max() == 0.0
    assert len(dart.panel_names) >= 2 and len(np.unique(dart.panel)) == len(dart.panel_names)
    # No slivers (issue 30): the shortest edge is at least 0.3 x the median, and every seam particle
    # has three neighbours or more (one hem corner of trousers may be left with two, where the outseam
    # meets the hem: the short pants' right one).
    short, lone = short_edges_and_lone_seam_corners(dart)
    assert short == 0 and lone <= (family == "pants"), (short, lone)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    if family == "skirt":  # one tube around both legs: a connected annulus
        assert mesh.body_count == 1 and mesh.euler_number == 0
    if family == "pants":  # two legs joined at the crotch: connected, three openings
        assert mesh.body_count == 1 and mesh.euler_number == -1
        assert dart.vertices[dart.lines["left_hem"], 0].min() > 0 > dart.vertices[dart.lines["right_hem"], 0].max()


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_dart_round_trips_exactly(name, tmp_path):
    original = read_npz(GARMENTS / f"{name}.npz")
    save_dart(load_dart(GARMENTS / f"{name}.npz"), tmp_path / "copy.npz")
    again = read_npz(tmp_path / "copy.npz")
    assert sorted(original) == sorted(again)
    for key in original:
        assert original[key].dtype == again[key].dtype and np.array_equal(original[key], again[key]), key


def test_rebuilt_template_matches_the_shipped_geometry(body):
    """The shipped file was made on another CPU: a rebuild here may differ by float rounding, and the
    remesh by a few vertices (seen: 12,285 against 12,271), so it is compared as geometry: vertex
    count within 0.5 %, surface distance both ways (mean under 0.3 mm, max under 3 mm; edges are
    11 mm) and every feature line's length within 1 %."""
    dart = make_dart("short-sleeve-top", body)
    shipped = load_dart(GARMENTS / "short-sleeve-top.npz")
    assert 5000 <= len(dart.vertices) <= 8000
    assert short_edges_and_lone_seam_corners(dart) == (0, 0)
    assert abs(len(dart.vertices) / len(shipped.vertices) - 1) <= 0.005
    assert abs(len(dart.faces) / len(shipped.faces) - 1) <= 0.005
    for source, target in ((dart, shipped), (shipped, dart)):
        distance = np.abs(SurfaceDistance(target.vertices, target.faces).query(source.vertices, winding=False)[0])
        assert distance.mean() < 3e-4 and distance.max() < 3e-3, (distance.mean(), distance.max())
    assert sorted(dart.lines) == sorted(shipped.lines) and dart.panel_names == shipped.panel_names
    for name in dart.lines:
        ours = loop_length(dart.vertices, np.asarray(dart.lines[name]))
        theirs = loop_length(shipped.vertices, np.asarray(shipped.lines[name]))
        assert abs(ours / theirs - 1) < 0.01, name


def test_template_build_is_deterministic_on_one_machine(body):
    first = make_dart("short-skirt", body, edge_length=0.02)
    again = make_dart("short-skirt", body, edge_length=0.02)
    for key, value in dart_arrays(first).items():
        assert np.array_equal(value, dart_arrays(again)[key]), key


@pytest.mark.slow
def test_edge_length_controls_resolution(body):
    coarse = make_dart("short-skirt", body, edge_length=0.02)
    fine = make_dart("short-skirt", body, edge_length=0.012)
    ratio = len(fine.vertices) / len(coarse.vertices)
    assert 2.0 < ratio < 3.6  # about (0.02 / 0.012)^2 = 2.8
    edges = np.linalg.norm(np.diff(coarse.vertices[coarse.faces[:, [0, 1]]], axis=1)[:, 0], axis=1)
    assert 0.014 < np.median(edges) < 0.026


@pytest.mark.slow
def test_seam_regimes_on_the_command_line(run_darts, tmp_path):
    out = tmp_path / "g.npz"
    code, _, err = run_darts("template", "short-skirt", "-o", out, "--seam", "all=repulsive", "--seam", "left_side=partial",
                             "--seam", "waistband=loose:5")
    assert code == 0, err
    dart = load_dart(out)
    seams = {s.name: s for s in dart.seams}
    assert seams["right_side"].regime == "repulsive" and seams["right_side"].rest_length > 0
    assert seams["waistband"].regime == "loose" and seams["waistband"].stiffness == 5.0
    partial = dart.pair_seam == dart.seam_names.index("left_side")
    active = dart.pair_active[partial]
    assert 0 < active.sum() < len(active)  # springs only on part of the seam
    assert np.all(dart.pair_position[partial][active] <= 0.5)
    assert set(REGIMES) >= {s.regime for s in dart.seams}


def test_accessories_are_stitched_to_the_neckline(darts_by_name, body_distance):
    dart = darts_by_name["tshirt-collar-tie"]
    assert dart.accessories == ["collar", "tie"] and {"collar", "tie"} <= set(dart.panel_names)
    for name in ("collar", "tie"):
        mine = dart.pair_seam == dart.seam_names.index(name)
        assert mine.any()
        garment_end, accessory_end = dart.pairs[mine].T
        assert np.isin(garment_end, dart.lines["neckline"]).all()
        panel = dart.panel_names.index(name)
        assert np.isin(accessory_end, dart.faces[dart.panel == panel]).all()
    signed, _, _ = body_distance.query(dart.vertices)
    assert signed.min() >= 0.0


def test_inspect_reports_and_draws(run_darts, tmp_path):
    code, out, _ = run_darts("inspect", GARMENTS / "long-pants.npz", "--json", "--png", tmp_path / "p.png")
    info = json.loads(out)
    assert code == 0 and info["category"] == "long-pants" and len(info["panels"]) >= 4
    assert {"left_inseam", "right_outseam", "waistband"} <= set(info["seams"])
    assert all(line["length_m"] > 0.2 for line in info["lines"].values())
    image = (tmp_path / "p.png").read_bytes()
    assert image[:8] == b"\x89PNG\r\n\x1a\n" and len(image) > 10_000


def test_commands_taking_a_garment_accept_shipped_names_and_list_them(run_darts, tmp_path, capsys):
    """darts inspect / export / deform take a shipped name like darts-sim; --help lists the names."""
    code, out, _ = run_darts("inspect", "short-skirt", "--json")
    assert code == 0 and json.loads(out)["category"] == "short-skirt"
    code, _, _ = run_darts("export", "short-skirt", "-o", tmp_path / "skirt.obj")
    assert code == 0 and (tmp_path / "skirt.obj").is_file()
    for command in ("inspect", "export", "deform"):
        with pytest.raises(SystemExit) as done:
            run_darts(command, "--help")
        out = capsys.readouterr().out
        assert done.value.code == 0 and "shipped garment" in out and "tshirt-collar-tie" in "".join(out.split()), command
    from sim.cli import parser

    assert "short-sleeve-dress" in "".join(parser().format_help().split())


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".glb"])
def test_export_mesh_with_panel_colours(run_darts, tmp_path, suffix):
    out = tmp_path / f"skirt{suffix}"
    code, _, err = run_darts("export", GARMENTS / "short-skirt.npz", "-o", out)
    assert code == 0, err
    mesh = trimesh.load(out, force="mesh", process=False)
    dart = load_dart(GARMENTS / "short-skirt.npz")
    assert len(mesh.faces) == len(dart.faces)
    colours = np.unique(np.asarray(mesh.visual.vertex_colors)[:, :3], axis=0)
    assert len(colours) == len(dart.panel_names)


def _broken(tmp_path, edit):
    arrays = dart_arrays(load_dart(GARMENTS / "short-skirt.npz"))
    edit(arrays)
    path = tmp_path / "broken.npz"
    save_npz(path, **arrays)
    return path


@pytest.mark.parametrize("edit, message", [
    (lambda a: a.pop("seam_regimes"), "missing key"),
    (lambda a: a.update(vertices=a["vertices"][:, :2]), "'vertices' has shape"),
    (lambda a: a["vertices"].__setitem__((0, 0), np.nan), "NaN"),
    (lambda a: a.update(faces=a["faces"] + 100000), "indices outside"),
    (lambda a: a.update(category=np.array("poncho")), "unknown category"),
    (lambda a: a["seam_regimes"].__setitem__(0, "glued"), "unknown regime"),
    (lambda a: a["seam_stiffness"].__setitem__(0, -1.0), "stiffness must be >= 0"),
    (lambda a: a.update(format=np.array("dart/99")), "not supported"),
    (lambda a: a.update(line_vertices=a["line_vertices"][::-1].copy()), "closed edge loop"),
])
def test_corrupt_darts_give_one_clear_line(tmp_path, run_darts, edit, message):
    path = _broken(tmp_path, edit)
    with pytest.raises(DartsInputError, match=message):
        load_dart(path)
    code, out, err = run_darts("inspect", path, "--png", tmp_path / "x.png")
    assert code == 2 and err.count("\n") == 1 and str(path) in err and message in err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("args, message", [
    (["poncho"], "unknown category"),
    (["short-skirt", "--seam", "nothing=stiff"], "unknown seam"),
    (["short-skirt", "--seam", "left_side=glued"], "unknown regime"),
    (["short-skirt", "--seam", "left_side=stiff:-5"], ">= 0"),
    (["short-skirt", "--seam", "left_side"], "NAME=REGIME"),
    (["short-skirt", "--edge-length", "0"], "edge_length must be a number in [0.003, 0.1]"),
    (["short-skirt", "--accessory", "collar"], "needs a neckline"),
])
def test_bad_template_requests_exit_2_without_output(tmp_path, run_darts, args, message):
    out = tmp_path / "g.npz"
    code, _, err = run_darts("template", *args, "-o", out)
    assert code == 2 and message in err and err.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("name", ["long-pants", "short-pants"])
def test_trousers_carry_a_sitting_allowance(name, darts_by_name, body_distance):
    """Trousers are cut snug at the waistband (DEFAULT_EASE) and SEAT_EASE off the body from
    SEAT_EASE_TAPER below the waist line down (issue 46: cut 6 mm off everywhere they stretched 34 %
    sitting)."""
    dart = darts_by_name[name]
    vertices = np.asarray(dart.vertices, np.float64)
    signed = body_distance.query(vertices)[0]
    below = vertices[:, 1].max() - vertices[:, 1] > SEAT_EASE_TAPER + 0.02
    assert np.median(signed[dart.lines["waist"]]) == pytest.approx(DEFAULT_EASE, abs=5e-4)
    assert np.median(signed[below]) == pytest.approx(SEAT_EASE, abs=1e-3)
    assert np.percentile(signed[below], 5) > 0.5 * SEAT_EASE


@pytest.mark.parametrize("name, ease", [("short-sleeve-top", WEARING_EASE), ("long-sleeve-dress", WEARING_EASE),
                                        ("sleeveless-top", WEARING_EASE), ("short-skirt", DEFAULT_EASE),
                                        ("long-skirt", DEFAULT_EASE)])
def test_every_other_category_keeps_one_ease_everywhere(name, ease, darts_by_name, body_distance):
    """Tops and dresses are cut WEARING_EASE off the body (issue 46: cut 6 mm off, the sleeved ones
    stretched 17-19 % squatting), skirts DEFAULT_EASE: where the cloth lies on the body (a top all
    over, a dress above the hips, a skirt at its waist; below, cloth bridges the legs) the median
    within 0.5 mm and 95 % of it at least 1.5 mm less."""
    dart = darts_by_name[name]
    assert CATEGORIES[dart.category].ease == ease
    vertices = np.asarray(dart.vertices, np.float64)
    family = CATEGORIES[dart.category].family
    on_body = (dart.lines["waist"] if family == "skirt" else
               np.flatnonzero(vertices[:, 1] > vertices[:, 1].max() - (0.4 if family == "dress" else 1.0)))
    signed = body_distance.query(vertices[on_body])[0]
    assert np.median(signed) == pytest.approx(ease, abs=5e-4)
    assert np.percentile(signed, 5) > ease - 1.5e-3


def test_ease_profile_grows_from_the_waistband_and_the_crotch_to_the_seat():
    """Down a leg 0.2 m off the mid-plane the ease grows from the waistband's to the seat's over
    SEAT_EASE_TAPER; at the crotch point (the lowest within 1 cm of x = 0) it is the waistband's,
    growing back over CROTCH_EASE_TAPER."""
    depths = np.array([0.0, 0.5, 1.0, 2.0, 10.0]) * SEAT_EASE_TAPER
    leg = np.c_[np.full(5, 0.2), 1.0 - depths, np.zeros(5)]
    crotch = [0.0, 1.0 - depths[-1] - 0.1, 0.0]
    beside = np.add(crotch, [0.0, 0.5 * CROTCH_EASE_TAPER, 0.0])
    vertices = np.r_[leg, [crotch, beside]]
    profile = ease_profile(vertices, 0.006, 0.03)
    assert profile == pytest.approx([0.006, 0.018, 0.03, 0.03, 0.03, 0.006, 0.018])
    assert ease_profile(vertices, 0.006, None) == pytest.approx(np.full(7, 0.006))
    assert CATEGORIES["long-pants"].seat_ease == SEAT_EASE and CATEGORIES["long-skirt"].seat_ease is None


def test_template_command_cuts_to_a_chosen_ease(run_darts, tmp_path, body_distance):
    """``darts template short-skirt --ease 0.012`` cuts the skirt 12 mm off the body (at its waist,
    where it lies on the body); an ease out of range is one line, exit 2, nothing written."""
    out = tmp_path / "loose.npz"
    code, _, err = run_darts("template", "short-skirt", "--ease", "0.012", "--edge-length", "0.03", "-o", out)
    assert code == 0, err
    dart = load_dart(out)
    waist = np.asarray(dart.vertices, np.float64)[dart.lines["waist"]]
    assert np.median(body_distance.query(waist)[0]) == pytest.approx(0.012, abs=1e-3)
    bad = tmp_path / "bad.npz"
    code, _, err = run_darts("template", "short-skirt", "--ease", "0.2", "-o", bad)
    assert code == 2 and "ease must be a number in [0, 0.05]" in err and err.count("\n") == 1, err
    assert not bad.exists()


def test_a_seat_ease_out_of_range_is_refused(body):
    with pytest.raises(DartsInputError, match="seat ease must be between 0 and 0.05 m"):
        build_template("long-pants", body, seat_ease=0.2)


def test_template_command_cuts_trousers_to_a_chosen_seat_ease(run_darts, tmp_path, body_distance):
    """``darts template long-pants --seat-ease 0.006`` cuts them as close as every other template
    (6 mm off the body below the waistband too); a seat ease for a skirt, or out of range, is one
    line, exit 2, nothing written."""
    out = tmp_path / "fitted.npz"
    code, _, err = run_darts("template", "long-pants", "--seat-ease", "0.006", "--edge-length", "0.03", "-o", out)
    assert code == 0, err
    dart = load_dart(out)
    vertices = np.asarray(dart.vertices, np.float64)
    below = vertices[:, 1].max() - vertices[:, 1] > SEAT_EASE_TAPER + 0.02
    assert np.median(body_distance.query(vertices[below])[0]) == pytest.approx(DEFAULT_EASE, abs=1e-3)
    for args, message in ((["short-skirt", "--seat-ease", "0.02"], "seat_ease is for trousers (long-pants, short-pants)"),
                          (["short-pants", "--seat-ease", "0.2"], "seat_ease must be a number in [0, 0.05]")):
        bad = tmp_path / "bad.npz"
        code, _, err = run_darts("template", *args, "-o", bad)
        assert code == 2 and message in err and err.count("\n") == 1, err
        assert not bad.exists()


@pytest.mark.slow
@pytest.mark.parametrize("category, betas", [
    ("sleeveless-dress", [-2.0, 1.5, -1.0]),  # the dress bridge once came out mis-oriented here
    ("short-sleeve-dress", [2.0, -1.0, 1.0]),
    ("long-pants", [-2.0, 1.5, -1.0]),
    ("long-skirt", [2.0, -1.0, 1.0]),
])
def test_templates_fit_other_body_shapes(body, category, betas):
    dart = make_dart(category, body, betas=betas)
    shaped, _ = body.shaped(np.array(betas, np.float32))
    signed, _, _ = SurfaceDistance(shaped[0].double().numpy(), body.faces).query(dart.vertices)
    assert signed.min() >= 0.0
    _, faces, _ = welded(dart)
    assert edge_manifold(faces) and len(boundary_loops(faces)) == len(dart.lines)
    assert np.allclose(dart.body_betas, betas)
    short, lone = short_edges_and_lone_seam_corners(dart)
    assert short == 0 and lone <= 1, (short, lone)


@pytest.mark.parametrize("category", ["short-sleeve-dress", "long-pants"])
def test_dataset_resolution_templates_have_no_slivers(body, category):
    """The reconstruction's templates (DATASET_EDGE_LENGTH, 2 cm) are built the same way."""
    from darts.templates.defaults import DATASET_EDGE_LENGTH

    short, lone = short_edges_and_lone_seam_corners(make_dart(category, body, edge_length=DATASET_EDGE_LENGTH))
    assert short == 0 and lone <= 1, (short, lone)
