"""Property-based fuzzing of every loader: damaged, mistyped and out-of-range inputs either load or
raise one DartsInputError naming the file (which the CLIs print as one line and exit 2), never
anything else; and the commands carry damaged inputs into native code without a crash (a child
process, ``tests.fuzz_cases``). CI runs the derandomised ``ci`` profile (``tests/conftest.py``: a
fixed number of examples per loader); ``scripts/fuzz_report.py`` runs thousands of cases."""
from __future__ import annotations

import json
import signal
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from darts.body.io import DEFAULT_BODY_PATH, load_body
from darts.camera import Camera
from darts.crdl.silhouette import read_mask
from darts.crdl.targets import read_target_lines
from darts.dart.io import load_dart
from darts.errors import DartsInputError
from darts.motion.amass import load_motion
from sim.batch.spec import load_jobs
from tests.fuzz_cases import (
    CRASH_PROBE,
    GARMENT,
    KINDS,
    MOTION,
    HypothesisPick,
    damaged_archive,
    damaged_body_pickle,
    legacy_body,
    run_cases,
)
from tests.helpers import legacy_pickle, npz_arrays

BATCH = Path(__file__).parents[1] / "scenes" / "batch" / "example.toml"
CAMERA = {"width": 64, "height": 48, "fx": 60.0, "fy": 60.0, "cx": 32.0, "cy": 24.0,
          "rotation": np.eye(3).tolist(), "translation": [0.0, 0.0, 3.0]}
_ARRAYS = {source: npz_arrays(source) for source in (MOTION, GARMENT, DEFAULT_BODY_PATH)}


def _holds_contract(load, path: Path) -> None:
    """``load(path)`` returns or raises a DartsInputError naming ``path`` in one line."""
    try:
        load(path)
    except DartsInputError as exc:
        text = str(exc)
        assert text.startswith(str(path)) and "\n" not in text, text


@pytest.mark.parametrize("load, source", [(load_motion, MOTION), (load_dart, GARMENT), (load_body, DEFAULT_BODY_PATH)],
                         ids=["motion", "garment", "body"])
@given(data=st.data())
def test_damaged_npz_files_load_or_name_the_file(load, source, data, tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / source.name
    path.write_bytes(damaged_archive(HypothesisPick(data), _ARRAYS[source]))
    _holds_contract(load, path)


@given(data=st.data())
def test_damaged_line_files_load_or_name_the_file(data, tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / "lines.npz"
    dart = load_dart(GARMENT)
    lines = {name: dart.vertices[loop] for name, loop in dart.lines.items()}
    path.write_bytes(damaged_archive(HypothesisPick(data), lines))
    _holds_contract(lambda p: read_target_lines(p, dart.category, list(dart.lines)), path)


_JSON = st.recursive(st.none() | st.booleans() | st.floats(allow_nan=True) | st.integers() | st.text(max_size=5),
                     lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
                     max_leaves=12)


@given(data=st.data())
def test_damaged_cameras_load_or_name_the_file(data, tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / "camera.json"
    camera = dict(CAMERA)
    key = data.draw(st.sampled_from(sorted(camera)))
    camera[key] = data.draw(_JSON)
    text = json.dumps(camera).encode()
    if data.draw(st.booleans()):
        text = text[:data.draw(st.integers(0, len(text)))]
    path.write_bytes(text)
    _holds_contract(Camera.from_json, path)


@given(data=st.binary(max_size=400), width=st.integers(1, 8), height=st.integers(1, 8))
def test_damaged_masks_load_or_name_the_file(data, width, height, tmp_path_factory):
    from PIL import Image

    path = tmp_path_factory.mktemp("fuzz") / "mask.png"
    Image.fromarray((np.arange(width * height).reshape(height, width) % 2 * 255).astype(np.uint8)).save(path)
    raw = bytearray(path.read_bytes())
    for k, byte in enumerate(data[:8]):
        raw[(k * 131 + byte) % len(raw)] ^= byte or 1
    path.write_bytes(bytes(raw))
    _holds_contract(lambda p: read_mask(p, width, height), path)


@given(data=st.data())
def test_damaged_batch_specs_load_or_name_the_file(data, tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / "spec.toml"
    lines = BATCH.read_text().splitlines()
    index = data.draw(st.integers(0, len(lines) - 1))
    lines[index] = data.draw(st.sampled_from([
        "", "frames = -3", "fps = 1e9", 'garments = "x"', "motions = []", "[sweep", 'seams = [["a"]]',
        "materials = [1]", "settle = nan", 'bogus = 1', 'solver = "nope"', "bodies = [{betas = ['a']}]",
    ]))
    path.write_text("\n".join(lines))
    _holds_contract(load_jobs, path)


def test_the_legacy_body_pickle_of_the_fuzz_suite_loads(tmp_path):
    (tmp_path / "body.pkl").write_bytes(legacy_pickle(legacy_body()))
    assert load_body(tmp_path / "body.pkl").num_vertices == len(_ARRAYS[DEFAULT_BODY_PATH]["v_template"])


@given(data=st.data())
def test_damaged_body_pickles_load_or_name_the_file(data, tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / "body.pkl"
    path.write_bytes(damaged_body_pickle(HypothesisPick(data)))
    _holds_contract(load_body, path)


#: Damaged-input cases per kind the commands run in a child process in CI (``scripts/fuzz_report.py`` runs thousands).
NATIVE_CASES = 3


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
def test_commands_carry_damaged_inputs_without_a_native_crash(kind):
    """Each damaged input goes through the commands that take it to native code (Warp, torch,
    scipy, PIL) in a child process: no signal, no traceback, exit 0, 2 (one line) or 3."""
    results = run_cases(kind, 0, NATIVE_CASES)
    assert [r["case"] for r in results] == list(range(NATIVE_CASES)), results
    for result in results:
        for run in result["runs"]:
            assert run["exit"] in (0, 2, 3), (result["case"], run)
            if run["exit"] == 2:
                assert run["stderr"].count("\n") == 1, run


def test_the_child_process_harness_names_the_case_a_signal_killed():
    results = run_cases(CRASH_PROBE, 0, 3)
    assert [(r["case"], r.get("signal")) for r in results] == [(0, None), (1, signal.SIGSEGV), (2, None)]


def test_an_archive_asking_for_a_zip_version_python_lacks_names_the_file(tmp_path):
    """The fuzz run's one find among 3,000 cases: a flipped byte in the central directory's
    'version needed to extract' made zipfile raise NotImplementedError, a traceback."""
    raw = bytearray((MOTION).read_bytes())
    entry = raw.index(b"PK\x01\x02")
    raw[entry + 6] = 108  # version 10.8
    path = tmp_path / "motion.npz"
    path.write_bytes(bytes(raw))
    with pytest.raises(DartsInputError, match="not a valid .npz archive .zip file version 10.8"):
        load_motion(path)
