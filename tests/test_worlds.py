"""Many worlds: several garment-on-body jobs in one solver (``sim.worlds``, ``sim.simulate_many``) —
each world in its own cell, measured on its own, stopped on its own, and each job given back as a
single run gives it."""
from __future__ import annotations

import json

import numpy as np
import pytest

from darts.errors import DartsInputError
from sim.api import SimJob, run_job, simulate_many
from sim.body_track import BodyTrack
from sim.engine.model import cloth_model, join_models
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
from sim.engine.tethers import surface_tethers
from sim.worlds import WORLD_MARGIN, World, simulate_worlds, world_offsets
from tests.helpers import sheet_dart
from tests.test_outfit import SLAB


def _still_track(vertices: np.ndarray, faces: np.ndarray, frames: int) -> BodyTrack:
    """A body that stands still for ``frames`` frames at 30 fps (no settle), already in place."""
    return BodyTrack(np.repeat(np.asarray(vertices, np.float64)[None], frames, 0), faces, 30.0, 0, np.eye(3),
                     np.zeros(3), np.zeros(3))


def _sheet(height: float, side: float = 0.2, spacing: float = 0.02):
    n = int(round(side / spacing)) + 1
    y, x = np.meshgrid(np.arange(n) * spacing - side / 2, np.arange(n) * spacing - side / 2, indexing="ij")
    vertices = np.stack([x.ravel(), y.ravel(), np.full(x.size, height)], axis=1)
    faces = [[i * n + j, i * n + j + 1, (i + 1) * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
    faces += [[i * n + j, (i + 1) * n + j + 1, (i + 1) * n + j] for i in range(n - 1) for j in range(n - 1)]
    return sheet_dart(vertices, np.array(faces))


def test_each_world_gets_its_own_cell_wider_than_any_body_sweeps():
    rng = np.random.default_rng(0)
    tracks = []
    for _ in range(7):  # bodies of different sizes walking different distances from different places
        start = rng.uniform(-5, 5, 3)
        walk = np.linspace(0, rng.uniform(0, 3), 12)[:, None, None] * np.array([1.0, 0.3, 0.0])
        tracks.append(_still_track(start + rng.uniform(-0.4, 0.4, (50, 3)), np.zeros((0, 3), int), 12))
        tracks[-1].vertices = tracks[-1].vertices + walk
    offsets = world_offsets(tracks)
    assert np.all(offsets[:, 2] == 0)  # the ground stays where it is
    boxes = [(t.vertices[..., :2].min((0, 1)) + o[:2], t.vertices[..., :2].max((0, 1)) + o[:2])
             for t, o in zip(tracks, offsets)]
    for a in range(len(boxes)):
        for b in range(a + 1, len(boxes)):
            gap = np.maximum(boxes[b][0] - boxes[a][1], boxes[a][0] - boxes[b][1]).max()
            assert gap >= WORLD_MARGIN - 1e-9
    centres = np.array([(low + high) / 2 for low, high in boxes])
    assert np.abs(centres.min(0) + centres.max(0)).max() < 1e-9  # the grid is centred on the origin


def test_each_world_of_a_model_is_measured_on_its_own():
    """Two sheets as two worlds over two slabs: the one pushed into its slab is 100 % inside, the
    other 0 %; the model as a whole half."""
    sheets = [cloth_model(_sheet(0.01)), cloth_model(_sheet(0.01))]
    model = join_models(sheets, ["a", "b"], worlds=True)
    assert model.worlds == 2 and np.array_equal(np.bincount(model.world), [len(m.rest) for m in sheets])
    assert model.layer.max() == 0  # worlds keep their own layers: not an outfit
    vertices, faces = SLAB
    shift = np.array([5.0, 0.0, 0.0])
    positions = np.concatenate([sheets[0].rest, sheets[1].rest + shift])
    positions[len(sheets[0].rest):, 2] = -0.05  # world b's sheet inside its slab
    solver = Simulation(model, positions, np.concatenate([faces, faces + len(vertices)]),
                        np.concatenate([vertices, vertices + shift]), SimSettings(ground=False))
    a, b = solver.measure_worlds(winding=True)
    assert (a.penetration, b.penetration) == (0.0, 1.0)
    assert (a.penetration_winding, b.penetration_winding) == (0.0, 1.0)
    assert solver.measure().penetration == pytest.approx(0.5, abs=0.01)


def test_each_world_gets_the_tethers_it_would_get_alone():
    one, two = cloth_model(_sheet(0.0)), cloth_model(_sheet(0.0, side=0.3, spacing=0.015))
    joined = join_models([one, two], ["a", "b"], worlds=True)
    pairs, limits = surface_tethers(joined)
    alone = [surface_tethers(one), surface_tethers(two)]
    first = pairs[:, 0] < len(one.rest)
    assert np.array_equal(pairs[first], alone[0][0]) and np.array_equal(limits[first], alone[0][1])
    assert np.array_equal(pairs[~first] - len(one.rest), alone[1][0]) and np.array_equal(limits[~first], alone[1][1])


def _sheet_worlds(frames: int, sinks=None):
    vertices, faces = SLAB
    sinks = sinks or [None, None]
    return [World(_sheet(0.05), _still_track(vertices, faces, frames), sinks[0]),
            World(_sheet(0.08, side=0.16), _still_track(vertices, faces, frames), sinks[1])]


def test_a_world_that_blows_up_stops_alone_and_the_others_go_on(monkeypatch):
    """Two sheets dropped on slabs; world 1's particles made non-finite after frame 4: it stops with
    its message and its 4 good frames, and world 0 goes on exactly as it would have."""
    settings = SimSettings(ground=False)
    clean_frames = []
    clean = simulate_worlds(_sheet_worlds(10, [lambda g, b: clean_frames.append(g), None]), settings)
    step = Simulation.step_frame
    stepped = []

    def step_and_break(self, body_next):
        step(self, body_next)
        stepped.append(1)
        if len(stepped) == 4:
            x = self.state.positions()
            x[self.model.world == 1] = np.nan
            self.state.x.assign(x.astype(np.float32))

    monkeypatch.setattr(Simulation, "step_frame", step_and_break)
    kept = [[], []]
    results = simulate_worlds(_sheet_worlds(10, [lambda g, b: kept[0].append(g), lambda g, b: kept[1].append(g)]),
                              settings)
    assert results[0].stable and len(results[0].frames) == 10 and clean[0].stable
    assert not results[1].stable and results[1].message.startswith("unstable at frame 4: a non-finite position")
    assert "particle" in results[1].message and len(kept[1]) == len(results[1].frames) == 4
    assert np.isfinite(kept[0]).all()
    assert np.abs(np.array(kept[0]) - np.array(clean_frames)).max() < 1e-5
    assert [f["strain"]["max"] for f in results[0].frames] == pytest.approx([f["strain"]["max"] for f in clean[0].frames],
                                                                             abs=1e-4)


@pytest.fixture(scope="module")
def top_and_skirt(tmp_path_factory):
    """A top on the walk and a skirt on another body shape on the squat, as two worlds of one solver
    and alone; a third job with other substeps, which cannot share their solver."""
    out = tmp_path_factory.mktemp("worlds")
    jobs = [SimJob("short-sleeve-top", "walk", frames=4, settle=0.3, stats=str(out / "top.json"),
                   output=str(out / "top.usdc")),
            SimJob("short-skirt", "squat", frames=3, settle=0.3, betas=[1.0, -0.5]),
            SimJob("short-skirt", "walk", frames=3, settle=0.2, settings={"substeps": 6})]
    many = simulate_many(jobs)
    alone = [run_job(SimJob(**{**vars(job), "stats": None, "output": None})) for job in jobs[:2]]
    return out, jobs, many, alone


def test_simulate_many_gives_each_job_what_its_single_run_gives(top_and_skirt):
    out, jobs, many, alone = top_and_skirt
    for run, single in zip(many, alone):
        assert run.stable, run.message
        assert run.garment.shape == single.garment.shape and run.body.shape == single.body.shape
        assert np.abs(run.body - single.body).max() < 1e-5  # each body handed back in its own world frame
        assert set(run.stats) == set(single.stats) and run.garment_names == single.garment_names
        # the same drape (worlds far from the origin round differently, and cloth amplifies it)
        assert np.linalg.norm(run.garment - single.garment, axis=2).mean() < 2e-3
        assert run.stats["max_penetration"] <= single.stats["max_penetration"] + 0.002
        assert run.stats["strain_p99"] == pytest.approx(single.stats["strain_p99"], rel=0.2, abs=0.01)
    assert json.loads((out / "top.json").read_text())["simulated_frames"] == many[0].stats["simulated_frames"]
    assert (out / "top.usdc").stat().st_size > 0


def test_jobs_that_cannot_share_a_solver_run_in_their_own_in_order(top_and_skirt):
    _, jobs, many, _ = top_and_skirt
    assert many[0].stats["substeps"] == many[1].stats["substeps"] != 6 and many[2].stats["substeps"] == 6
    assert many[2].stable and many[2].garment.shape[0] == 3


@pytest.mark.parametrize("call, problem", [
    (lambda: simulate_many(SimJob("short-skirt", "walk")), "jobs"),
    (lambda: simulate_many([SimJob("short-skirt", "walk")], worlds=0), "worlds"),
    (lambda: simulate_many([SimJob("short-skirt", "walk"), SimJob("short-skirt", "no-such-motion")]), "no-such-motion"),
    (lambda: simulate_many([SimJob("short-skirt", "walk", stats="s.json"), SimJob("short-pants", "walk", stats="s.json")]),
     "written by job 0 and job 1"),
])
def test_bad_input_to_simulate_many_is_refused_before_anything_runs(call, problem):
    with pytest.raises(DartsInputError, match=problem):
        call()


def test_a_lone_world_is_a_single_run_bit_for_bit(body):
    """One world through the many-world loop is ``sim.run.simulate`` exactly: same positions, same
    measures every frame (same machine, same process)."""
    import darts
    from sim.body_track import build_body_track
    from sim.run import simulate

    dart = darts.load_garment("short-skirt")
    track = build_body_track(body, darts.load_motion("squat"), 30.0, 0.2)
    track.vertices = track.vertices[:12]
    alone, world = [], []
    single = simulate(dart, track, SimSettings(), lambda g, _: alone.append(g), winding=True, measure_every=3)
    many = simulate_worlds([World(dart, track, lambda g, _: world.append(g))], SimSettings(), winding=True,
                           measure_every=3)[0]
    assert len(alone) == 6 and np.array_equal(np.array(alone), np.array(world)) and single.frames == many.frames


def test_an_outfit_is_one_world_beside_a_lone_garment():
    """An outfit (two layers) and a lone garment as two worlds: each comes back with its own
    garments, the outfit with its layer measures, neither inside its body."""
    runs = simulate_many([SimJob(["long-pants", "long-sleeve-top"], "walk", frames=2, settle=0.2, winding=True),
                          SimJob("short-skirt", "walk", frames=2, settle=0.2, winding=True)])
    outfit, skirt = runs
    assert outfit.stable and skirt.stable and outfit.garment_names == ["long_pants", "long_sleeve_top"]
    assert set(outfit.stats["garments"]) == {"long_pants", "long_sleeve_top"} and "garments" not in skirt.stats
    assert outfit.stats["max_layer_inside"] is not None and outfit.stats["max_penetration"] < 0.01
    assert skirt.stats["max_penetration"] < 0.01
