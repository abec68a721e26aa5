"""The posed body's overlapping parts pressed apart (``sim.body_separation``, issue 46), checked by
an independent inside test: the generalised winding number, summed in numpy over every face."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from darts.body.segmentation import PART_INDEX
from darts.geometry.mesh import vertex_normals
from darts.motion.amass import load_motion
from scenes import MOTIONS_DIR
from sim.body_separation import ARM_GAP_FACTOR, ITERATIONS, MOVABLE_PARTS, STEP, BodySeparation, separate_parts
from sim.body_track import build_body_track
from sim.engine.settings import SimSettings

SQUAT_BOTTOM = 63  # the squat's track frame where the thighs sink deepest into the belly and calves


def winding_numbers(vertices: np.ndarray, faces: np.ndarray, points: np.ndarray) -> np.ndarray:
    """[P] generalised winding numbers of a closed triangle mesh at ``points`` (van Oosterom and
    Strackee's solid angle of each triangle, summed, over 4 pi)."""
    total = np.zeros(len(points))
    for start in range(0, len(points), 256):
        p = points[start:start + 256, None, None, :]
        a, b, c = (vertices[faces[:, k]][None, :, :] - p[:, :, 0] for k in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
        det = np.einsum("pfi,pfi->pf", a, np.cross(b, c))
        div = la * lb * lc + np.einsum("pfi,pfi->pf", a, b) * lc + np.einsum("pfi,pfi->pf", b, c) * la \
            + np.einsum("pfi,pfi->pf", c, a) * lb
        total[start:start + 256] = (2.0 * np.arctan2(det, div)).sum(1) / (4.0 * np.pi)
    return total


def inside_another_part(vertices: np.ndarray, faces: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """The ``candidates`` (vertex indices) whose point 1 mm outside their own surface is inside the
    body: they lie inside another part."""
    probes = vertices[candidates] + 0.001 * vertex_normals(vertices, faces)[candidates]
    return candidates[winding_numbers(vertices, faces, probes) > 0.5]


def two_spheres(overlap: float, first: str = "left_thigh", second: str = "left_calf"):
    """Two unit-ish spheres (radius 0.1 m) whose surfaces overlap by ``overlap`` m, as one mesh; the
    first labelled ``first``, the second ``second`` (by default a thigh and a calf: parts that may move)."""
    a = trimesh.creation.icosphere(subdivisions=3, radius=0.1)
    b = trimesh.creation.icosphere(subdivisions=3, radius=0.1)
    b.apply_translation([0.2 - overlap, 0.0, 0.0])
    vertices = np.vstack([a.vertices, b.vertices])
    faces = np.vstack([a.faces, b.faces + len(a.vertices)])
    parts = np.r_[np.full(len(a.vertices), PART_INDEX[first]), np.full(len(b.vertices), PART_INDEX[second])]
    return vertices, faces, parts, len(a.vertices)


def test_two_overlapping_spheres_are_pressed_a_gap_apart():
    vertices, faces, parts, first = two_spheres(overlap=0.02)
    gap = 0.01
    assert len(inside_another_part(vertices, faces, np.arange(len(vertices)))) > 20
    separated = BodySeparation(faces, parts, gap)(vertices)
    assert len(inside_another_part(separated, faces, np.arange(len(vertices)))) == 0
    # the closest vertices of the two are about the gap apart, pressed from both sides alike
    a, b = separated[:first], separated[first:]
    closest = np.linalg.norm(a[:, None] - b[None], axis=2).min()
    assert 0.5 * gap <= closest <= 1.5 * gap
    depth_a = 0.1 - a[:, 0].max()
    depth_b = b[:, 0].min() - (0.1 - 0.02)
    assert abs(depth_a - depth_b) < 0.002
    # only the pressed sides move, by no more than the rounds allow
    moved = np.linalg.norm(separated - vertices, axis=1)
    assert moved.max() <= ITERATIONS * STEP + 1e-9
    assert (moved[:first][vertices[:first, 0] < 0.0] == 0).all()


def test_an_upper_arm_and_the_torso_are_pressed_further_apart():
    """Room for a top's two layers between the arm and the chest: ARM_GAP_FACTOR gaps, where a thigh
    and a calf (above) meet one gap apart; a forearm against the torso keeps one gap."""
    gap = 0.01
    for first, second, expected in [("upper_torso", "right_upper_arm", ARM_GAP_FACTOR * gap),
                                    ("left_upper_arm", "lower_torso", ARM_GAP_FACTOR * gap),
                                    ("upper_torso", "left_forearm", gap)]:
        vertices, faces, parts, count = two_spheres(0.0, first, second)  # touching
        separated = BodySeparation(faces, parts, gap)(vertices)
        closest = np.linalg.norm(separated[:count, None] - separated[None, count:], axis=2).min()
        assert 0.75 * expected <= closest <= 1.25 * expected, (first, second, closest)


def test_parts_apart_by_more_than_the_gap_and_a_zero_gap_are_left_alone():
    vertices, faces, parts, _ = two_spheres(overlap=-0.05)  # 5 cm apart
    assert np.array_equal(BodySeparation(faces, parts, 0.01)(vertices), vertices)
    vertices, faces, parts, _ = two_spheres(overlap=0.02)
    track = vertices[None]
    assert separate_parts(track, faces, parts, 0.0) is track


def test_only_the_parts_a_garment_covers_move():
    vertices, faces, parts, first = two_spheres(overlap=0.02)
    parts[first:] = PART_INDEX["left_foot"]  # the second sphere is a foot: it keeps its shape
    assert "left_foot" not in MOVABLE_PARTS
    separated = BodySeparation(faces, parts, 0.01)(vertices)
    assert np.array_equal(separated[first:], vertices[first:])
    assert len(inside_another_part(separated, faces, np.arange(first))) == 0
    # a part that may move, next to one that may not (a forearm at the wrist): the moves averaged
    # over the rings stop at the border
    vertices, faces, parts, first = two_spheres(overlap=0.02)
    hand = np.flatnonzero(vertices[:, 0] > 0.095)
    hand = hand[hand >= first]  # the second sphere's side just past where the first presses it (x < 0.1)
    parts[hand] = PART_INDEX["left_hand"]
    separated = BodySeparation(faces, parts, 0.01)(vertices)
    moved = np.linalg.norm(separated - vertices, axis=1)
    assert (moved[hand] == 0).all() and moved[first:].max() > 0.005


@pytest.fixture(scope="module")
def squat_tracks(body):
    motion = load_motion(MOTIONS_DIR / "squat.npz")
    posed = build_body_track(body, motion, 30.0, 0.5, gap=0.0)
    separated = build_body_track(body, motion, 30.0, 0.5, gap=SimSettings().body_gap)
    return posed, separated


def test_the_squatting_body_no_longer_overlaps_itself(body, squat_tracks):
    """At the bottom of the squat the skinned body has 163 vertices of the thighs, hips, calves and
    upper arms inside another part; separated 30 (in the skin's folds, where a move would turn a face
    over and is held back), no face turned over, the rest of the body where it was."""
    posed, separated = squat_tracks
    faces = np.asarray(body.faces)
    movable = np.flatnonzero(np.isin(posed.parts, [PART_INDEX[name] for name in MOVABLE_PARTS]))
    before = inside_another_part(posed.vertices[SQUAT_BOTTOM], faces, movable)
    after = inside_another_part(separated.vertices[SQUAT_BOTTOM], faces, movable)
    assert len(before) >= 100 and len(after) <= 0.2 * len(before)
    moved = np.linalg.norm(separated.vertices - posed.vertices, axis=2)
    assert moved.max() <= ITERATIONS * STEP + 1e-6
    assert (moved[0] == 0).all()  # the rest pose: nothing overlaps, nothing moves
    assert (moved[:, ~np.isin(posed.parts, [PART_INDEX[name] for name in MOVABLE_PARTS])] == 0).all()
    # no face turned over: every face keeps its orientation against the skinned one
    def face_normals(v):
        return np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])
    turned = (face_normals(separated.vertices[SQUAT_BOTTOM]) * face_normals(posed.vertices[SQUAT_BOTTOM])).sum(1) <= 0
    assert turned.sum() == 0


def test_the_separated_body_moves_as_smoothly_as_the_skinned_one(squat_tracks):
    """The moves follow the pose: the body's largest vertex acceleration between frames stays of the
    skinned body's order (13.7 m/s^2 skinned, 29.4 separated)."""
    posed, separated = squat_tracks

    def acceleration(v):
        return np.linalg.norm(np.diff(v, 2, axis=0), axis=2).max() * posed.fps ** 2

    assert acceleration(separated.vertices) <= 2.5 * acceleration(posed.vertices)


def test_a_body_track_built_without_a_gap_named_is_the_one_darts_sim_simulates_against(body, squat_tracks):
    """``build_body_track``'s default gap is ``SimSettings``' own: a track made by a caller that names
    no gap (the posed dataset did, and got the skinned body) is pressed apart like darts-sim's."""
    posed, separated = squat_tracks
    default = build_body_track(body, load_motion(MOTIONS_DIR / "squat.npz"), 30.0, 0.5)
    assert np.array_equal(default.vertices, separated.vertices)
    assert np.abs(default.vertices - posed.vertices).max() > 0.005


def test_the_posed_dataset_poses_its_garments_on_the_body_darts_sim_uses(monkeypatch):
    """The posed dataset's garments are simulated on the body pressed apart by its own settings'
    gap (``SimSettings.body_gap``), not on the skinned body."""
    import sim.body_track
    from sim.dataset.cli import garment_jobs
    from sim.dataset.posed import make_posed_garment

    class Built(Exception):
        pass

    gaps = []

    def recording(*args, gap=None, **kwargs):
        gaps.append(gap)
        raise Built

    monkeypatch.setattr(sim.body_track, "build_body_track", recording)
    job = garment_jobs(1, 1, 0, ["short-pants"])[0]
    with pytest.raises(Built):
        make_posed_garment(job, None)
    assert gaps == [SimSettings().body_gap] and gaps[0] > 0
