"""USD export: metadata, time samples and extents, validators, atomic writes."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from darts.dart.export import panel_colors
from darts.dart.io import load_dart
from darts.motion.amass import load_motion
from darts.motion.posing import pose_sequence
from exporters.usd import UsdAnimationWriter, validate_usd
from scenes import MOTIONS_DIR

GARMENTS = Path(__file__).parents[1] / "scenes" / "garments"


@pytest.fixture(scope="module")
def walk_frames(body):
    motion = load_motion(MOTIONS_DIR / "walk.npz")
    vertices, _ = pose_sequence(body, motion.with_frames(body_pose=motion.body_pose[:12], trans=motion.trans[:12]))
    return vertices, motion.fps


@pytest.mark.parametrize("suffix", [".usda", ".usdc"])
def test_animated_stage_is_valid_and_reads_back(body, walk_frames, tmp_path, suffix):
    from pxr import Usd, UsdGeom

    vertices, fps = walk_frames
    dart = load_dart(GARMENTS / "short-sleeve-top.npz")
    garment = dart.vertices[None] + np.linspace(0, 0.1, len(vertices))[:, None, None]
    path = tmp_path / f"scene{suffix}"
    with UsdAnimationWriter(path, fps) as writer:
        writer.add_mesh("body", body.faces, body.num_vertices, np.full((len(body.faces), 3), 0.8))
        writer.add_mesh("garment", dart.faces, len(dart.vertices), panel_colors(len(dart.panel_names))[dart.panel])
        writer.add_curves("garment", dart.pairs)
        for frame in range(len(vertices)):
            writer.write_frame({"body": vertices[frame], "garment": garment[frame]})
    assert validate_usd(path) == []
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == fps and stage.GetStartTimeCode() == 0 and stage.GetEndTimeCode() == len(vertices) - 1
    assert stage.GetDefaultPrim().GetPath() == "/World"
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/body"))
    points = np.array(mesh.GetPointsAttr().Get(5))
    assert np.array_equal(points, vertices[5])
    extent = np.array(mesh.GetExtentAttr().Get(5))
    assert np.allclose(extent, [vertices[5].min(0), vertices[5].max(0)])
    garment_mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/garment"))
    assert len(garment_mesh.GetDisplayColorPrimvar().Get()) == len(dart.faces)
    assert len(garment_mesh.GetPointsAttr().GetTimeSamples()) == len(vertices)


def test_failed_export_leaves_no_file(body, tmp_path):
    path = tmp_path / "broken.usdc"
    with pytest.raises(ValueError, match="finite"):
        with UsdAnimationWriter(path, 30.0) as writer:
            writer.add_mesh("body", body.faces, body.num_vertices)
            bad = np.zeros((body.num_vertices, 3), np.float32)
            bad[3] = np.nan
            writer.write_frame({"body": bad})
    assert list(tmp_path.iterdir()) == []


def test_validators_catch_a_stage_without_metadata(tmp_path):
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(tmp_path / "bare.usda"))
    UsdGeom.Mesh.Define(stage, "/World/m").CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    stage.GetRootLayer().Save()
    errors = " ".join(validate_usd(tmp_path / "bare.usda"))
    assert "upAxis" in errors and "metersPerUnit" in errors and "defaultPrim" in errors
