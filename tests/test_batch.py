"""`darts batch`: SPEC to jobs, a local Ray run, resuming after SIGKILL, a broken job, bad input."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from darts.dart.build import make_dart
from darts.dart.io import save_dart
from darts.errors import DartsInputError
from darts.jobs import MANIFEST, read_manifest
from sim.batch.spec import load_jobs

EXAMPLE = Path(__file__).parents[1] / "scenes" / "batch" / "example.toml"


@pytest.fixture(scope="module")
def coarse_garments(body, tmp_path_factory):
    """The example's two garments at 3 cm edges (about 700 vertices): the same jobs, a few seconds each."""
    folder = tmp_path_factory.mktemp("garments")
    for name in ("short-skirt", "sleeveless-top"):
        save_dart(make_dart(name, body, edge_length=0.03), folder / f"{name}.npz")
    return folder


def _spec(folder: Path, garments, frames: int, extra: str = "") -> Path:
    path = folder / "spec.toml"
    path.write_text(EXAMPLE.read_text().replace("frames = 6", f"frames = {frames}")
                    .replace('garments = ["short-skirt", "sleeveless-top"]', f"garments = {json.dumps(garments)}") + extra)
    return path


def _published(out: Path) -> list[Path]:
    return [d for d in out.glob("*") if d.is_dir() and not d.name.startswith(".")]


def _darts_batch(*args, **kwargs) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "darts.cli.main", "batch", *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs)


def test_example_spec_is_the_cross_product():
    jobs = load_jobs(EXAMPLE)
    assert len(jobs) == 8 and len({job.id for job in jobs}) == 8
    combos = {(j.inputs["garment"], j.inputs["motion"], j.inputs["body"]) for j in jobs}
    assert combos == {(g, m, b) for g in ("short-skirt", "sleeveless-top") for m in ("walk", "squat") for b in ("mean", "broad")}
    broad = next(j for j in jobs if j.inputs["body"] == "broad")
    assert broad.inputs["betas"] == [1.5, 0.8] and "--betas 1.5 0.8" in broad.inputs["command"]
    assert all("--frames 6 --settle 0.3" in j.inputs["command"] for j in jobs)


def test_an_outfit_is_one_job_of_its_garments(tmp_path):
    spec = tmp_path / "outfits.toml"
    spec.write_text('[sim]\nframes = 2\n[sweep]\ngarments = [["long-pants", "long-sleeve-top"], "short-skirt"]\n'
                    'motions = ["walk"]\n')
    outfit, single = load_jobs(spec)
    assert outfit.inputs["job"]["garment"] == ["long-pants", "long-sleeve-top"] and single.inputs["garment"] == "short-skirt"
    assert outfit.inputs["command"].startswith("darts-sim long-pants long-sleeve-top walk -o")
    assert outfit.id.startswith("long-pants-long-sleeve-top_walk_mean")
    spec.write_text('[sweep]\ngarments = [["long-pants", "no-such-top"]]\nmotions = ["walk"]\n')
    with pytest.raises(DartsInputError, match="no-such-top"):
        load_jobs(spec)
    spec.write_text('[sweep]\ngarments = [["long-pants", ["long-sleeve-top"]]]\nmotions = ["walk"]\n')
    with pytest.raises(DartsInputError, match="not a list of lists"):
        load_jobs(spec)


@pytest.mark.slow
def test_killed_batch_resumes_without_redoing_finished_jobs(coarse_garments, tmp_path):
    spec = _spec(tmp_path, [str(coarse_garments / "short-skirt.npz"), str(coarse_garments / "sleeveless-top.npz")], 12)
    out = tmp_path / "out"
    first = _darts_batch(spec, "-o", out, "--workers", "2")
    deadline = time.time() + 240
    in_flight: list[Path] = []
    while time.time() < deadline:  # kill once a job has finished while another is still being written
        if any((d / "result.json").is_file() for d in _published(out)):
            in_flight = list(out.glob(".*.tmp-*"))
            if in_flight:
                break
        time.sleep(0.1)
    first.send_signal(signal.SIGKILL)
    first.wait()
    finished = {d.name: (d / "result.json").stat().st_mtime_ns for d in _published(out)}
    assert 1 <= len(finished) < 8 and in_flight, "the kill must come mid-way, with jobs in flight"
    for folder in _published(out):  # every published folder is complete
        assert {"result.json", "stats.json", "sim.usdc"} <= {p.name for p in folder.iterdir()}, folder
    again = _darts_batch(spec, "-o", out, "--workers", "2")
    _, err = again.communicate(timeout=600)
    assert again.returncode == 0, err
    rows = read_manifest(out / MANIFEST)
    assert len(rows) == 8 and all(row["status"] == "ok" for row in rows.values())
    assert all((out / name / "result.json").stat().st_mtime_ns == mtime for name, mtime in finished.items())
    assert not list(out.glob(".*.tmp-*"))
    lines = (out / MANIFEST).read_text().splitlines()
    assert len(lines) == 8  # rewritten: one row per job
    row = json.loads(lines[0])
    assert {"garment", "motion", "body", "betas", "status", "wall_seconds", "sim_fps", "max_penetration",
            "max_seam_gap", "stable", "error", "command"} <= set(row)
    assert row["stable"] and row["max_penetration"] <= 0.01 and row["sim_fps"] > 0


@pytest.mark.slow
def test_a_broken_garment_fails_its_jobs_only(coarse_garments, tmp_path, run_darts):
    broken = tmp_path / "broken.npz"
    broken.write_bytes(b"PK\x03\x04 this is not a garment")
    spec = _spec(tmp_path, [str(coarse_garments / "short-skirt.npz"), str(broken)], 1)
    spec.write_text(spec.read_text().replace('motions = ["walk", "squat"]', 'motions = ["walk"]'))
    out = tmp_path / "out"
    code, stdout, _ = run_darts("batch", spec, "-o", out)
    assert code == 1
    rows = list(read_manifest(out / MANIFEST).values())
    failed = [r for r in rows if r["status"] == "failed"]
    assert len(rows) == 4 and len(failed) == 2 and all(r["garment"] == str(broken) for r in failed)
    assert all("broken.npz" in r["error"] and "npz" in r["error"] for r in failed)
    assert all(r["status"] == "ok" for r in rows if r not in failed)
    assert not any((out / r["id"]).exists() for r in failed)
    assert "2 of 4 jobs succeeded" in stdout


@pytest.mark.parametrize("case, problem", [
    ("unreadable", "is not valid TOML"),
    ("missing", "no such file"),
    ("unknown key", "unknown key(s) frame"),
    ("bad setting", "substeps must be >= 1"),
    ("unknown material", "unknown material 'wool'"),
    ("address", "cannot reach a Ray cluster at 127.0.0.1:9"),
    ("unknown garment", "sweep.garments: poncho: neither a file nor a shipped garment (shipped: long-pants"),
    ("missing motion file", "jobs[0].motion: "),
])
@pytest.mark.parametrize("listing", [False, True])
def test_bad_batch_input_is_one_line_exit_2_and_no_output(case, problem, listing, tmp_path, run_darts):
    """Also with --list, which runs nothing: the same checks, and OUT_DIR is not made."""
    spec = tmp_path / "spec.toml"
    text = EXAMPLE.read_text()
    spec.write_text({"unreadable": "[sim\nframes = ", "missing": text, "unknown key": text.replace("frames = 6", "frame = 6"),
                     "bad setting": text + "\n[[jobs]]\ngarment = 'short-skirt'\nmotion = 'walk'\nsim = { substeps = 0 }\n",
                     "unknown material": text.replace("[sweep]", "[sweep]\nmaterials = ['wool']"),
                     "address": text,
                     "unknown garment": text.replace('garments = ["short-skirt"', 'garments = ["poncho"'),
                     "missing motion file": text + "\n[[jobs]]\ngarment = 'short-skirt'\nmotion = 'gone/dance.npz'\n",
                     }[case])
    if case == "missing":
        spec.unlink()
    args = ["batch", spec, "-o", tmp_path / "out"] + (["--address", "127.0.0.1:9"] if case == "address" else [])
    args += ["--list"] if listing else []
    code, out, err = run_darts(*args)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and problem in err, err
    assert err.startswith("darts: error: ") and not (tmp_path / "out").exists()


def test_listing_a_batch_writes_nothing(tmp_path, run_darts):
    code, stdout, _ = run_darts("batch", EXAMPLE, "-o", tmp_path / "out", "--list")
    assert code == 0 and "darts-sim" in stdout and not (tmp_path / "out").exists()


def test_a_group_of_jobs_is_published_job_by_job_and_a_bad_one_fails_alone(tmp_path):
    """``darts.jobs.run_group`` (``darts batch --worlds``): each job of a group in its own folder
    with its own row; a group refused as a whole is done job by job, so only the bad job fails."""
    from darts.jobs import RESULT, Job, run_group

    def together(jobs, folders):
        if any(job.inputs["bad"] for job in jobs):
            raise DartsInputError("bad.npz", "not a garment")
        for folder in folders:
            (folder / "out.txt").write_text("together")
        return [{"how": "together"} for _ in jobs]

    def alone(job, folder):
        if job.inputs["bad"]:
            raise DartsInputError("bad.npz", "not a garment")
        (folder / "out.txt").write_text("alone")
        return {"how": "alone"}

    good = [Job(f"good{k}", {"bad": False}) for k in range(3)]
    rows = run_group(together, alone, good, tmp_path)
    assert [r["status"] for r in rows] == ["ok"] * 3 and all(r["how"] == "together" for r in rows)
    assert all(json.loads((tmp_path / j.id / RESULT).read_text())["id"] == j.id for j in good)
    mixed = [Job("a", {"bad": False}), Job("b", {"bad": True}), Job("c", {"bad": False})]
    rows = run_group(together, alone, mixed, tmp_path)
    assert [r["status"] for r in rows] == ["ok", "failed", "ok"] and rows[1]["error"] == "bad.npz: not a garment"
    assert (tmp_path / "a" / "out.txt").read_text() == "alone" and not (tmp_path / "b").exists()
    assert not list(tmp_path.glob(".*.tmp-*"))


@pytest.mark.slow
def test_a_batch_steps_its_jobs_as_worlds_of_one_solver(coarse_garments, tmp_path, run_darts):
    spec = _spec(tmp_path, [str(coarse_garments / "short-skirt.npz"), str(coarse_garments / "sleeveless-top.npz")], 2)
    out = tmp_path / "out"
    code, stdout, _ = run_darts("batch", spec, "-o", out, "--worlds", "4", "--workers", "2")
    assert code == 0 and "8 of 8 jobs succeeded" in stdout
    rows = list(read_manifest(out / MANIFEST).values())
    assert len(rows) == 8 and all(r["stable"] and r["frames"] == 2 for r in rows)
    assert all(r["max_penetration"] <= 0.01 for r in rows if r["body"] == "mean")
    assert all({"result.json", "stats.json", "sim.usdc"} <= {p.name for p in (out / r["id"]).iterdir()} for r in rows)
