"""The body track the solver collides with: settle blend, frames, interpolation, rest placement."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from darts.dart.io import load_dart
from darts.geometry.distance import SurfaceDistance
from darts.motion.amass import load_motion
from darts.motion.posing import pose_sequence
from darts.motion.resampling import resample
from scenes import MOTIONS_DIR
from sim.body_track import build_body_track

GARMENTS = Path(__file__).parents[1] / "scenes" / "garments"


@pytest.fixture(scope="module")
def run_track(body):
    motion = load_motion(MOTIONS_DIR / "run.npz")
    return motion, build_body_track(body, motion, fps=30.0, settle=0.5, gap=0.0)  # the body as skinned


def test_track_starts_at_rest_and_reaches_the_first_frame(body, run_track):
    motion, track = run_track
    assert track.settle_frames == 15 and abs(track.duration - (0.5 + motion.duration)) < 1.5 / 30
    rest = body.shaped()[0][0].double().numpy()
    assert np.abs(track.vertices[0] - track.place_rest(rest)).max() < 1e-4
    recorded, _ = pose_sequence(body, resample(motion, 30.0))
    assert np.abs(track.vertices[track.settle_frames:] - recorded).max() < 1e-5
    # The blend is gradual: no frame-to-frame jump larger than in the recorded motion itself.
    steps = np.abs(np.diff(track.vertices, axis=0)).max(axis=(1, 2))
    assert steps[: track.settle_frames].max() < 0.05


def test_positions_interpolate_between_frames(run_track):
    _, track = run_track
    t = 20.25 / track.fps
    expected = 0.75 * track.vertices[20] + 0.25 * track.vertices[21]
    assert np.allclose(track.positions(t), expected)
    assert np.array_equal(track.positions(-1.0), track.vertices[0])
    assert np.array_equal(track.positions(1e6), track.vertices[-1])


def test_rest_garment_is_placed_outside_the_body(body, run_track):
    _, track = run_track
    dart = load_dart(GARMENTS / "short-sleeve-top.npz")
    placed = track.place_rest(dart.vertices)
    signed, _, _ = SurfaceDistance(track.vertices[0], body.faces).query(placed)
    assert signed.min() >= 0.0 and placed[:, 2].min() > 0.5  # Z up: the shirt hangs above the hips


def test_negative_settle_is_refused(body):
    with pytest.raises(ValueError, match="settle"):
        build_body_track(body, load_motion(MOTIONS_DIR / "walk.npz"), 30.0, -1.0)
