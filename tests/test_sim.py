"""The cloth solver: free fall, the dihedral gradient, the five seam regimes, stability, determinism."""
from __future__ import annotations

import re

import numpy as np
import pytest

from darts.dart.io import load_dart
from darts.geometry.warp_runtime import warp
from darts.motion.amass import load_motion
from darts.shipped import shipped_motions
from scenes import GARMENTS_DIR, MOTIONS_DIR
from sim.body_track import build_body_track
from sim.engine import kernels
from sim.engine.model import cloth_model, dihedral_angles
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
from sim.run import simulate

wp = warp()
MM = 1e-3


def _walk(frames: int):
    motion = load_motion(MOTIONS_DIR / "walk.npz")
    return motion.with_frames(trans=motion.trans[:frames], **{k: v[:frames] for k, v in motion.parts().items()})


@pytest.fixture(scope="module")
def walk_track(body):
    """The first 20 frames of the walk (0.63 s) after 0.5 s of settling."""
    return build_body_track(body, _walk(20), 30.0, 0.5)


def _skirt_run(track, settings=None, **seams):
    dart = load_dart(GARMENTS_DIR / "short-skirt.npz")
    for name, setting in seams.items():
        regime, _, stiffness = setting.partition(":")
        dart.set_seam(name, regime, float(stiffness) if stiffness else None)
    result = simulate(dart, track, settings or SimSettings())
    assert result.stable, result.message
    return result


def _gaps(result, seam, key="max"):
    return np.array([frame["seam_gap"][seam][key] for frame in result.frames])


@pytest.fixture(scope="module")
def welded_stiff_loose(walk_track):
    return _skirt_run(walk_track, waistband="welded", left_side="stiff", right_side="loose:20")


@pytest.mark.parametrize("solver", ["xpbd", "mass-spring"])
def test_free_fall_accelerates_at_g(body, solver):
    """Far from the body, with no air: after n substeps of dt, v = g n dt and
    z drop = g dt^2 n (n + 1) / 2 (symplectic Euler), i.e. g t^2 / 2 within 1 %."""
    dart = load_dart(GARMENTS_DIR / "short-skirt.npz")
    model = cloth_model(dart)
    settings = SimSettings(solver=solver, air_density=0.0, damping=0.0, ground=False)
    far_body = np.asarray(body.v_template, np.float64) + [0.0, 0.0, 100.0]
    solver_ = Simulation(model, model.rest, body.faces, far_body, settings)
    frames = 15
    for _ in range(frames):
        solver_.step_frame(far_body)
    t = frames / settings.fps
    drop = (model.rest - solver_.positions())[:, 2]
    speed = -solver_.v.numpy()[:, 2]
    assert abs(speed.mean() / (9.81 * t) - 1) < 1e-3
    assert abs(drop.mean() / (0.5 * 9.81 * t * t) - 1) < 0.01
    # A garment falling freely keeps its shape: edges within 0.1 % of rest.
    x = solver_.positions()
    strain = np.linalg.norm(x[model.edges[:, 0]] - x[model.edges[:, 1]], axis=1) / model.edge_rest - 1
    assert np.abs(strain).max() < 1e-3


@wp.kernel
def _hinge_gradient(points: wp.array(dtype=wp.vec3), angle: wp.array(dtype=float), grad: wp.array(dtype=wp.vec3)):
    a, gi, gj, gk, gl, ok = kernels.dihedral_gradient(points[0], points[1], points[2], points[3], 1.0, 0.0)
    angle[0] = a
    grad[0] = gi
    grad[1] = gj
    grad[2] = gk
    grad[3] = gl


def test_dihedral_gradient_matches_finite_differences():
    rng = np.random.default_rng(3)
    for _ in range(5):
        points = np.array([[0, 0, 0], [1, 0, 0], [0.3, 0.8, 0.1], [0.6, -0.7, 0.3]]) + rng.normal(0, 0.1, (4, 3))
        angle, grad = wp.zeros(1, dtype=float), wp.zeros(4, dtype=wp.vec3)
        wp.launch(_hinge_gradient, 1, [wp.array(points.astype(np.float32), dtype=wp.vec3), angle, grad])
        hinge = np.array([[0, 1, 2, 3]])
        assert abs(angle.numpy()[0] - dihedral_angles(points, hinge)[0]) < 1e-5
        numeric = np.zeros((4, 3))
        for p in range(4):
            for c in range(3):
                step = np.zeros((4, 3))
                step[p, c] = 1e-6
                numeric[p, c] = (dihedral_angles(points + step, hinge)[0] - dihedral_angles(points - step, hinge)[0]) / 2e-6
        assert np.abs(grad.numpy() - numeric).max() < 1e-3 * max(1.0, np.abs(numeric).max())


@wp.kernel
def _hinge_errors(points: wp.array2d(dtype=wp.vec3), rest: wp.array(dtype=float), error: wp.array(dtype=float)):
    h = wp.tid()
    c, gi, gj, gk, gl, ok = kernels.dihedral_gradient(points[h, 0], points[h, 1], points[h, 2], points[h, 3],
                                                      wp.cos(rest[h]), wp.sin(rest[h]))
    error[h] = c


def test_dihedral_error_is_the_wrapped_angle_less_the_rest_angle():
    """Near the rest angle (the polynomial) and far from it (atan2), across the wrap at +-pi."""
    rng = np.random.default_rng(5)
    count = 20000
    points = np.array([[0, 0, 0], [1, 0, 0], [0.3, 0.8, 0.1], [0.6, -0.7, 0.3]]) + rng.normal(0, 0.4, (count, 4, 3))
    angle = dihedral_angles(points.reshape(-1, 3), np.arange(4 * count).reshape(count, 4))
    rest = np.where(rng.random(count) < 0.5, angle + rng.normal(0, 0.3, count), rng.uniform(-np.pi, np.pi, count))
    error = wp.zeros(count, dtype=float)
    wp.launch(_hinge_errors, count, [wp.array(points.astype(np.float32), dtype=wp.vec3),
                                     wp.array(rest.astype(np.float32)), error])
    expected = np.angle(np.exp(1j * (angle - rest)))  # wrapped into [-pi, pi]
    difference = np.angle(np.exp(1j * (error.numpy() - expected)))
    near = np.abs(expected) < np.pi / 4
    assert 0.3 * count < near.sum() < 0.9 * count
    assert np.abs(difference).max() < 2e-5


def test_welded_is_exactly_closed_stiff_within_a_millimetre_loose_wider(welded_stiff_loose):
    result = welded_stiff_loose
    assert np.all(_gaps(result, "waistband") == 0.0)
    stiff, loose = _gaps(result, "left_side"), _gaps(result, "right_side")
    assert stiff.max() <= 1 * MM
    assert _gaps(result, "right_side", "mean").mean() > 2 * _gaps(result, "left_side", "mean").mean()
    assert loose.max() > stiff.max()
    assert max(frame["penetration"] for frame in result.frames) <= 0.01


def test_loose_gap_grows_as_stiffness_falls(walk_track, welded_stiff_loose):
    softer = _skirt_run(walk_track, left_side="loose:5", right_side="loose:1")
    mean_gap = {
        2000: _gaps(welded_stiff_loose, "left_side", "mean").mean(),
        20: _gaps(welded_stiff_loose, "right_side", "mean").mean(),
        5: _gaps(softer, "left_side", "mean").mean(),
        1: _gaps(softer, "right_side", "mean").mean(),
    }
    values = [mean_gap[k] for k in (2000, 20, 5, 1)]
    assert all(a < b for a, b in zip(values, values[1:])), mean_gap


@pytest.mark.slow
def test_the_tops_stiff_seams_hold_where_it_touches_the_body_and_loose_ones_open_as_they_soften(walk_track):
    """Issue 46: the top's shoulders and armholes lie on the body, whose friction held each end of
    a seam pair by its own push and opened stiff seams by 3.5 mm; the seams projected once more after
    friction keep them within 2 mm, and loose seams open further at each lower stiffness."""
    widest = {}
    for setting in ("stiff", "loose:20", "loose:5", "loose:2"):
        dart = load_dart(GARMENTS_DIR / "short-sleeve-top.npz")
        regime, _, stiffness = setting.partition(":")
        dart.set_seam("all", regime, float(stiffness) if stiffness else None)
        result = simulate(dart, walk_track, SimSettings())
        assert result.stable, result.message
        widest[setting] = max(max(g["max"] for g in frame["seam_gap"].values()) for frame in result.frames)
    values = list(widest.values())
    assert widest["stiff"] <= 2 * MM and all(a < b for a, b in zip(values, values[1:])), widest
    assert widest["loose:2"] >= 4 * widest["stiff"] and widest["loose:2"] >= 5 * MM, widest


@pytest.mark.slow
def test_the_tops_sleeves_folded_at_the_armpits_do_not_cross_themselves(body):
    """Issue 46: walking, the arm presses the sleeve's bunched underside against the torso. With the
    body's contacts last in every sweep and creases pushed a centimetre a sweep, each fold was pushed
    off its own nearest body part through the fold beside it: 123-127 crossing edges over the first
    30 walk frames (runs started 1 um apart); with the garment's own contacts last, creases held to
    3 mm a sweep and the facing gap shared, 38-50; with the cuts untangled too, 24 (38 on the same
    track without)."""
    track = build_body_track(body, _walk(60), 30.0, 0.5)  # the walk's first second: 30 frames at 30 fps
    result = simulate(load_dart(GARMENTS_DIR / "short-sleeve-top.npz"), track, SimSettings())
    assert result.stable and len(result.frames) == 30, result.message
    assert max(frame["self_intersections"] for frame in result.frames) <= 32


def test_repulsive_opens_towards_its_rest_length_and_partial_opens_only_unsprung(body):
    track = build_body_track(body, _walk(20), 30.0, 0.0)  # no settle: watch the gap open from 0
    result = _skirt_run(track, left_side="repulsive", right_side="partial")
    repulsive = _gaps(result, "left_side", "mean")
    rest = 0.02
    # Closed at rest; a 200 N/m spring on ~16 mg particles opens within the first frame (33 ms).
    assert repulsive[0] == 0.0
    assert np.all((0.8 * rest < repulsive[1:]) & (repulsive[1:] < 1.1 * rest))
    assert _gaps(result, "right_side", "sprung_max").max() <= 1 * MM
    assert _gaps(result, "right_side", "open_mean")[-1] >= 10 * MM


def test_mass_spring_keeps_stiff_seams_closed(walk_track):
    result = _skirt_run(walk_track, SimSettings(solver="mass-spring"), waistband="welded")
    assert np.all(_gaps(result, "waistband") == 0.0)
    assert _gaps(result, "left_side").max() <= 1 * MM and _gaps(result, "right_side").max() <= 1 * MM


@pytest.mark.slow
def test_runs_are_deterministic_for_a_seed(body):
    track = build_body_track(body, _walk(4), 30.0, 0.1)
    dart = load_dart(GARMENTS_DIR / "short-skirt.npz")
    def run(seed):
        out = []
        simulate(dart, track, SimSettings(wind=(2.0, 0.0, 0.0), gust=0.8, seed=seed), lambda g, b: out.append(g))
        return np.array(out)

    first, again, other = run(1), run(1), run(2)
    assert np.array_equal(first, again)
    assert np.abs(first - other).max() > 1e-5  # gusts differ with the seed


def test_a_blow_up_stops_the_run_and_keeps_the_frames_before(body):
    """A speed limit the draping skirt passes after a few frames stands in for a blow-up."""
    dart = load_dart(GARMENTS_DIR / "short-skirt.npz")
    kept = []
    track = build_body_track(body, _walk(20), 30.0, 0.0)
    result = simulate(dart, track, SimSettings(max_speed=1.0), lambda g, b: kept.append(g))
    assert not result.stable and "m/s" in result.message
    assert re.search(r"particle \d+ at [\d.]+ m/s, worst constraint on it: (edge|seam|body|self)", result.message)
    assert 0 < len(kept) == len(result.frames) < 20
    assert all(frame["max_speed"] <= 1.0 for frame in result.frames) and np.isfinite(kept).all()


def test_non_finite_state_is_reported(body):
    dart = load_dart(GARMENTS_DIR / "short-skirt.npz")
    model = cloth_model(dart)
    solver = Simulation(model, model.rest, body.faces, np.asarray(body.v_template, np.float64), SimSettings())
    x = solver.x.numpy()
    x[7] = np.nan
    solver.x.assign(x)
    assert solver.measure().finite is False
    assert solver.diagnose().startswith("particle 7 non-finite, worst constraint on it: edge 7-")


_SKIRT_RUNS: dict = {}


def _short_skirt_on(body, motion: str):
    """The short skirt through a whole shipped motion at the defaults (each motion run once; the squat
    measured by the body's winding number too)."""
    if motion not in _SKIRT_RUNS:
        track = build_body_track(body, load_motion(MOTIONS_DIR / f"{motion}.npz"), 30.0, 0.5, gap=SimSettings().body_gap)
        _SKIRT_RUNS[motion] = (simulate(load_dart(GARMENTS_DIR / "short-skirt.npz"), track, SimSettings(),
                                        winding=motion == "squat"),
                               len(track.vertices) - track.settle_frames)
    return _SKIRT_RUNS[motion]


@pytest.mark.slow
@pytest.mark.parametrize("motion", shipped_motions())
def test_every_shipped_motion_simulates_with_the_skirt_out_of_the_body(body, motion):
    """Stable, every frame, and the skirt out of the body by the closest point (1 %) on every shipped
    motion, the squat included (0.08 % measured; 4.9 % before the body's overlapping parts were
    pressed apart, ``sim.body_separation``, almost all of it cloth lying where the squatting body
    overlapped itself)."""
    result, frames = _short_skirt_on(body, motion)
    assert result.stable, result.message
    assert len(result.frames) == frames
    assert max(frame["penetration"] for frame in result.frames) <= 0.01


@pytest.mark.slow
def test_the_squat_stretches_the_skirt_far_less_than_before_the_overlap_release(body):
    """Strain p99 at the bottom of the squat: 173 % before the overlap release, 26 % with it and the
    refresh, 21 % with the body's parts pressed apart (issue 46's target is 15 % for trousers)."""
    result, _ = _short_skirt_on(body, "squat")
    assert max(frame["strain"]["p99"] for frame in result.frames) <= 0.5


@pytest.mark.slow
def test_the_squat_keeps_the_skirt_out_of_the_body_by_the_winding_number(body):
    """Inside the body by its winding number, the part in the body's own overlap included: at most 2 %
    (issue 46; 0.08 % measured, 10.3 % before the body's parts were pressed apart)."""
    result, _ = _short_skirt_on(body, "squat")
    assert max(frame["penetration_winding"] for frame in result.frames) <= 0.02
