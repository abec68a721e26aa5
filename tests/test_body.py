"""The SMPL-format body: the bundled default, official file loading, export, segmentation."""
from __future__ import annotations

import json
import pickle
import sys
import types

import numpy as np
import pytest
import scipy.sparse
import torch

from darts.body.io import body_from_arrays, load_body
from darts.body.joints import SMPL_PARENTS, SMPLX_JOINT_NAMES
from darts.body.lbs import axis_angle_to_matrix
from darts.body.segmentation import PART_NAMES, body_segmentation, segment_body
from darts.errors import DartsInputError
from darts.fileio import save_npz
from tests.helpers import ChumpyArray, legacy_pickle, random_motion_arrays
from tests.reference_smpl import ReferenceSMPL, rodrigues


def test_default_body_is_an_smpl_t_pose(body, run_darts):
    code, out, _ = run_darts("body", "info", "--json")
    info = json.loads(out)
    assert code == 0
    assert info["joints"] == 24 and info["parents"] == SMPL_PARENTS.tolist()
    assert 1.6 <= info["height_m"] <= 1.9
    assert info["betas"] >= 10
    _, joints = body.shaped()
    joints = joints[0].numpy()
    names = body.joint_names
    for side in ("left", "right"):
        dy = joints[names.index(f"{side}_wrist"), 1] - joints[names.index(f"{side}_shoulder"), 1]
        assert abs(dy) < 0.05
    # T-pose: arms along +-X, left arm on +X, face towards +Z (nose in front of the head joint).
    assert joints[names.index("left_wrist"), 0] > 0.6 and joints[names.index("right_wrist"), 0] < -0.6


def test_default_body_mesh_is_closed_and_weights_are_a_partition(body):
    faces = body.faces
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert (counts == 2).all(), "every edge is shared by exactly two triangles"
    weights = body.weights.numpy()
    assert weights.min() >= 0 and np.allclose(weights.sum(1), 1, atol=1e-5)
    # 6,890 vertices like SMPL: collision cost of the body matches what SMPL users expect.
    assert 6000 <= body.num_vertices <= 8000


def test_shape_directions_change_the_body(body):
    rest, _ = body.shaped()
    for k in range(10):
        betas = torch.zeros(k + 1)
        betas[k] = 2.0
        moved, _ = body.shaped(betas)
        assert (moved - rest).norm(dim=-1).max() > 0.005


def test_rodrigues_matches_reference_and_has_finite_gradient_at_zero():
    rng = np.random.default_rng(1)
    vectors = rng.normal(0, 1.0, (50, 3))
    ours = axis_angle_to_matrix(torch.tensor(vectors)).numpy()
    assert np.abs(ours - np.stack([rodrigues(v) for v in vectors])).max() < 1e-12
    zero = torch.zeros(3, dtype=torch.float64, requires_grad=True)
    axis_angle_to_matrix(zero).sum().backward()
    assert torch.isfinite(zero.grad).all()


def test_lbs_is_differentiable(body):
    pose = torch.zeros(1, 24, 3, dtype=torch.float32, requires_grad=True)
    betas = torch.zeros(4, requires_grad=True)
    out = body(pose, betas=betas)
    out.vertices[..., 1].mean().backward()
    assert pose.grad.abs().sum() > 0 and betas.grad.abs().sum() > 0


def test_export_matches_reference_smpl_for_random_poses(tmp_path, run_darts):
    """`darts body export` output, posed by an independent SMPL implementation, equals
    `darts body pose` to 0.1 mm."""
    betas = [0.8, -1.2, 0.5, 0.3]
    code, _, err = run_darts("body", "export", "-o", tmp_path / "body.npz", "--betas", *betas)
    assert code == 0, err
    arrays = random_motion_arrays(6, seed=3)
    save_npz(tmp_path / "motion.npz", **arrays)
    code, _, err = run_darts("body", "pose", tmp_path / "motion.npz", "-o", tmp_path / "posed.npz", "--betas", *betas)
    assert code == 0, err
    posed = np.load(tmp_path / "posed.npz")
    reference = ReferenceSMPL(tmp_path / "body.npz")
    pose24 = np.concatenate([arrays["poses"][:, :66], np.zeros((6, 6))], axis=1).reshape(6, 24, 3)
    for frame in range(6):
        expected = reference(pose24[frame], np.zeros(0), arrays["trans"][frame])
        assert np.abs(posed["vertices"][frame] - expected).max() < 1e-4


def test_exported_npz_loads_back_identically(body, tmp_path):
    from darts.body.io import export_smpl_npz, read_body

    export_smpl_npz(read_body(), tmp_path / "b.npz")
    again = load_body(tmp_path / "b.npz")
    pose = torch.randn(3, 24, 3) * 0.3
    assert (again(pose).vertices - body(pose).vertices).abs().max() < 1e-5


def _official_arrays(body, num_joints_layout="smpl"):
    arrays = {
        "v_template": body.v_template.double().numpy(), "shapedirs": body.shapedirs.double().numpy(),
        "posedirs": np.zeros((body.num_vertices, 3, 207)), "J_regressor": body.J_regressor.double().numpy(),
        "weights": body.weights.double().numpy(),
        "kintree_table": np.stack([np.r_[4294967295, SMPL_PARENTS[1:]], np.arange(24)]).astype(np.int64),
        "f": body.faces.astype(np.uint32),
    }
    return arrays


def test_legacy_pickle_with_chumpy_and_sparse_loads_without_chumpy(body, tmp_path):
    """SMPL's legacy .pkl: chumpy arrays and a scipy sparse J_regressor, read with no chumpy installed."""
    arrays = _official_arrays(body)
    legacy = dict(arrays, shapedirs=ChumpyArray(arrays["shapedirs"]),
                  J_regressor=scipy.sparse.csc_matrix(arrays["J_regressor"]), bs_style="lbs", bs_type="lrotmin")
    (tmp_path / "SMPL_NEUTRAL.pkl").write_bytes(legacy_pickle(legacy))
    assert "chumpy" not in sys.modules

    loaded = load_body(tmp_path / "SMPL_NEUTRAL.pkl")
    assert loaded.kind == "smpl" and loaded.num_betas == body.num_betas
    pose = torch.randn(2, 24, 3) * 0.3
    assert (loaded(pose).vertices - body(pose).vertices).abs().max() < 1e-5


def test_pickle_with_foreign_classes_is_refused(tmp_path):
    path = tmp_path / "evil.pkl"
    with open(path, "wb") as handle:
        pickle.dump({"v_template": types.SimpleNamespace(a=1)}, handle)
    with pytest.raises(DartsInputError, match="refusing to load"):
        load_body(path)


def _smplx_like(body) -> dict:
    """A 55-joint SMPL-X-layout file made from the default body: extra joints carry no weight."""
    parents = list(SMPL_PARENTS[:22]) + [15, 15, 15]
    for wrist in (20, 21):
        for _finger in range(5):
            parents += [wrist, len(parents), len(parents) + 1]
    weights = np.zeros((body.num_vertices, 55))
    w24 = body.weights.double().numpy()
    weights[:, :22] = w24[:, :22]
    weights[:, 20] += w24[:, 22]
    weights[:, 21] += w24[:, 23]
    regressor = np.zeros((55, body.num_vertices))
    regressor[:22] = body.J_regressor.double().numpy()[:22]
    regressor[22:25] = body.J_regressor.double().numpy()[15]
    regressor[25:40] = body.J_regressor.double().numpy()[22]
    regressor[40:55] = body.J_regressor.double().numpy()[23]
    return {
        "v_template": body.v_template.double().numpy(), "shapedirs": body.shapedirs.double().numpy(),
        "posedirs": np.zeros((body.num_vertices, 3, 54 * 9)), "J_regressor": regressor, "weights": weights,
        "kintree_table": np.stack([parents, np.arange(55)]), "f": body.faces,
        # Official SMPL-X .npz files also hold pickled dicts; they must be skipped, not unpickled.
        "joint2num": np.array({"pelvis": 0}, dtype=object), "part2num": np.array({"body": 0}, dtype=object),
    }


def test_smplx_layout_npz_and_derived_segmentation(body, tmp_path):
    save_npz(tmp_path / "SMPLX_NEUTRAL.npz", **_smplx_like(body))
    smplx = load_body(tmp_path / "SMPLX_NEUTRAL.npz")
    assert smplx.kind == "smplx" and smplx.joint_names == SMPLX_JOINT_NAMES
    labels = body_segmentation(smplx)  # no labels in the file: derived from its joints
    assert (labels == body_segmentation(body)).mean() > 0.98


def test_segmentation_has_every_part_and_clean_arm_cuts(body):
    labels = body_segmentation(body)
    counts = np.bincount(labels, minlength=len(PART_NAMES))
    assert (counts > 20).all(), dict(zip(PART_NAMES, counts))
    vertices, joints = body.shaped()
    vertices, joints = vertices[0].numpy(), joints[0].numpy()
    names = body.joint_names
    for side, sign in (("left", 1), ("right", -1)):
        shoulder_x = joints[names.index(f"{side}_shoulder"), 0]
        upper = vertices[labels == PART_NAMES.index(f"{side}_upper_arm")]
        assert (sign * upper[:, 0] >= sign * shoulder_x - 1e-6).all()
    head = vertices[labels == PART_NAMES.index("head")]
    torso = vertices[labels == PART_NAMES.index("upper_torso")]
    assert head[:, 1].min() > torso[:, 1].max() - 0.02
    # The derived rules reproduce the labels shipped with the body. The labels were baked on another
    # CPU: a vertex within float rounding of a cut plane may fall on the other side here, so a
    # handful (at most 0.05 % of the vertices) may differ.
    differ = (segment_body(vertices, joints, names) != labels).sum()
    assert differ <= 0.0005 * len(labels), differ


@pytest.mark.parametrize("problem, edit, message", [
    ("missing key", lambda a: a.pop("weights"), "missing key"),
    ("wrong shape", lambda a: a.update(shapedirs=a["shapedirs"][:10]), "shapedirs"),
    ("NaN", lambda a: a["v_template"].__setitem__((0, 0), np.nan), "NaN"),
    ("bad faces", lambda a: a.update(f=a["f"] + 10**6), "'f'"),
])
def test_corrupt_body_files_give_clear_errors(body, tmp_path, run_darts, problem, edit, message):
    arrays = _official_arrays(body)
    edit(arrays)
    path = tmp_path / "broken.npz"
    save_npz(path, **arrays)
    with pytest.raises(DartsInputError, match=message):
        load_body(path)
    code, out, err = run_darts("body", "export", "--body", path, "-o", tmp_path / "out.npz")
    assert code == 2 and err.count("\n") == 1 and str(path) in err and message in err
    assert not (tmp_path / "out.npz").exists()


def test_text_file_named_npz_is_rejected(tmp_path, run_darts):
    path = tmp_path / "body.npz"
    path.write_text("not a model\n")
    code, _, err = run_darts("body", "info", "--body", path)
    assert code == 2 and "not a valid .npz archive" in err and str(path) in err


def test_body_from_arrays_rejects_unordered_tree(body):
    arrays = _official_arrays(body)
    arrays["kintree_table"] = arrays["kintree_table"].copy()
    arrays["kintree_table"][0, 1] = 5
    with pytest.raises(DartsInputError, match="parent before"):
        body_from_arrays(arrays, "x.npz")
