"""Property-based fuzzing of every loader: damaged, mistyped and out-of-range inputs either load or
raise one DartsInputError naming the file (which the CLIs print as one line and exit 2), never
anything else. CI runs the derandomised ``ci`` profile (a fixed number of examples per loader);
``HYPOTHESIS_PROFILE=long pytest tests/test_fuzz_inputs.py`` runs 1,000 per loader by hand."""
from __future__ import annotations

import io
import json
import os
import zipfile
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from darts.body.io import DEFAULT_BODY_PATH, REQUIRED_KEYS, load_body
from darts.camera import Camera
from darts.crdl.silhouette import read_mask
from darts.crdl.targets import read_target_lines
from darts.dart.io import load_dart
from darts.errors import DartsInputError
from darts.motion.amass import load_motion
from scenes import GARMENTS_DIR, MOTIONS_DIR
from sim.batch.spec import load_jobs
from tests.helpers import ChumpyArray, chumpy_holding_itself, legacy_pickle, nested_chumpy, npz_arrays

settings.register_profile("ci", max_examples=25, derandomize=True, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
settings.register_profile("long", max_examples=1000, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

MOTION = MOTIONS_DIR / "squat.npz"
GARMENT = GARMENTS_DIR / "short-skirt.npz"
BATCH = Path(__file__).parents[1] / "scenes" / "batch" / "example.toml"
CAMERA = {"width": 64, "height": 48, "fx": 60.0, "fy": 60.0, "cx": 32.0, "cy": 24.0,
          "rotation": np.eye(3).tolist(), "translation": [0.0, 0.0, 3.0]}


_ARRAYS = {source: npz_arrays(source) for source in (MOTION, GARMENT, DEFAULT_BODY_PATH)}

#: Values a mistyped member may hold instead of its own.
_WRONG_VALUES = st.sampled_from([
    np.array(["a", "b"]), np.array("text"), np.zeros(3, complex), np.zeros(3, dtype=[("x", "f4"), ("y", "i4")]),
    np.array([np.nan, 1.0]), np.array([np.inf]), np.zeros((0, 3)), np.zeros((2, 2, 2)), np.array(1e38),
    np.array(-1), np.array(True), np.zeros(5, np.uint8), np.arange(7, dtype=np.int64) - 3, np.full((4, 3), 1e30),
])


def _damaged_archive(data, arrays: dict[str, np.ndarray]) -> bytes:
    """An ``.npz`` of ``arrays`` with one drawn damage: a member dropped, replaced by a wrong value,
    renamed, or the archive's bytes flipped or cut."""
    arrays = dict(arrays)
    kind = data.draw(st.sampled_from(["drop", "replace", "rename", "flip", "truncate", "lzma"]))
    key = data.draw(st.sampled_from(sorted(arrays)))
    if kind == "drop":
        arrays.pop(key)
    elif kind == "replace":
        arrays[key] = data.draw(_WRONG_VALUES)
    buffer = io.BytesIO()
    method = zipfile.ZIP_LZMA if kind == "lzma" else zipfile.ZIP_DEFLATED
    with zipfile.ZipFile(buffer, "w", method) as archive:
        for name, value in arrays.items():
            member = io.BytesIO()
            np.save(member, value)
            archive.writestr(name if (kind == "rename" and name == key) else f"{name}.npy", member.getvalue())
    return _flip_or_cut(data, buffer.getvalue(), "flip" if kind == "lzma" else kind)


def _flip_or_cut(data, raw: bytes, kind: str) -> bytes:
    """``raw`` with 1 to 8 drawn bytes flipped (``kind`` "flip") or cut at a drawn length ("truncate")."""
    raw = bytearray(raw)
    if kind == "flip":
        for _ in range(data.draw(st.integers(1, 8))):
            raw[data.draw(st.integers(0, len(raw) - 1))] ^= data.draw(st.integers(1, 255))
    elif kind == "truncate":
        raw = raw[:data.draw(st.integers(0, len(raw) - 1))]
    return bytes(raw)


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
    path.write_bytes(_damaged_archive(data, _ARRAYS[source]))
    _holds_contract(load, path)


@given(data=st.data())
def test_damaged_line_files_load_or_name_the_file(data, tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / "lines.npz"
    dart = load_dart(GARMENT)
    lines = {name: dart.vertices[loop] for name, loop in dart.lines.items()}
    path.write_bytes(_damaged_archive(data, lines))
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


def _list_holding_itself():
    values = [1.0]
    values.append(values)
    return values


#: Values a legacy SMPL pickle may hold instead of an array (made fresh for each example).
_PICKLED_VALUES = st.sampled_from([
    lambda: {1, 2}, lambda: "text", lambda: None, lambda: {"x": 1}, lambda: [[1.0, 2.0], [3.0]],
    chumpy_holding_itself, lambda: nested_chumpy(np.zeros(3), 5000), lambda: nested_chumpy(np.zeros(3), 3),
    _list_holding_itself,
    lambda: ChumpyArray(np.array(["a"])), lambda: ChumpyArray(None), lambda: scipy.sparse.csr_matrix((2, 2)),
    lambda: ChumpyArray(np.zeros(3, complex)), lambda: np.array([np.nan]),
])


def _legacy_body() -> dict:
    """The bundled body as an official legacy ``.pkl`` holds it: chumpy arrays, a sparse regressor."""
    arrays = {key: _ARRAYS[DEFAULT_BODY_PATH][key] for key in REQUIRED_KEYS}
    for key in ("v_template", "shapedirs", "weights"):
        arrays[key] = ChumpyArray(arrays[key])
    arrays["J_regressor"] = scipy.sparse.csc_matrix(arrays["J_regressor"])
    return arrays


def test_the_legacy_body_pickle_of_the_fuzz_suite_loads(tmp_path):
    (tmp_path / "body.pkl").write_bytes(legacy_pickle(_legacy_body()))
    assert load_body(tmp_path / "body.pkl").num_vertices == len(_ARRAYS[DEFAULT_BODY_PATH]["v_template"])


@given(data=st.data())
def test_damaged_body_pickles_load_or_name_the_file(data, tmp_path_factory):
    values = _legacy_body()
    key = data.draw(st.sampled_from(sorted(values)))
    kind = data.draw(st.sampled_from(["drop", "replace", "flip", "truncate"]))
    if kind == "drop":
        values.pop(key)
    elif kind == "replace":
        values[key] = data.draw(_PICKLED_VALUES)()
    path = tmp_path_factory.mktemp("fuzz") / "body.pkl"
    path.write_bytes(_flip_or_cut(data, legacy_pickle(values), kind))
    _holds_contract(load_body, path)
