"""AMASS-format motions: formats, validation, resampling, the shipped procedural motions."""
from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from darts.errors import DartsInputError
from darts.fileio import save_npz
from darts.motion.amass import load_motion
from darts.motion.posing import pose_sequence
from darts.motion.resampling import resample, slerp_rotvecs
from darts.shipped import shipped_motions
from scenes import MOTIONS_DIR
from tests.helpers import random_motion_arrays, write_classic_amass_120fps

SHIPPED = ["walk", "run", "wave", "jumping_jacks", "twist", "squat", "sit", "kneel", "arms_down", "arms_crossed"]


def _posed(body, path):
    return pose_sequence(body, load_motion(path))


def test_all_three_amass_layouts_pose_the_same_body(body, tmp_path):
    smplh = random_motion_arrays(5, seed=1)
    smplh["gender"] = np.array(b"female")  # bytes, as in some AMASS releases
    save_npz(tmp_path / "smplh.npz", **smplh)
    poses = smplh["poses"]
    smpl = {k: v for k, v in smplh.items() if k != "poses"}
    save_npz(tmp_path / "smpl.npz", poses=np.concatenate([poses[:, :66], np.zeros((5, 6))], 1), **smpl)
    n_release = {
        "root_orient": poses[:, :3], "pose_body": poses[:, 3:66], "pose_hand": poses[:, 66:],
        "pose_jaw": np.zeros((5, 3)), "pose_eye": np.zeros((5, 6)), "trans": smplh["trans"],
        "betas": np.zeros(16), "gender": np.array("male"), "mocap_frame_rate": np.array(30.0),
        "surface_model_type": np.array("smplx"),
    }
    save_npz(tmp_path / "smplx_n.npz", **n_release)
    formats = {p: load_motion(tmp_path / f"{p}.npz").source_format for p in ("smplh", "smpl", "smplx_n")}
    assert formats == {"smplh": "amass-smplh", "smpl": "amass-smpl", "smplx_n": "amass-smplx-n"}
    assert load_motion(tmp_path / "smplh.npz").gender == "female"
    reference, _ = _posed(body, tmp_path / "smplh.npz")
    for name in ("smpl", "smplx_n"):
        vertices, _ = _posed(body, tmp_path / f"{name}.npz")
        assert np.abs(vertices - reference).max() < 1e-5


def test_amass_semantics_translation_is_added_after_lbs(body, tmp_path):
    arrays = random_motion_arrays(3, seed=2)
    save_npz(tmp_path / "a.npz", **arrays)
    moved = dict(arrays, trans=arrays["trans"] + [1.0, -2.0, 0.5])
    save_npz(tmp_path / "b.npz", **moved)
    a, _ = _posed(body, tmp_path / "a.npz")
    b, _ = _posed(body, tmp_path / "b.npz")
    assert np.abs((b - a) - np.array([1.0, -2.0, 0.5], np.float32)).max() < 1e-5


def test_slerp_halfway_and_resample_keeps_duration(tmp_path):
    a = np.zeros((1, 3))
    b = np.array([[0, 0, np.pi / 2]])
    half = slerp_rotvecs(a, b, np.array([0.5]))
    assert np.allclose(half, [[0, 0, np.pi / 4]])
    frames = 241  # 2 s at 120 fps
    t = np.arange(frames) / 120.0
    arrays = {"poses": np.zeros((frames, 156)), "trans": np.c_[t, 0 * t, 0 * t],
              "mocap_framerate": np.array(120.00004577), "betas": np.zeros(16), "gender": np.array("neutral")}
    arrays["poses"][:, 2] = t  # root yaw grows at 1 rad/s
    save_npz(tmp_path / "m.npz", **arrays)
    motion = resample(load_motion(tmp_path / "m.npz"), 30.0)
    assert motion.num_frames == 61 and abs(motion.duration - 2.0) < 1e-3
    new_t = np.arange(61) / 30.0
    assert np.allclose(motion.trans[:, 0], new_t, atol=1e-5)
    angles = Rotation.from_rotvec(motion.body_pose[:, 0]).magnitude()
    assert np.allclose(angles, new_t, atol=1e-5)


def _motion_of(body_pose: np.ndarray, fps: float, trans: np.ndarray | None = None):
    from darts.motion.amass import Motion

    return Motion(body_pose=body_pose, trans=np.zeros((len(body_pose), 3)) if trans is None else trans, fps=fps)


def test_a_falling_rate_filters_motion_capture_jitter_and_keeps_smooth_motion():
    """120 -> 30 fps: white jitter of 0.01 rad on every joint comes out at under half its size
    (picking every fourth frame would keep all of it), a 1 Hz swing of 0.5 rad within 0.5 % of it."""
    t = np.arange(481) / 120.0
    swing = np.zeros((len(t), 21, 3))
    swing[:, 3, 0] = 0.5 * np.sin(2 * np.pi * t)
    jitter = np.random.default_rng(0).normal(0.0, 0.01, swing.shape)
    clean, noisy = resample(_motion_of(swing, 120.0), 30.0), resample(_motion_of(swing + jitter, 120.0), 30.0)
    picked = (swing + jitter)[::4] - swing[::4]
    assert np.std(picked) > 0.0095
    assert np.std(noisy.body_pose - clean.body_pose) < 0.5 * 0.01
    expected = 0.5 * np.sin(2 * np.pi * np.arange(clean.num_frames) / 30.0)
    assert np.abs(clean.body_pose[:, 3, 0] - expected).max() < 0.005 * 0.5
    assert np.allclose(clean.body_pose[0], swing[0]) and np.allclose(clean.body_pose[-1], swing[-1], atol=1e-9)


def test_a_rising_rate_interpolates_without_filtering():
    """30 -> 120 fps: every source frame comes back exactly, the frames between by slerp."""
    rng = np.random.default_rng(1)
    pose = rng.normal(0.0, 0.3, (31, 21, 3))
    fine = resample(_motion_of(pose, 30.0, rng.normal(0.0, 0.1, (31, 3))), 120.0)
    assert fine.num_frames == 121
    assert np.allclose(Rotation.from_rotvec(fine.body_pose[::4].reshape(-1, 3)).as_matrix(),
                       Rotation.from_rotvec(pose.reshape(-1, 3)).as_matrix(), atol=1e-9)
    halfway = slerp_rotvecs(pose[:1], pose[1:2], np.full((1, 21), 0.5))
    assert np.allclose(Rotation.from_rotvec(fine.body_pose[2].reshape(-1, 3)).as_matrix(),
                       Rotation.from_rotvec(halfway.reshape(-1, 3)).as_matrix(), atol=1e-9)


def test_classic_smplh_file_at_120_fps_poses_and_resamples_without_nan(body, tmp_path, run_darts):
    """A classic AMASS file: 120.00004577 fps, dmpls, bytes gender, resampled to 30 fps."""
    write_classic_amass_120fps(MOTIONS_DIR / "run.npz", tmp_path / "amass_120.npz")
    code, out, err = run_darts("body", "pose", tmp_path / "amass_120.npz", "-o", tmp_path / "posed.npz", "--fps", 30)
    assert code == 0, err
    posed = np.load(tmp_path / "posed.npz")
    assert posed["vertices"].shape == (91, body.num_vertices, 3)
    assert np.isfinite(posed["vertices"]).all() and float(posed["fps"]) == 30.0


def test_shipped_motions_exist_in_classic_smplh_layout():
    assert set(SHIPPED) <= set(shipped_motions())
    for name in SHIPPED:
        motion = load_motion(MOTIONS_DIR / f"{name}.npz")
        assert motion.source_format == "amass-smplh"
        assert 2.0 <= motion.duration <= 5.0
        # Starts in the rest pose (only the root's Y-up -> Z-up rotation), so cloth can drape first.
        assert np.abs(motion.body_pose[0, 1:]).max() < 1e-9
        assert np.allclose(Rotation.from_rotvec(motion.body_pose[0, 0]).as_euler("xyz", degrees=True), [90, 0, 0], atol=1e-6)


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_motion_feet_stay_on_the_floor(body, name):
    motion = load_motion(MOTIONS_DIR / f"{name}.npz")
    vertices, joints = pose_sequence(body, motion)
    assert np.isfinite(vertices).all()
    lowest = vertices[..., 2].min(axis=1)
    assert lowest.min() > -0.03, "nothing sinks through the floor"
    window = int(0.5 * motion.fps)
    # Standing: the lowest point touches the floor; the airborne phases of running and jumping
    # jacks end in a landing within every half second.
    landings = [lowest[i:i + window].min() for i in range(0, len(lowest) - window + 1, window)]
    assert max(landings) < 0.03
    if name not in ("run", "jumping_jacks"):
        assert lowest.max() < 0.03


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_motion_joint_angles_are_plausible(name):
    motion = load_motion(MOTIONS_DIR / f"{name}.npz")
    angles = np.linalg.norm(motion.body_pose[:, 1:], axis=-1)
    assert angles.max() < np.radians(150)
    knees = motion.body_pose[:, [4, 5], 0]  # knee flexion is a positive rotation about X
    assert knees.min() > -0.05 and knees.max() < np.radians(145)


def test_the_deep_poses_reach_what_they_are_named_for(body):
    """Halfway through each (the hold): sitting, the thighs horizontal (hips within 8 cm of the
    knees' height) and the seat at a chair's height; kneeling, the knees on the floor and the thighs
    upright; arms down, the wrists at the hips' height under the shoulders; arms crossed, each wrist past the body's middle."""
    from darts.body.joints import BODY_JOINT_NAMES as J

    def middle(name):
        motion = load_motion(MOTIONS_DIR / f"{name}.npz")
        _, joints = pose_sequence(body, motion)
        return {n: joints[len(joints) // 2, J.index(n)] for n in J}

    sit = middle("sit")
    assert abs(sit["left_hip"][2] - sit["left_knee"][2]) < 0.08 and 0.35 < sit["left_hip"][2] < 0.6
    kneel = middle("kneel")
    assert kneel["left_knee"][2] < 0.12 and kneel["right_knee"][2] < 0.12
    assert kneel["left_hip"][2] - kneel["left_knee"][2] > 0.3
    down = middle("arms_down")
    for side in ("left", "right"):  # hanging: the wrist at the hips' height, under the shoulder
        assert down[f"{side}_wrist"][2] < down[f"{side}_hip"][2] + 0.1
        assert np.linalg.norm(down[f"{side}_wrist"][:2] - down[f"{side}_shoulder"][:2]) < 0.15
    crossed = middle("arms_crossed")
    side = crossed["left_shoulder"][:2] - crossed["right_shoulder"][:2]  # points to the body's left
    centre = 0.5 * (crossed["left_shoulder"][:2] + crossed["right_shoulder"][:2])
    assert (crossed["left_wrist"][:2] - centre) @ side < 0 < (crossed["right_wrist"][:2] - centre) @ side


def test_walk_stance_foot_does_not_slide(body):
    motion = load_motion(MOTIONS_DIR / "walk.npz")
    _, joints = pose_sequence(body, motion)
    ankles = joints[:, [7, 8]]
    stance = np.argmin(ankles[..., 2], axis=1)
    rows = np.arange(1, len(ankles))
    same = stance[1:] == stance[:-1]
    slide = np.linalg.norm(ankles[rows, stance[1:], :2] - ankles[rows - 1, stance[1:], :2], axis=-1)[same]
    assert slide.max() * motion.fps < 0.05  # metres per second
    assert np.linalg.norm(motion.trans[-1, :2] - motion.trans[0, :2]) > 2.0  # and it walks somewhere


@pytest.mark.parametrize("problem, arrays, message", [
    ("missing trans", lambda a: a.pop("trans"), "missing key 'trans'"),
    ("wrong width", lambda a: a.update(poses=a["poses"][:, :100]), "'poses' has shape"),
    ("NaN", lambda a: a["poses"].__setitem__((1, 4), np.nan), "NaN"),
    ("zero frames", lambda a: a.update(poses=a["poses"][:0], trans=a["trans"][:0]), "zero frames"),
    ("frame mismatch", lambda a: a.update(trans=a["trans"][:2]), "frames"),
    ("fps zero", lambda a: a.update(mocap_framerate=np.array(0.0)), "must be positive"),
    ("fps tiny", lambda a: a.update(mocap_framerate=np.array(1e-300)), "frames/s, not a motion's"),
    ("fps huge", lambda a: a.update(mocap_framerate=np.array(4.6e18)), "frames/s, not a motion's"),
    ("no fps", lambda a: a.pop("mocap_framerate"), "missing frame rate"),
])
def test_bad_motion_files_give_one_clear_line_and_no_output(tmp_path, run_darts, problem, arrays, message):
    data = random_motion_arrays(4)
    arrays(data)
    path = tmp_path / "bad.npz"
    save_npz(path, **data)
    with pytest.raises(DartsInputError, match=message):
        load_motion(path)
    code, out, err = run_darts("body", "pose", path, "-o", tmp_path / "out.npz")
    assert code == 2 and err.count("\n") == 1 and str(path) in err and message in err
    assert not (tmp_path / "out.npz").exists()
    assert not list(tmp_path.glob(".out.npz.*"))  # no half-written temporary either


def test_text_file_renamed_npz_and_missing_file(tmp_path, run_darts):
    path = tmp_path / "motion.npz"
    path.write_text("walk\n")
    code, _, err = run_darts("motion", "info", path)
    assert code == 2 and "not a valid .npz archive" in err
    code, _, err = run_darts("motion", "info", tmp_path / "nothing.npz")
    assert code == 2 and "neither a file nor a shipped motion" in err


def test_motion_info_and_ground(run_darts, tmp_path):
    code, out, _ = run_darts("motion", "info", "walk", "--json")
    info = json.loads(out)
    assert code == 0 and info["frames"] == 241 and info["fps"] == 60 and info["joints"]["body_pose"] == 22
    lifted = random_motion_arrays(3)
    lifted["trans"][:, 2] += 5.0
    save_npz(tmp_path / "high.npz", **lifted)
    code, _, err = run_darts("body", "pose", tmp_path / "high.npz", "-o", tmp_path / "p.npz", "--ground")
    assert code == 0, err
    assert abs(np.load(tmp_path / "p.npz")["vertices"][..., 2].min()) < 1e-5
