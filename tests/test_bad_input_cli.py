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
from pathlib import Path

import numpy as np
import pytest

from darts.body.io import DEFAULT_BODY_PATH as BODY
from darts.body.io import REQUIRED_KEYS
from darts.fileio import temporary_prefix
from scenes import GARMENTS_DIR, MOTIONS_DIR
from tests.helpers import chumpy_holding_itself, legacy_pickle, nested_chumpy, npz_arrays

SKIRT = GARMENTS_DIR / "short-skirt.npz"
SQUAT = MOTIONS_DIR / "squat.npz"


def _one_line(code, err, *names):
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "error:" in lines[0] and "Traceback" not in err, err
    assert all(str(n) in lines[0] for n in names), lines[0]
    return lines[0]


def _patch_zip_headers(path, local_offset, central_offset, change):
    """Rewrite one 16-bit field of every local and central zip header: ``value -> change(value)``."""
    raw = bytearray(path.read_bytes())
    for signature, offset in ((b"PK\x03\x04", local_offset), (b"PK\x01\x02", central_offset)):
        at = raw.find(signature)
        while at >= 0:
            (value,) = struct.unpack_from("<H", raw, at + offset)
            struct.pack_into("<H", raw, at + offset, change(value))
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
    ("deflate", "is damaged"), ("no suffix", "is not a .npy array"), ("lzma", "is damaged"),
    ("not npy", "member 'poses.npy' is damaged"),
])
def test_a_damaged_motion_is_one_line(damage, problem, tmp_path, run_sim):
    arrays, path, out = npz_arrays(SQUAT), tmp_path / "motion.npz", tmp_path / "out.usdc"
    if damage == "huge":
        _huge_member(path, arrays, "trans")
    elif damage in ("no suffix", "lzma", "not npy"):
        with zipfile.ZipFile(path, "w", zipfile.ZIP_LZMA if damage == "lzma" else zipfile.ZIP_STORED) as archive:
            for name, value in arrays.items():
                member = io.BytesIO()
                np.save(member, value)
                data = b"not an array" if (damage == "not npy" and name == "poses") else member.getvalue()
                archive.writestr(name if damage == "no suffix" else f"{name}.npy", data)
        if damage == "lzma":  # the LZMA stream of the first member lies about its contents
            raw = bytearray(path.read_bytes())
            raw[120:140] = bytes(20)
            path.write_bytes(bytes(raw))
    else:
        if damage.startswith("betas"):
            arrays["betas"] = np.array(["a", "b"]) if damage == "betas text" else np.zeros(3, [("x", "f4"), ("y", "i4")])
        (np.savez_compressed if damage == "deflate" else np.savez)(path, **arrays)
        if damage == "encrypted":
            _patch_zip_headers(path, 6, 8, lambda flags: flags | 1)  # general purpose bit 0: encrypted
        elif damage == "method":
            _patch_zip_headers(path, 8, 10, lambda method: 99)  # compression method
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
    arrays = npz_arrays(SKIRT)
    arrays.update({key: make(arrays[key]) for key, make in change.items()})
    path = tmp_path / "garment.npz"
    np.savez(path, **arrays)
    code, _, err = run_sim(path, SQUAT, "-o", tmp_path / "out.usdc", "--frames", "2", "--quiet")
    assert problem in _one_line(code, err, path) and not (tmp_path / "out.usdc").exists()
    code, _, err = run_darts("inspect", path)
    assert problem in _one_line(code, err, path)


def test_a_garment_without_vertices_is_refused(tmp_path, run_sim, run_darts):
    """Every per-vertex, per-face, per-line and per-pair array empty, so that each agrees with the next."""
    arrays = npz_arrays(SKIRT)
    arrays.update(vertices=np.zeros((0, 3), np.float32), faces=np.zeros((0, 3), np.int32), panel=np.zeros(0, np.int32),
                  line_names=np.zeros(0, "<U1"), line_offsets=np.zeros(1, np.int32), line_vertices=np.zeros(0, np.int32),
                  pairs=np.zeros((0, 2), np.int32), pair_seam=np.zeros(0, np.int32),
                  pair_position=np.zeros(0, np.float32), pair_active=np.zeros(0, bool))
    path = tmp_path / "g.npz"
    np.savez(path, **arrays)
    code, _, err = run_sim(path, SQUAT, "-o", tmp_path / "o.usdc", "--frames", "2", "--quiet")
    assert "no triangles" in _one_line(code, err, path) and not (tmp_path / "o.usdc").exists()
    code, _, err = run_darts("inspect", path)
    assert "no triangles" in _one_line(code, err, path)


def test_hull_vertices_without_hull_faces_is_refused(tmp_path, run_darts):
    arrays = npz_arrays(SKIRT)
    arrays["hull_vertices"] = arrays["vertices"][:10]
    arrays.pop("hull_faces", None)
    np.savez(tmp_path / "g.npz", **arrays)
    code, _, err = run_darts("inspect", tmp_path / "g.npz")
    assert "come together" in _one_line(code, err, tmp_path / "g.npz")


@pytest.mark.parametrize("args, problem", [
    (["--fps", "1e6"], "fps must be a number in [1, 1000], got float 1000000.0"), (["--settle", "1e9"], "frames, more than"),
])
def test_sizes_that_would_exhaust_memory_are_refused(args, problem, tmp_path, run_sim):
    code, _, err = run_sim(SKIRT, SQUAT, "-o", tmp_path / "o.usdc", "--quiet", *args)
    assert problem in _one_line(code, err)


def test_a_motion_at_a_nanohertz_frame_rate_is_refused(tmp_path, run_sim, run_darts):
    arrays = npz_arrays(SQUAT)
    arrays["mocap_framerate"] = np.array(1e-9)
    np.savez(tmp_path / "slow.npz", **arrays)
    code, _, err = run_sim(SKIRT, tmp_path / "slow.npz", "-o", tmp_path / "o.usdc", "--quiet")
    assert "frames/s, not a motion's" in _one_line(code, err, tmp_path / "slow.npz")  # refused as it is read
    code, _, err = run_darts("body", "pose", "squat", "-o", tmp_path / "p.npz", "--fps", "1e9")
    assert "fps must be a number in [1, 1000]" in _one_line(code, err) and not (tmp_path / "p.npz").exists()


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


@pytest.mark.parametrize("option", [["--wind", "nan"], ["--wind", "1,2"], ["--material", "bogus"], ["--format", "xyz"]])
def test_an_option_error_is_one_line_not_the_usage_block(option, tmp_path, run_sim):
    code, _, err = run_sim(SKIRT, SQUAT, "-o", tmp_path / "o.usdc", *option)
    assert option[0] in _one_line(code, err) and "usage:" not in err


@pytest.mark.parametrize("value, problem", [
    (np.array(["a", "b"]), "must be numbers"), (np.zeros((2, 3), complex), "must be numbers"),
    (np.array([object(), 1], dtype=object), "'v_template'"),
])
def test_a_body_npz_with_the_wrong_dtype_is_one_line(value, problem, tmp_path, run_darts):
    arrays = npz_arrays(BODY)
    arrays["v_template"] = value
    np.savez(tmp_path / "body.npz", **arrays)
    code, _, err = run_darts("body", "info", "--body", tmp_path / "body.npz")
    assert problem in _one_line(code, err, tmp_path / "body.npz")


@pytest.mark.parametrize("make, problem", [
    (chumpy_holding_itself, "nested more than"), (lambda: nested_chumpy(np.zeros((6890, 3)), 5001), "nested more than"),
    (lambda: {1.0, 2.0}, "found a set"), (lambda: "abc", "found a str"),
])
def test_a_body_pickle_holding_no_array_is_one_line(make, problem, tmp_path, run_darts):
    arrays = npz_arrays(BODY)
    legacy = {key: arrays[key] for key in REQUIRED_KEYS}
    legacy["v_template"] = make()
    (tmp_path / "body.pkl").write_bytes(legacy_pickle(legacy))
    code, _, err = run_darts("body", "info", "--body", tmp_path / "body.pkl")
    assert problem in _one_line(code, err, tmp_path / "body.pkl")


def _child(*args) -> subprocess.CompletedProcess:
    """A darts command in a child process, so that a native crash (a signal, exit -11) shows as
    such instead of killing the test run."""
    return subprocess.run([sys.executable, "-m", "darts.cli.main", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


@pytest.mark.parametrize("faces, problem", [
    (np.zeros((0, 3), np.uint32), "holds 0 proper triangles"),
    (np.array([[0, 1, 2]], np.uint32), "holds 1 proper triangles"),
    (np.array([[0, 0, 1]] * 50, np.uint32), "holds 0 proper triangles"),
])
def test_a_body_without_a_surface_is_refused_not_crashed_on(faces, problem, tmp_path):
    """Warp's mesh and the distance queries crashed (exit 139, no message) on a body with no faces."""
    arrays = npz_arrays(BODY)
    arrays["f"] = faces
    np.savez(tmp_path / "body.npz", **arrays)
    for command in (("body", "info"), ("template", "short-skirt", "-o", tmp_path / "g.npz")):
        done = _child(*command, "--body", tmp_path / "body.npz")
        assert done.returncode == 2 and problem in done.stderr and len(done.stderr.strip().splitlines()) == 1, done
    assert not (tmp_path / "g.npz").exists()


@pytest.mark.parametrize("damage, problem", [
    (lambda m: m.indices.__setitem__(0, 10**6), "whose indices fall outside its 24x6890 shape"),
    (lambda m: m.indptr.__setitem__(-1, 10**6), "whose CSC pointers do not fit"),
])
def test_a_pickled_sparse_regressor_out_of_its_shape_is_one_line(damage, problem, tmp_path):
    """scipy's toarray() wrote outside its memory for indices out of range (exit 139)."""
    import scipy.sparse

    arrays = npz_arrays(BODY)
    legacy = {key: arrays[key] for key in REQUIRED_KEYS}
    regressor = scipy.sparse.csc_matrix(arrays["J_regressor"])
    damage(regressor)
    legacy["J_regressor"] = regressor
    (tmp_path / "body.pkl").write_bytes(legacy_pickle(legacy))
    done = _child("body", "info", "--body", tmp_path / "body.pkl")
    assert done.returncode == 2 and problem in done.stderr and len(done.stderr.strip().splitlines()) == 1, done


def test_pose_correctives_stored_as_an_object_array_are_refused_not_dropped(tmp_path, run_darts):
    """An optional key the reader cannot take (an object array would need pickle) was left out
    without a word, so the body posed without its correctives."""
    arrays = npz_arrays(BODY)
    arrays["posedirs"] = np.array([np.zeros((6890, 3, 207))], dtype=object)
    np.savez(tmp_path / "body.npz", **arrays)
    code, _, err = run_darts("body", "info", "--body", tmp_path / "body.npz")
    assert "'posedirs' is an object array" in _one_line(code, err, tmp_path / "body.npz")


def test_a_pickled_sparse_regressor_reads_as_its_dense_self(tmp_path):
    """The checked conversion gives what scipy's does, duplicates summed."""
    import scipy.sparse

    from darts.body.io import _sparse_to_dense

    dense = np.random.default_rng(0).random((6, 9)) * (np.random.default_rng(1).random((6, 9)) > 0.6)
    for matrix in (scipy.sparse.csc_matrix(dense), scipy.sparse.csr_matrix(dense), scipy.sparse.coo_matrix(dense)):
        assert np.array_equal(_sparse_to_dense(matrix, "J_regressor", "x"), dense)
    twice = scipy.sparse.coo_matrix(([1.0, 2.0], ([0, 0], [1, 1])), shape=(2, 2))
    assert _sparse_to_dense(twice, "J_regressor", "x")[0, 1] == 3.0


@pytest.mark.parametrize("content, problem", [
    (lambda: BODY.read_bytes(), "is a zip archive (an .npz?), not a pickle: name it .npz"),
    # the pickle module's message for a persistent id carries a line break
    (lambda: b"P0\n.", "A load persistent id instruction was encountered, but no persistent_load"),
])
def test_a_body_pkl_that_is_no_pickle_is_one_line(content, problem, tmp_path, run_darts):
    path = tmp_path / "body.pkl"
    path.write_bytes(content())
    code, _, err = run_darts("body", "info", "--body", path)
    assert problem in _one_line(code, err, path)


def test_an_unreadable_file_says_so_not_that_it_is_no_zip(tmp_path, run_darts, monkeypatch):
    """Permission is simulated (``chmod 0`` does not stop root, who runs CI)."""
    path = tmp_path / "motion.npz"
    path.write_bytes(SQUAT.read_bytes())
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda p, mode, **kw: Path(p) != path and real_access(p, mode, **kw))
    code, _, err = run_darts("motion", "info", path)
    assert "permission denied" in _one_line(code, err, path)


def test_darts_sim_has_a_version(capsys):
    from sim.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.startswith("darts-sim ")


def _darts_sim(*args):
    """darts-sim in a child process with SIGINT's default disposition: a test run started in the
    background by a shell inherits SIGINT ignored, and Python then never turns it into Ctrl-C."""
    return subprocess.Popen([sys.executable, "-m", "sim.cli", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait_for_frames(run, frames: int, deadline=120) -> str:
    """Read the run's progress bar (stderr) until it has counted ``frames``; return what it read.
    (A USD layer is on disk only when it is saved at the end, so its temporary file cannot tell
    that a run is under way.)"""
    import re

    end, seen = time.time() + deadline, ""
    while time.time() < end:
        chunk = os.read(run.stderr.fileno(), 4096).decode(errors="replace")
        if not chunk:
            break
        seen += chunk
        counts = [int(n) for n in re.findall(r"(\d+)/\d+ \[", seen)]
        if counts and max(counts) >= frames:
            break
    return seen


@pytest.mark.slow
def test_interrupted_and_killed_runs_leave_nothing_half_written(tmp_path):
    out = tmp_path / "out.usdc"
    run = _darts_sim(SKIRT, SQUAT, "-o", out, "--frames", "60")
    head = _wait_for_frames(run, 5)
    run.send_signal(signal.SIGINT)
    _, rest = run.communicate(timeout=60)
    err = head + rest
    assert run.returncode == 130 and err.strip().splitlines()[-1] == "darts-sim: interrupted", err
    assert not out.exists() and not list(tmp_path.glob(".out.usdc.*"))
    for output in (out, tmp_path / "frames"):  # a USD file, and a folder of an OBJ sequence
        killed = _darts_sim(SKIRT, SQUAT, "-o", output, "--frames", "60")
        _wait_for_frames(killed, 5)
        left = list(tmp_path.glob(f".{output.name}.*"))
        killed.kill()
        killed.wait()
        assert not output.exists()
        assert all(p.name.startswith(temporary_prefix(output).rsplit("-", 2)[0]) for p in left)
        if output.suffix == "":  # the sequence's folder is on disk from the start (a USD layer only once saved)
            assert left
        deadline = time.monotonic() + 10  # the janitor process notices its writer is gone
        while list(tmp_path.glob(f".{output.name}.*")) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not list(tmp_path.glob(f".{output.name}.*")), "the killed run's temporary was left behind"
    again = _darts_sim(SKIRT, SQUAT, "-o", out, "--frames", "2", "--quiet")
    assert again.wait(timeout=300) == 0 and out.exists()
