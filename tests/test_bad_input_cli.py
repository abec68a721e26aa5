"""The bad-input contract at the command line: ``PROG: error: FILE: problem`` on one line, exit 2,
nothing written; and runs that are interrupted or killed leave nothing half-written."""
from __future__ import annotations

import io
import os
import signal
import struct
import subprocess
import sys
import time
import zipfile

import numpy as np
import pytest

from darts.fileio import temporary_prefix
from scenes import GARMENTS_DIR, MOTIONS_DIR

SKIRT = GARMENTS_DIR / "short-skirt.npz"
SQUAT = MOTIONS_DIR / "squat.npz"


def _one_line(code, err, *names):
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "error:" in lines[0] and "Traceback" not in err, err
    assert all(str(n) in lines[0] for n in names), lines[0]
    return lines[0]


def _arrays(path):
    with np.load(path) as archive:
        return {key: archive[key] for key in archive.files}


def _set_zip_flag(path, local_offset, central_offset, value):
    raw = bytearray(path.read_bytes())
    for signature, offset in ((b"PK\x03\x04", local_offset), (b"PK\x01\x02", central_offset)):
        at = raw.find(signature)
        while at >= 0:
            struct.pack_into("<H", raw, at + offset, value)
            at = raw.find(signature, at + 4)
    path.write_bytes(bytes(raw))


def _huge_member(path, arrays, key):
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (100000000000, 3), }"
    header += " " * (118 - len(header)) + "\n"
    with zipfile.ZipFile(path, "w") as archive:
        for name, value in arrays.items():
            member = io.BytesIO()
            np.save(member, value)
            data = member.getvalue()
            if name == key:
                data = b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode() + bytes(64)
            archive.writestr(f"{name}.npy", data)


@pytest.mark.parametrize("damage, problem", [
    ("encrypted", "is encrypted"), ("method", "compression method 99"), ("huge", "more than an input may hold"),
    ("betas text", "'betas' must be numbers"), ("betas record", "'betas' must be numbers"),
    ("deflate", "is damaged"), ("no suffix", "is not a .npy array"),
])
def test_a_damaged_motion_is_one_line(damage, problem, tmp_path, run_sim):
    arrays, path, out = _arrays(SQUAT), tmp_path / "motion.npz", tmp_path / "out.usdc"
    if damage == "huge":
        _huge_member(path, arrays, "trans")
    elif damage == "no suffix":
        with zipfile.ZipFile(path, "w") as archive:
            for name, value in arrays.items():
                member = io.BytesIO()
                np.save(member, value)
                archive.writestr(name, member.getvalue())
    else:
        if damage.startswith("betas"):
            arrays["betas"] = np.array(["a", "b"]) if damage == "betas text" else np.zeros(3, [("x", "f4"), ("y", "i4")])
        (np.savez_compressed if damage == "deflate" else np.savez)(path, **arrays)
        if damage == "encrypted":
            raw = bytearray(path.read_bytes())
            raw[raw.find(b"PK\x03\x04") + 6] |= 1
            raw[raw.find(b"PK\x01\x02") + 8] |= 1
            path.write_bytes(bytes(raw))
        elif damage == "method":
            _set_zip_flag(path, 8, 10, 99)
        elif damage == "deflate":
            raw = bytearray(path.read_bytes())
            raw[200:260] = bytes(60)
            path.write_bytes(bytes(raw))
    code, _, err = run_sim(SKIRT, path, "-o", out, "--frames", "2", "--quiet")
    assert problem in _one_line(code, err, path) and not out.exists()


@pytest.mark.parametrize("change, problem", [
    (dict(vertices=lambda a: np.zeros_like(a)), "0 m across"),
    (dict(material_density=lambda a: np.array(1e-30, a.dtype)), "outside the range of cloth"),
    (dict(material_thickness=lambda a: np.array(1e38, a.dtype)), "outside the range of cloth"),
])
def test_a_garment_that_cannot_be_simulated_is_refused_at_the_door(change, problem, tmp_path, run_sim, run_darts):
    arrays = _arrays(SKIRT)
    arrays.update({key: make(arrays[key]) for key, make in change.items()})
    path = tmp_path / "garment.npz"
    np.savez(path, **arrays)
    code, _, err = run_sim(path, SQUAT, "-o", tmp_path / "out.usdc", "--frames", "2", "--quiet")
    assert problem in _one_line(code, err, path) and not (tmp_path / "out.usdc").exists()
    code, _, err = run_darts("inspect", path)
    assert problem in _one_line(code, err, path)


def test_hull_vertices_without_hull_faces_is_refused(tmp_path, run_darts):
    arrays = _arrays(SKIRT)
    arrays["hull_vertices"] = arrays["vertices"][:10]
    arrays.pop("hull_faces", None)
    np.savez(tmp_path / "g.npz", **arrays)
    code, _, err = run_darts("inspect", tmp_path / "g.npz")
    assert "come together" in _one_line(code, err, tmp_path / "g.npz")


@pytest.mark.parametrize("args, problem", [
    (["--fps", "1e6"], "frames, more than"), (["--settle", "1e9"], "frames, more than"),
])
def test_sizes_that_would_exhaust_memory_are_refused(args, problem, tmp_path, run_sim):
    code, _, err = run_sim(SKIRT, SQUAT, "-o", tmp_path / "o.usdc", "--quiet", *args)
    assert problem in _one_line(code, err)


def test_a_motion_at_a_nanohertz_frame_rate_is_refused(tmp_path, run_sim, run_darts):
    arrays = _arrays(SQUAT)
    arrays["mocap_framerate"] = np.array(1e-9)
    np.savez(tmp_path / "slow.npz", **arrays)
    code, _, err = run_sim(SKIRT, tmp_path / "slow.npz", "-o", tmp_path / "o.usdc", "--quiet")
    assert "frames, more than" in _one_line(code, err, tmp_path / "slow.npz")
    code, _, err = run_darts("body", "pose", "squat", "-o", tmp_path / "p.npz", "--fps", "1e9")
    assert "frames, more than" in _one_line(code, err) and not (tmp_path / "p.npz").exists()


@pytest.mark.parametrize("where", ["stats dir", "stats proc", "preview proc", "output proc", "parent file"])
def test_every_output_is_checked_before_the_run(where, tmp_path, run_sim):
    (tmp_path / "afile").write_text("")
    out = tmp_path / "out.usdc"
    extra = {"stats dir": ["--stats", tmp_path], "stats proc": ["--stats", "/proc/stats.json"],
             "preview proc": ["--preview", "/proc/p.png"], "output proc": [], "parent file": []}[where]
    if where == "output proc":
        out = "/proc/out.usdc"
    if where == "parent file":
        out = tmp_path / "afile" / "out.usdc"
    code, _, err = run_sim(SKIRT, SQUAT, "-o", out, "--frames", "2", "--quiet", *extra)
    _one_line(code, err)
    assert not (tmp_path / "out.usdc").exists()


def test_an_unknown_garment_name_lists_the_shipped_ones(tmp_path, run_sim):
    code, _, err = run_sim("nosuch", SQUAT, "-o", tmp_path / "o.usdc")
    line = _one_line(code, err, "nosuch")
    assert "neither a file nor a shipped garment" in line and "short-skirt" in line


@pytest.mark.parametrize("target, problem", [("/dev/null", "character device"), ("dir", "is a directory"),
                                             ("loop", "symbolic link loop"), ("dangling", "broken symbolic link")])
def test_what_a_path_is_instead_of_a_file(target, problem, tmp_path, run_darts):
    path = {"/dev/null": "/dev/null", "dir": tmp_path, "loop": tmp_path / "loop.npz", "dangling": tmp_path / "d.npz"}[target]
    if target == "loop":
        os.symlink(path, path)
    if target == "dangling":
        os.symlink(tmp_path / "missing", path)
    code, _, err = run_darts("motion", "info", path)
    assert problem in _one_line(code, err, path)


def test_darts_sim_has_a_version(capsys):
    from sim.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.startswith("darts-sim ")


def _darts_sim(*args):
    return subprocess.Popen([sys.executable, "-m", "sim.cli", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _wait_for_temporary(folder, deadline=120):
    end = time.time() + deadline
    while time.time() < end and not list(folder.glob(".out.usdc.*")):
        time.sleep(0.05)
    return list(folder.glob(".out.usdc.*"))


def test_interrupted_and_killed_runs_leave_nothing_half_written(tmp_path):
    out = tmp_path / "out.usdc"
    run = _darts_sim(SKIRT, SQUAT, "-o", out, "--frames", "60")
    assert _wait_for_temporary(tmp_path), "the run never started writing"
    run.send_signal(signal.SIGINT)
    _, err = run.communicate(timeout=60)
    assert run.returncode == 130 and err.strip().splitlines()[-1] == "darts-sim: interrupted", err
    assert not out.exists() and not list(tmp_path.glob(".out.usdc.*"))
    killed = _darts_sim(SKIRT, SQUAT, "-o", out, "--frames", "60", "--quiet")
    left = _wait_for_temporary(tmp_path)
    killed.kill()
    killed.wait()
    assert left and not out.exists() and all(p.name.startswith(temporary_prefix(out).rsplit("-", 2)[0]) for p in left)
    again = _darts_sim(SKIRT, SQUAT, "-o", out, "--frames", "2", "--quiet")
    assert again.wait(timeout=300) == 0 and out.exists()
    assert not [p for p in left if p.exists()], "the killed run's temporary file was not cleaned up"
