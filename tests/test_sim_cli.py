"""`darts-sim`: USD and mesh-sequence output, stats, the 120 fps AMASS file, bad input, blow-ups."""
from __future__ import annotations

import json

import numpy as np
import pytest

from exporters.usd import validate_usd
from scenes import GARMENTS_DIR, MOTIONS_DIR
from tests.helpers import write_classic_amass_120fps

QUICK = ("--frames", 5, "--settle", 0.2, "--quiet")


def test_usd_output_is_valid_animated_and_measured(run_sim, tmp_path):
    from pxr import Usd, UsdGeom

    out, stats_path = tmp_path / "walk.usda", tmp_path / "stats.json"
    code, _, err = run_sim("short-skirt", "walk", "-o", out, "--stats", stats_path, "--seam-curves", *QUICK)
    assert code == 0, err
    assert validate_usd(out) == []
    stage = Usd.Stage.Open(str(out))
    assert UsdGeom.GetStageUpAxis(stage) == "Z" and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == 30.0 and (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, 4.0)
    assert stage.GetDefaultPrim().GetPath() == "/World"
    garment = UsdGeom.Mesh(stage.GetPrimAtPath("/World/garment"))
    assert garment.GetPointsAttr().GetTimeSamples() == [0.0, 1.0, 2.0, 3.0, 4.0]
    points = np.array(garment.GetPointsAttr().Get(4.0))
    assert points.shape[1] == 3 and np.isfinite(points).all() and 0.5 < points[:, 2].mean() < 1.2  # on the hips, Z up
    assert stage.GetPrimAtPath("/World/body").IsValid() and stage.GetPrimAtPath("/World/garment_seams").IsValid()
    stats = json.loads(stats_path.read_text())
    assert {"vertices", "substeps", "fps", "wall_seconds", "sim_fps", "frames"} <= set(stats)
    assert stats["vertices"] == len(points) and stats["substeps"] == 20 and stats["fps"] == 30.0
    assert len(stats["frames"]) == 5 and stats["sim_fps"] > 0 and stats["stable"]
    frame = stats["frames"][-1]
    assert frame["penetration"] <= 0.01 and frame["max_speed"] < 5.0 and frame["self_intersections"] == 0
    assert stats["self_contact"] is True and stats["max_self_intersections"] == 0
    assert set(frame["seam_gap"]) == {"left_side", "right_side", "waistband"}
    assert all(gap["max"] <= 1e-3 for gap in frame["seam_gap"].values())  # every seam stiff
    # speeds: the fastest of any substep is at least the last substep's, and at least what the
    # recorded frames show (a frame's displacement is the mean of its substeps' velocities)
    for f in stats["frames"][1:]:
        assert f["max_substep_speed"] >= f["max_speed"] - 1e-6
        assert f["max_substep_speed"] >= f["frame_speed"] - 1e-4 and 0 < f["frame_speed"] < 5.0
    assert stats["max_substep_speed"] == max(f["max_substep_speed"] for f in stats["frames"])


def test_mesh_sequence_output(run_sim, tmp_path):
    import trimesh

    out = tmp_path / "frames"
    code, _, err = run_sim(GARMENTS_DIR / "short-skirt.npz", MOTIONS_DIR / "walk.npz", "-o", out, "--format", "ply",
                           "--solver", "mass-spring", *QUICK)
    assert code == 0, err
    names = sorted(p.name for p in out.iterdir())
    assert names == [f"{kind}_{i:04d}.ply" for kind in ("body", "garment") for i in range(5)]
    garment = trimesh.load(out / "garment_0004.ply", process=False)
    from darts.dart.io import load_dart

    vertex_count = len(load_dart(GARMENTS_DIR / "short-skirt.npz").vertices)
    assert len(garment.vertices) == vertex_count and np.isfinite(garment.vertices).all()


@pytest.mark.slow
def test_classic_amass_120fps_file_simulates_at_30fps(run_sim, tmp_path):
    write_classic_amass_120fps(MOTIONS_DIR / "run.npz", tmp_path / "amass_120.npz")
    stats_path = tmp_path / "stats.json"
    code, _, err = run_sim("short-skirt", tmp_path / "amass_120.npz", "-o", tmp_path / "run.usdc", "--fps", 30,
                           "--stats", stats_path, "--quiet")
    assert code == 0, err
    stats = json.loads(stats_path.read_text())
    assert len(stats["frames"]) == 91 and stats["stable"]
    assert all(np.isfinite(f["max_speed"]) for f in stats["frames"])


@pytest.mark.parametrize("args, message", [
    (("walk", "walk"), "short-skirt"),  # a motion given as the garment: replaced below
    (("short-skirt", "short-skirt"), "motion"),
    (("short-skirt", "walk", "--seam", "nosuch=stiff"), "unknown seam 'nosuch'"),
    (("short-skirt", "walk", "--seam", "left_side=glued"), "unknown regime 'glued'"),
    (("short-skirt", "walk", "--seam", "left_side=loose:-5"), "stiffness must be"),
    (("short-skirt", "walk", "--fps", 0), "fps must be > 0"),
    (("short-skirt", "walk", "--start", 500), "frame range"),
    # the walk has 121 frames at 30 fps: five from 119 would be cut to two without a word
    (("short-skirt", "walk", "--start", 119, "--frames", 5), "run past the motion's end: it has 121 frames at 30 fps, 2 left"),
    (("missing.npz", "walk"), "missing.npz"),
])
def test_bad_input_is_one_line_exit_2_and_no_output(run_sim, tmp_path, args, message):
    garment, motion, *rest = args
    garment = MOTIONS_DIR / "walk.npz" if garment == "walk" else garment
    motion = GARMENTS_DIR / "short-skirt.npz" if motion == "short-skirt" else motion
    out = tmp_path / "out.usdc"
    code, _, err = run_sim(garment, motion, "-o", out, *rest, "--quiet")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("darts-sim: error:")
    if message != "short-skirt":
        assert message in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_blow_up_exits_3_and_keeps_the_good_frames(run_sim, tmp_path):
    from pxr import Usd

    out, stats_path = tmp_path / "out.usdc", tmp_path / "stats.json"
    code, _, err = run_sim("short-skirt", "walk", "-o", out, "--max-speed", 1.0, "--settle", 0, "--stats", stats_path, "--quiet")
    assert code == 3 and "unstable at frame" in err
    stats = json.loads(stats_path.read_text())
    kept = len(stats["frames"])
    assert not stats["stable"] and 0 < kept < 60
    stage = Usd.Stage.Open(str(out))
    assert stage.GetEndTimeCode() == kept - 1


@pytest.mark.slow
def test_preview_gif_and_png_show_the_animation(run_sim, run_darts, tmp_path):
    from PIL import Image

    out, gif = tmp_path / "walk.usdc", tmp_path / "walk.gif"
    code, _, err = run_sim("short-skirt", "walk", "-o", out, "--preview", gif, "--no-self-contact", *QUICK)
    assert code == 0, err
    with Image.open(gif) as image:
        assert image.n_frames == 5 and min(image.size) >= 300
        first = np.asarray(image.convert("RGB"), np.float64)
        image.seek(4)
        last = np.asarray(image.convert("RGB"), np.float64)
    # Something is drawn (not a blank canvas), in the garment's panel colours, and it moves.
    assert (first.sum(axis=2) < 600).mean() > 0.02
    assert np.abs(first - last).mean() > 0.1
    png = tmp_path / "sheet.png"
    code, _, err = run_darts("render", out, "-o", png)
    assert code == 0, err
    with Image.open(png) as image:
        assert image.size[0] > 3 * image.size[1]  # six frames side by side


def test_preview_bad_input_is_one_line_and_writes_nothing(run_sim, run_darts, tmp_path):
    code, _, err = run_sim("short-skirt", "walk", "-o", tmp_path / "a.usdc", "--preview", tmp_path / "a.avi", *QUICK)
    assert code == 2 and "preview must end in" in err and not list(tmp_path.iterdir())
    not_usd = tmp_path / "fake.usd"
    not_usd.write_text("hello")
    code, _, err = run_darts("render", not_usd, "-o", tmp_path / "b.gif")
    assert code == 2 and "fake.usd" in err and not (tmp_path / "b.gif").exists()
    code, _, err = run_darts("render", MOTIONS_DIR / "walk.npz", "-o", tmp_path / "b.gif")
    assert code == 2 and "walk.npz" in err and not (tmp_path / "b.gif").exists()
