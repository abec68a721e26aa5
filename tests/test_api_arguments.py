"""The Python API keeps the commands' error contract: a bad argument (its type, its range, its shape,
an unknown key) raises ``DartsInputError`` whose one-line message names the argument — never a bare
TypeError from numpy, torch or Warp (``darts.arguments``). The table holds the calls of issue 48 and
more per function; ``test_fuzzed_api_calls_return_or_raise_one_input_error`` draws many more."""
from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import darts
import darts.body
import darts.motion
import sim
from darts.errors import DartsInputError
from tests.fuzz_api import _objects, call_case
from tests.fuzz_cases import HypothesisPick


def _skirt():
    return _objects()["coarse"]


def _short():
    return _objects()["short"]


_PICTURE = np.full((32, 32, 3), 128, np.uint8)

BAD_CALLS = [
    # loaders
    (lambda: darts.load_motion(123), "motion", "a path, a shipped motion's name or a Motion, got int 123"),
    (lambda: darts.load_garment(None), "garment", "got NoneType None"),
    (lambda: darts.load_body(3.5), "body", "None, a path or a BodyModel"),
    (lambda: darts.load_motion("walk", fps=-5), "fps", "a number in [1, 1000], got int -5"),
    (lambda: darts.load_motion("walk", fps="30"), "fps", "got str '30'"),
    (lambda: darts.load_motion(""), "motion", "got str ''"),
    (lambda: darts.save_garment("short-skirt", "g.npz"), "garment", "a Dart"),
    (lambda: darts.save_garment(_skirt(), 5), "path", "a path, got int 5"),
    # pose
    (lambda: darts.pose("walk", betas=["a"]), "betas", "a list of numbers"),
    (lambda: darts.pose("walk", betas="1 2"), "betas", "got str"),
    (lambda: darts.pose(_short(), betas=[float("nan")]), "betas", "a list of numbers"),
    (lambda: darts.pose(_short(), betas=[0.0] * 400), "betas", "400 given, the body has 16"),
    (lambda: darts.pose(_short(), betas=np.zeros((5, 3))), "betas", "[2, K <= 16]"),
    (lambda: darts.pose(_short(), ground="yes"), "ground", "True or False"),
    # template
    (lambda: darts.template(5), "category", "one of"),
    (lambda: darts.template("short-skirt", edge_length="0.01"), "edge_length", "got str '0.01'"),
    (lambda: darts.template("short-skirt", edge_length=float("nan")), "edge_length", "in [0.003, 0.1]"),
    (lambda: darts.template("short-skirt", seams="all=loose"), "seams", "not one string"),
    (lambda: darts.template("short-skirt", accessories=[1]), "accessories", "a list of strings"),
    (lambda: darts.template("short-skirt", material=None), "material", "a str"),
    # deform
    (lambda: darts.deform(_skirt(), edits="hem=0.1"), "edits", "a list of strings, e.g. ['hem=0.1'], not one string"),
    (lambda: darts.deform(_skirt(), edits=["hem=0.1"], solver=3), "solver", "got int 3"),
    (lambda: darts.deform(_skirt(), edits=["hem=0.1"], silhouette_weight=-1), "silhouette_weight", ">= 0"),
    (lambda: darts.deform(_skirt(), edits=["hem=0.1"], progress=None), "progress", "True or False"),
    (lambda: darts.deform(_skirt(), lines=42), "lines", "a lines.npz path or a dict"),
    # pictures
    (lambda: darts.classify(42), "image", "a picture's path or an [H,W,3] uint8 array"),
    (lambda: darts.classify(_PICTURE, mask=7), "mask", "got int 7"),
    (lambda: darts.classify(_PICTURE, mask=np.ones((3, 32, 32), bool)), "mask", "not [H,W]"),
    (lambda: darts.read_outfit(None), "image", "got NoneType"),
    (lambda: darts.reconstruct(_PICTURE, category=3), "category", "one of"),
    (lambda: darts.reconstruct(_PICTURE, garment="hat"), "garment", "unknown garment 'hat'"),
    (lambda: darts.reconstruct(_PICTURE, edge_length=[1]), "edge_length", "got list"),
    (lambda: darts.reconstruct(_PICTURE, camera=3), "camera", "a Camera or a camera.json path"),
    (lambda: darts.reconstruct(_PICTURE, accept_low_confidence="no"), "accept_low_confidence", "True or False"),
    (lambda: darts.reconstruct_outfit(_PICTURE, garments="upper"), "garments", "not one string"),
    (lambda: darts.reconstruct_outfit(_PICTURE, lengths=1), "lengths", "True or False"),
    # darts.body, darts.motion
    (lambda: darts.body.read_body(5), "path", "None or a path"),
    (lambda: darts.body.export_smpl_npz("x", "y.npz"), "body", "a BodyArrays"),
    (lambda: darts.motion.resample(_short(), 0), "fps", "a number in [1, 1000]"),
    (lambda: darts.motion.resample("walk", 30), "motion", "a Motion"),
    (lambda: darts.motion.save_motion(None, "x.npz"), "motion", "a Motion"),
    (lambda: darts.motion.load_motion(None), "path", "a path"),
    (lambda: darts.motion.pose_sequence(_objects()["body"], "walk"), "motion", "a Motion (darts.load_motion)"),
    (lambda: darts.motion.pose_sequence(_objects()["body"], _short(), chunk=0), "chunk", ">= 1"),
    # sim.simulate
    (lambda: sim.simulate(_skirt(), _short(), frames=2.5), "frames", "a whole number >= 1, got float 2.5"),
    (lambda: sim.simulate(_skirt(), _short(), frames=2.0), "frames", "(an int, not a float)"),
    (lambda: sim.simulate(_skirt(), _short(), frames="2"), "frames", "got str '2'"),
    (lambda: sim.simulate(_skirt(), _short(), settings={"substeps": 0}), "substeps", "substeps must be >= 1, got 0"),
    (lambda: sim.simulate(_skirt(), _short(), settings={"substep": 4}), "substep", "unknown key 'substep'"),
    (lambda: sim.simulate(_skirt(), _short(), settings=5), "settings", "a dict of SimSettings fields"),
    (lambda: sim.simulate(_skirt(), _short(), bogus=1), "bogus", "unknown option 'bogus'"),
    (lambda: sim.simulate(_skirt(), _short(), start=-1), "start", ">= 0"),
    (lambda: sim.simulate(_skirt(), _short(), settle=float("inf")), "settle", ">= 0"),
    (lambda: sim.simulate(_skirt(), _short(), betas="1"), "betas", "a list of numbers"),
    (lambda: sim.simulate(_skirt(), _short(), seams="all=loose"), "seams", "not one string"),
    (lambda: sim.simulate(_skirt(), _short(), output=5), "output", "None or a path"),
    (lambda: sim.simulate(_skirt(), _short(), format="abc"), "format", "unknown format 'abc'"),
    (lambda: sim.simulate(_skirt(), _short(), measure_every=0), "measure_every", ">= 1"),
    (lambda: sim.simulate(_skirt(), _short(), keep_frames="yes"), "keep_frames", "True or False"),
    (lambda: sim.simulate([], _short()), "garment", "at least one garment"),
    (lambda: sim.simulate(5, _short()), "garment", "got int 5"),
    (lambda: sim.simulate(["short-skirt", 5], _short()), "garment", "got int 5"),
    (lambda: sim.simulate(_skirt(), 5), "motion", "got int 5"),
    (lambda: sim.simulate(_skirt(), _short(), body=5), "body", "None, a path or a BodyModel"),
    (lambda: sim.run_job("job"), "job", "a SimJob"),
    # sim.SimSettings
    (lambda: sim.SimSettings(substeps="x"), "substeps", "got str 'x'"),
    (lambda: sim.SimSettings(fps=float("inf")), "fps", "a number"),
    (lambda: sim.SimSettings(fps=-30), "fps", "fps must be > 0"),
    (lambda: sim.SimSettings(wind=(1, 2)), "wind", "three numbers"),
    (lambda: sim.SimSettings(ground="no"), "ground", "True or False"),
    (lambda: sim.SimSettings(solver=None), "solver", "a str"),
    (lambda: sim.SimSettings(iterations=0), "iterations", "iterations must be >= 1"),
    # sim.SimJob.from_dict
    (lambda: sim.SimJob.from_dict({"garment": 5, "motion": "walk"}), "garment", "got int 5"),
    (lambda: sim.SimJob.from_dict({"garment": "short-skirt"}), "motion", "'motion' is missing"),
    (lambda: sim.SimJob.from_dict({}), "garment", "'garment' is missing"),
    (lambda: sim.SimJob.from_dict([]), "job", "a dict of SimJob's fields"),
    (lambda: sim.SimJob.from_dict({"garment": "x", "motion": "walk", "colour": 1}), "colour", "unknown key 'colour'"),
    (lambda: sim.SimJob.from_dict({"garment": "x", "motion": "walk", "settings": {"fps": -1}}), "fps", "fps must be > 0"),
    (lambda: sim.SimJob.from_dict({"garment": "x", "motion": "walk", "settings": []}), "settings", "a dict"),
]


@pytest.mark.parametrize("call, argument, problem", BAD_CALLS,
                         ids=[f"{k}-{argument}" for k, (_, argument, _) in enumerate(BAD_CALLS)])
def test_a_bad_argument_raises_one_input_error_naming_it(call, argument, problem, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(DartsInputError) as error:
        call()
    message = str(error.value)
    assert argument in message and problem in message and "\n" not in message, message
    assert os.listdir(tmp_path) == []  # nothing written


def test_a_job_round_trips_through_its_dict_and_numbers_of_numpy_types_are_taken():
    job = sim.SimJob("short-skirt", "walk", {"substeps": np.int64(12), "wind": [1, 0, 0]}, frames=np.int32(3),
                     settle=np.float32(0.25), betas=np.zeros(2), seams=["all=loose"])
    assert job.settings.substeps == 12 and job.settings.wind == (1.0, 0.0, 0.0) and job.frames == 3
    assert type(job.frames) is int and job.betas == (0.0, 0.0) and job.seams == ("all=loose",)
    assert sim.SimJob.from_dict(job.to_dict()) == job


@given(data=st.data())
def test_fuzzed_api_calls_return_or_raise_one_input_error(data):
    """A working call of a drawn public function with one argument replaced by a drawn wrong value
    (``tests.fuzz_api``) returns or raises DartsInputError in one line, never another exception."""
    case = call_case(HypothesisPick(data))
    assert case["outcome"] != "bare", case
    assert case["outcome"] == "returned" or case["one_line"], case
