"""The Python API (docs/api.md): its example runs as written, and a script gets what the commands get."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import darts
import sim
from darts.camera import Camera
from darts.errors import DartsInputError

DOC = Path(__file__).parents[1] / "docs" / "api.md"


def _example() -> str:
    text = DOC.read_text()
    section = text[text.index("## Example"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


@pytest.mark.slow
def test_the_documented_example_runs_as_written(capsys):
    namespace: dict = {}
    exec(compile(_example(), str(DOC), "exec"), namespace)
    printed = capsys.readouterr().out
    run, report, shirt = namespace["run"], namespace["report"], namespace["shirt"]
    assert run.stable and run.garment.shape == (4, len(shirt.vertices), 3) and run.body.shape == (4, 6890, 3)
    assert run.garment.dtype == np.float32 and np.isfinite(run.garment).all()
    assert report["handle_rmse"] < 0.005 and report["penetration"] < 0.02
    assert run.stats["max_penetration"] <= 0.01 and len(run.stats["frames"]) == 4
    assert 0.3 < namespace["lowest"] < 1.2  # a top hangs from the shoulders, well above the ground (Z up)
    assert "max strain" in printed and "(4, 6890, 3)" in printed


def test_a_script_and_darts_sim_get_the_same_numbers(run_sim, tmp_path):
    quick = {"frames": 2, "settle": 0.1}
    code, _, err = run_sim("short-skirt", "squat", "-o", tmp_path / "cli.usdc", "--stats", tmp_path / "cli.json",
                           "--frames", 2, "--settle", 0.1, "--quiet")
    assert code == 0, err
    # the body as a BodyModel, as every darts function takes it (the CLI reads the bundled file)
    run = sim.simulate("short-skirt", "squat", stats=str(tmp_path / "api.json"), body=darts.load_body(), **quick)
    cli, api = (json.loads((tmp_path / f"{name}.json").read_text()) for name in ("cli", "api"))
    assert cli["frames"] == api["frames"] == run.stats["frames"]  # deterministic on one machine
    assert run.garment.shape == (2, cli["vertices"], 3)


def test_jobs_travel_as_json_and_come_back_equal():
    job = sim.SimJob("short-skirt", "walk", sim.SimSettings(wind=(1.0, 0.0, 0.0), substeps=12), frames=3,
                     betas=[0.5], seams=("all=loose",), output="out.usdc")
    again = sim.SimJob.from_dict(json.loads(json.dumps(job.to_dict())))
    assert again == job


@pytest.mark.parametrize("call, problem", [
    (lambda: darts.load_garment("no-such-garment"), "neither a file nor a shipped garment"),
    (lambda: darts.load_motion("no-such-motion"), "neither a file nor a shipped motion"),
    (lambda: darts.template("cape"), "unknown category 'cape'"),
    (lambda: darts.deform("short-skirt"), "needs either target lines or one or more edits"),
    (lambda: darts.deform("short-skirt", lines={"collar": np.zeros((4, 3))}), "line 'collar' is not a line"),
    (lambda: darts.reconstruct(np.zeros((4, 4), np.uint8)), "[H,W,3] uint8"),
    (lambda: darts.deform("short-skirt", edits=["hem=0.05"], mask=np.zeros((64, 64), bool),
                          camera=Camera.default("short-skirt", 64)), "the mask is empty"),
    (lambda: darts.reconstruct(np.zeros((224, 224, 3), np.uint8), silhouette="fuzzy"), "unknown silhouette term 'fuzzy'"),
    (lambda: sim.simulate("short-skirt", "walk", material="wool"), "unknown material 'wool'"),
    (lambda: sim.simulate("short-skirt", "walk", sim.SimSettings(solver="fem")), "unknown solver 'fem'"),
    (lambda: sim.simulate("short-skirt", "walk", frames=0), "frames must be a whole number >= 1, got int 0"),
    (lambda: sim.simulate("short-skirt", "walk", sim.SimSettings(tether_scale=0.5)), "tether scale must be in [0.9, 1]"),
    (lambda: sim.simulate("short-skirt", "walk", output="x.abc"), "output must end in"),
])
def test_bad_input_raises_one_clear_error(call, problem):
    with pytest.raises(DartsInputError) as error:
        call()
    assert problem in str(error.value) and "\n" not in str(error.value)


def test_a_garment_made_for_another_body_is_refused_with_the_body_it_needs(tmp_path):
    """A DART cut on another body model is not draped on the default body without a word: the run
    says which body it was made for; given that body, it runs."""
    from darts.body.io import export_smpl_npz, read_body

    export_smpl_npz(read_body(), tmp_path / "small.npz", betas=[-2.0])
    skirt = darts.template("short-skirt", body=tmp_path / "small.npz", edge_length=0.03)
    assert skirt.body_model == "small"
    with pytest.raises(darts.DartsInputError, match="was made for the body 'small', and the run's body is 'darts-default-v1'"):
        sim.simulate(skirt, "walk", frames=1, settle=0.0)
    run = sim.simulate(skirt, "walk", frames=1, settle=0.0, body=str(tmp_path / "small.npz"))
    assert run.stable and run.garment.shape[0] == 1
