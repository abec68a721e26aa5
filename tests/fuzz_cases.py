"""Damaged inputs for the fuzz suite, and the commands that carry them into native code.

The damage is drawn through a ``Pick`` (``HypothesisPick`` in the in-process property tests,
``RandomPick``, numpy seeded, in the child process), so both draw from the same recipes. A native
crash (a segfault in Warp, scipy, PIL or torch) kills the process it happens in, so the commands
run in a child (``python -m tests.fuzz_cases KIND FIRST COUNT``): it prints one JSON line as each
case starts and one as it ends; ``run_cases`` reads them, names the case a signal killed, and starts
a new child after it. Each command runs in-process in the child, through its ``main`` (the console
script's code), so an exception other than ``DartsInputError`` escaping it is a traceback.
"""
from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
import tempfile
import time
import traceback
import zipfile
from pathlib import Path

import numpy as np
import scipy.sparse

from darts.body.io import DEFAULT_BODY_PATH, REQUIRED_KEYS
from scenes import GARMENTS_DIR, MOTIONS_DIR
from tests.helpers import ChumpyArray, chumpy_holding_itself, legacy_pickle, nested_chumpy, npz_arrays

MOTION = MOTIONS_DIR / "squat.npz"
GARMENT = GARMENTS_DIR / "short-skirt.npz"


class RandomPick:
    """Draws from a seeded numpy generator."""

    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)

    def one(self, values):
        return values[int(self.rng.integers(len(values)))]

    def integer(self, low: int, high: int) -> int:
        """An integer in [low, high]."""
        return int(self.rng.integers(low, high + 1))


class HypothesisPick:
    """Draws through hypothesis' ``data`` (shrinkable examples)."""

    def __init__(self, data):
        self.data = data

    def one(self, values):
        from hypothesis import strategies as st

        return self.data.draw(st.sampled_from(list(values)))

    def integer(self, low: int, high: int) -> int:
        from hypothesis import strategies as st

        return self.data.draw(st.integers(low, high))


#: Values a mistyped member may hold instead of its own.
WRONG_VALUES = [
    np.array(["a", "b"]), np.array("text"), np.zeros(3, complex), np.zeros(3, dtype=[("x", "f4"), ("y", "i4")]),
    np.array([np.nan, 1.0]), np.array([np.inf]), np.zeros((0, 3)), np.zeros((2, 2, 2)), np.array(1e38),
    np.array(-1), np.array(True), np.zeros(5, np.uint8), np.arange(7, dtype=np.int64) - 3, np.full((4, 3), 1e30),
]


def damaged_archive(pick, arrays: dict[str, np.ndarray]) -> bytes:
    """An ``.npz`` of ``arrays`` with one drawn damage: a member dropped, replaced by a wrong value,
    renamed, or the archive's bytes flipped or cut."""
    arrays = dict(arrays)
    kind = pick.one(["drop", "replace", "rename", "flip", "truncate", "lzma"])
    key = pick.one(sorted(arrays))
    if kind == "drop":
        arrays.pop(key)
    elif kind == "replace":
        arrays[key] = pick.one(WRONG_VALUES)
    return npz_bytes(arrays, renamed=key if kind == "rename" else None, lzma=kind == "lzma",
                     damage=(pick, "flip" if kind == "lzma" else kind))


def npz_bytes(arrays: dict[str, np.ndarray], renamed: str | None = None, lzma: bool = False, damage=None) -> bytes:
    """The bytes of an ``.npz`` holding ``arrays`` (``renamed`` stored without its .npy suffix;
    ``damage``: (pick, "flip" | "truncate") applied to the bytes)."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_LZMA if lzma else zipfile.ZIP_DEFLATED) as archive:
        for name, value in arrays.items():
            member = io.BytesIO()
            np.save(member, value)
            archive.writestr(name if name == renamed else f"{name}.npy", member.getvalue())
    return flip_or_cut(*damage, buffer.getvalue()) if damage else buffer.getvalue()


def flip_or_cut(pick, kind: str, raw: bytes) -> bytes:
    """``raw`` with 1 to 8 drawn bytes flipped (``kind`` "flip") or cut at a drawn length ("truncate")."""
    raw = bytearray(raw)
    if kind == "flip":
        for _ in range(pick.integer(1, 8)):
            raw[pick.integer(0, len(raw) - 1)] ^= pick.integer(1, 255)
    elif kind == "truncate":
        raw = raw[:pick.integer(0, len(raw) - 1)]
    return bytes(raw)


def _list_holding_itself():
    values = [1.0]
    values.append(values)
    return values


#: Values a legacy SMPL pickle may hold instead of an array (made fresh for each example).
PICKLED_VALUES = [
    lambda: {1, 2}, lambda: "text", lambda: None, lambda: {"x": 1}, lambda: [[1.0, 2.0], [3.0]],
    chumpy_holding_itself, lambda: nested_chumpy(np.zeros(3), 5000), lambda: nested_chumpy(np.zeros(3), 3),
    _list_holding_itself,
    lambda: ChumpyArray(np.array(["a"])), lambda: ChumpyArray(None), lambda: scipy.sparse.csr_matrix((2, 2)),
    lambda: ChumpyArray(np.zeros(3, complex)), lambda: np.array([np.nan]),
]


def body_arrays() -> dict[str, np.ndarray]:
    """The bundled body's arrays, by key."""
    return npz_arrays(DEFAULT_BODY_PATH)


def legacy_body() -> dict:
    """The bundled body as an official legacy ``.pkl`` holds it: chumpy arrays, a sparse regressor."""
    arrays = {key: body_arrays()[key] for key in REQUIRED_KEYS}
    for key in ("v_template", "shapedirs", "weights"):
        arrays[key] = ChumpyArray(arrays[key])
    arrays["J_regressor"] = scipy.sparse.csc_matrix(arrays["J_regressor"])
    return arrays


def damaged_body_pickle(pick) -> bytes:
    """A legacy body pickle with one drawn damage: a value dropped, replaced (``PICKLED_VALUES``, or
    a sparse regressor whose indices run out of range), or the bytes flipped or cut."""
    values = legacy_body()
    key = pick.one(sorted(values))
    kind = pick.one(["drop", "replace", "sparse", "flip", "truncate"])
    if kind == "drop":
        values.pop(key)
    elif kind == "replace":
        values[key] = pick.one(PICKLED_VALUES)()
    elif kind == "sparse":
        regressor = values["J_regressor"].copy()
        regressor.indices[pick.integer(0, len(regressor.indices) - 1)] = pick.one([10 ** 6, -5, 2 ** 31 - 1])
        values["J_regressor"] = regressor
    return flip_or_cut(pick, kind, legacy_pickle(values))


def poisoned_faces(pick, faces: np.ndarray, count: int) -> np.ndarray:
    """Triangles that native mesh code would choke on: none, one, out of range, negative, all
    degenerate, or floats (``count`` vertices)."""
    kind = pick.one(["empty", "one", "beyond", "negative", "degenerate", "float", "wide"])
    if kind == "empty":
        return np.zeros((0, 3), faces.dtype)
    if kind == "one":
        return faces[:1]
    if kind == "degenerate":
        return np.repeat(faces[:, :1], 3, axis=1)
    if kind == "float":
        return faces.astype(np.float64) + 0.5
    if kind == "wide":
        return np.concatenate([faces, faces[:, :1]], axis=1)
    faces = faces.copy()
    faces[pick.integer(0, len(faces) - 1), pick.integer(0, 2)] = count + 10 ** 6 if kind == "beyond" else -3
    return faces


def extreme_points(pick, points: np.ndarray) -> np.ndarray:
    """Points that load but are no garment's or body's size or place: scaled by 1e-4 to 1e4, moved
    10 km, or shaken by 5 cm noise."""
    kind = pick.one(["scale", "far", "shaken"])
    if kind == "scale":
        return points * pick.one([1e-4, 0.01, 100.0, 1e4])
    if kind == "far":
        return points + np.array([1e4, 0.0, -1e4], points.dtype)
    noise = np.random.default_rng(pick.integer(0, 10 ** 6)).normal(0.0, 0.05, points.shape)
    return (points + noise).astype(points.dtype)


def damaged_body_npz(pick) -> bytes:
    """A body ``.npz`` with its faces poisoned (``poisoned_faces``), its rest shape extreme
    (``extreme_points``) or one drawn archive damage."""
    arrays = body_arrays()
    kind = pick.one(["faces", "extreme", "archive"])
    if kind == "faces":
        arrays["f"] = poisoned_faces(pick, arrays["f"], len(arrays["v_template"]))
    elif kind == "extreme":
        arrays["v_template"] = extreme_points(pick, arrays["v_template"])
    else:
        return damaged_archive(pick, arrays)
    return npz_bytes(arrays)


def damaged_garment(pick) -> bytes:
    """A garment ``.npz`` with its faces, seams or lines poisoned, its vertices extreme, or one drawn
    archive damage."""
    arrays = npz_arrays(GARMENT)
    kind = pick.one(["faces", "pairs", "lines", "extreme", "archive", "archive"])
    if kind == "extreme":
        arrays["vertices"] = extreme_points(pick, arrays["vertices"])
    elif kind == "faces":
        arrays["faces"] = poisoned_faces(pick, arrays["faces"], len(arrays["vertices"]))
    elif kind in ("pairs", "lines"):
        key = "pairs" if kind == "pairs" else "line_vertices"
        values = arrays[key].copy()
        values.flat[pick.integer(0, values.size - 1)] = pick.one([10 ** 6, -1, len(arrays["vertices"])])
        arrays[key] = values
    else:
        return damaged_archive(pick, arrays)
    return npz_bytes(arrays)


def damaged_image(pick) -> tuple[bytes, str]:
    """A small picture (PNG or JPEG, of a drawn mode) with bytes flipped or cut: (bytes, suffix)."""
    from PIL import Image

    suffix = pick.one([".png", ".jpg"])
    mode = pick.one(["RGB", "L", "I;16", "RGBA", "P", "1"] if suffix == ".png" else ["RGB", "L", "CMYK"])
    pixels = (np.arange(48 * 40 * 3).reshape(40, 48, 3) * 7 % 256).astype(np.uint8)
    buffer = io.BytesIO()
    Image.fromarray(pixels).convert(mode).save(buffer, format="PNG" if suffix == ".png" else "JPEG")
    return flip_or_cut(pick, pick.one(["flip", "truncate", "none"]), buffer.getvalue()), suffix


def damaged_motion(pick) -> bytes:
    """A short AMASS motion with extreme translations or joint angles (up to 1e4 m, 1e3 rad), or one
    drawn archive damage."""
    arrays = short_motion_arrays()
    kind = pick.one(["trans", "poses", "archive", "archive"])
    if kind == "trans":
        arrays["trans"] = arrays["trans"] * pick.one([1e-6, 100.0, 1e4])
    elif kind == "poses":
        arrays["poses"] = arrays["poses"] * pick.one([10.0, 1e3])
    else:
        return damaged_archive(pick, arrays)
    return npz_bytes(arrays)


def _files(kind: str, pick) -> dict[str, bytes]:
    """A damaged input of ``kind`` (``KINDS``) drawn by ``pick``: file name -> bytes."""
    if kind == "body":
        return {"body.npz": damaged_body_npz(pick)}
    if kind == "body-pickle":
        return {"body.pkl": damaged_body_pickle(pick)}
    if kind == "garment":
        return {"garment.npz": damaged_garment(pick)}
    if kind == "motion":
        return {"motion.npz": damaged_motion(pick)}
    if kind == "image":
        raw, suffix = damaged_image(pick)
        return {f"picture{suffix}": raw}
    raise ValueError(kind)


KINDS = ("body", "body-pickle", "garment", "motion", "image")


def short_motion_arrays() -> dict[str, np.ndarray]:
    """The shipped squat's first 6 frames, as AMASS arrays."""
    arrays = npz_arrays(MOTION)
    return {k: v[:6] if v.ndim and len(v) == len(arrays["trans"]) else v for k, v in arrays.items()}


def commands(kind: str, folder: Path) -> list[list[str]]:
    """The commands (program, args...) a case of ``kind`` in ``folder`` runs: each reads the damaged
    file and, where it loads, carries it through native code (Warp meshes and solver, torch, PIL)."""
    out = str(folder / "out")
    motion = str(folder / "motion.npz")
    run = ["--frames", "1", "--settle", "0", "--quiet"]
    if kind in ("body", "body-pickle"):
        body = str(next(folder.glob("body.*")))
        return [["darts", "body", "info", "--body", body],
                ["darts", "body", "pose", motion, "--body", body, "-o", out + "-posed.npz"],
                ["darts", "template", "short-skirt", "--body", body, "--edge-length", "0.05", "-o", out + ".npz"],
                ["darts-sim", out + ".npz", motion, "--body", body, *run, "-o", out + ".usdc"]]
    if kind == "garment":
        garment = str(folder / "garment.npz")
        return [["darts", "inspect", garment], ["darts-sim", garment, motion, *run, "-o", out + ".usdc"]]
    if kind == "motion":
        return [["darts", "motion", "info", motion], ["darts", "body", "pose", motion, "-o", out + ".npz"],
                ["darts-sim", "short-skirt", motion, *run, "-o", out + ".usdc"]]
    picture = str(next(folder.glob("picture.*")))
    return [["darts", "classify", picture]]


def _main_of(program: str):
    if program == "darts":
        from darts.cli.main import main
    else:
        from sim.cli import main
    return main


def run_command(argv: list[str]) -> dict:
    """One command run in this process: its exit code and stderr lines, or the traceback that escaped it."""
    stderr = io.StringIO()
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            code = _main_of(argv[0])(argv[1:])
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    except Exception:  # noqa: BLE001 - what escapes a command's main is what the fuzz looks for
        return {"command": argv, "exit": None, "traceback": traceback.format_exc(limit=-3)}
    return {"command": argv, "exit": code, "stderr": stderr.getvalue()}


def run_case(kind: str, seed: int, folder: Path) -> list[dict]:
    """Case ``seed`` of ``kind``: its damaged file written into ``folder``, every command of it run."""
    for path in folder.iterdir():
        path.unlink()
    (folder / "motion.npz").write_bytes(npz_bytes(short_motion_arrays()))
    for name, raw in _files(kind, RandomPick(seed * 7919 + KINDS.index(kind))).items():
        (folder / name).write_bytes(raw)
    return [run_command(argv) for argv in commands(kind, folder)]


#: A kind whose case 1 crashes its process as a segfault in native code would (the harness's own test).
CRASH_PROBE = "crash-probe"


def child(kind: str, first: int, count: int) -> None:
    """Run cases ``first`` .. ``first + count - 1`` of ``kind``, a JSON line as each starts and ends."""
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(first, first + count):
            print(json.dumps({"case": seed, "started": True}), flush=True)
            if kind == CRASH_PROBE:
                if seed == 1:
                    import ctypes

                    ctypes.string_at(0)  # reads address 0: SIGSEGV
                runs = []
            else:
                runs = run_case(kind, seed, Path(tmp))
            print(json.dumps({"case": seed, "runs": runs}), flush=True)


def run_cases(kind: str, first: int, count: int, timeout: float = 900.0) -> list[dict]:
    """Cases ``first`` .. ``first + count - 1`` of ``kind`` run in child processes: one result per
    case, ``{"case", "runs"}``, or ``{"case", "signal"}`` for a case whose child a signal killed (a
    native crash; a new child takes the next case), or ``{"case", "timeout"}``."""
    results, seed, end = [], first, first + count
    deadline = time.monotonic() + timeout
    while seed < end:
        command = [sys.executable, "-m", "tests.fuzz_cases", kind, str(seed), str(end - seed)]
        try:
            proc = subprocess.run(command, capture_output=True, text=True, cwd=Path(__file__).parents[1],
                                  timeout=max(1.0, deadline - time.monotonic()))
            stdout, code, stderr = proc.stdout, proc.returncode, proc.stderr
        except subprocess.TimeoutExpired as exc:
            stdout, code, stderr = (exc.stdout or b"").decode(), None, ""
        lines = [json.loads(line) for line in stdout.splitlines() if line.startswith("{")]
        results += [line for line in lines if "runs" in line]
        if code == 0:
            break
        last = max([line["case"] for line in lines], default=seed - 1)
        failed = last if lines and "started" in lines[-1] else last + 1
        outcome = {"timeout": True} if code is None else {"signal": -code} if code < 0 else {"child_exit": code}
        results.append({"case": failed, **outcome, "stderr": stderr[-2000:]})
        if code is None:
            break
        seed = failed + 1
    return results


if __name__ == "__main__":
    child(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]))
