"""Bad arguments for the Python API's fuzzing: each case takes one public function's call that
works (``calls``: cheap inputs, a two-frame motion, a coarse garment), replaces one argument by a
drawn wrong value (``WRONG``: wrong types, NaN, infinities, huge numbers, empty and odd strings,
paths that are not there, nested lists, arrays of text ...) and calls it. The contract
(``call_case``): it returns, or raises ``DartsInputError`` in one line — never another exception.
Each case runs in a fresh scratch working directory, since a wrong value may be a valid output path
(and a file written there would shadow a shipped name in the next case).
"""
from __future__ import annotations

import contextlib
import functools
import tempfile
import traceback
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError
from scenes import MOTIONS_DIR

#: Wrong values drawn for an argument (some happen to be valid for some arguments: then the call runs).
WRONG = [
    None, True, False, 0, -1, 7, 2.5, -0.5, float("nan"), float("inf"), -float("inf"), 1e300, 10 ** 30, 1j,
    "", " ", "x", "walk", "short-skirt", "upper", "all=loose", "hem=0.1", "/nonexistent/file.npz", "/", "/dev/null",
    "a.usdc", "out/", b"bytes", [], [1.0], [0.5, -0.5], ["a"], [[1.0, 2.0]], [None], (1, 2, 3), {}, {"a": 1},
    {"substeps": 0}, set(), object(), np.zeros(0), np.zeros((2, 2)), np.zeros((4, 4, 3), np.uint8), np.array(["a"]),
    np.float32(0.02), np.int64(3), np.full(3, np.nan), Path("."), Path("missing.npz"), print, Ellipsis,
]


@functools.cache
def _objects() -> dict:
    """The valid inputs the baseline calls share (made once)."""
    import darts

    motion = darts.load_motion("walk")
    short = motion.with_frames(trans=motion.trans[:2], **{k: v[:2] for k, v in motion.parts().items()})
    return {"body": darts.load_body(), "short": short, "coarse": darts.template("short-skirt", edge_length=0.05),
            "tiny": np.full((32, 32, 3), 128, np.uint8), "mask": np.ones((32, 32), bool)}


def calls() -> dict[str, tuple]:
    """Every public API function fuzzed: name -> (callable, the keyword arguments of a call that works)."""
    import darts
    import darts.body
    import darts.motion
    import sim
    from darts.body.io import read_body

    o = _objects()
    run = dict(frames=1, settle=0.0, start=0, end=None, body=None, betas=None, material=None, seams=(), output=None,
               format="obj", seam_curves=False, stats=None, preview=None, winding=None, measure_every=10)
    pictures = dict(body=None, betas=None, edge_length=0.02, progress=False, silhouette="outline",
                    silhouette_weight=None, lengths=False)
    return {
        "darts.load_body": (darts.load_body, {"body": None}),
        "darts.load_motion": (darts.load_motion, {"motion": "walk", "fps": None}),
        "darts.load_garment": (darts.load_garment, {"garment": "short-skirt"}),
        "darts.save_garment": (darts.save_garment, {"garment": o["coarse"], "path": "out.npz"}),
        "darts.pose": (darts.pose, {"motion": o["short"], "body": None, "betas": None, "ground": False, "progress": False}),
        "darts.template": (darts.template, {"category": "short-skirt", "body": None, "betas": None, "edge_length": 0.05,
                                            "seams": (), "accessories": (), "material": "cotton"}),
        "darts.deform": (darts.deform, {"garment": o["coarse"], "lines": None, "edits": ["hem=0.05"], "body": None,
                                        "mask": None, "camera": None, "solver": "local-global",
                                        "silhouette_weight": None, "progress": False, "silhouette": "outline"}),
        "darts.classify": (darts.classify, {"image": o["tiny"], "mask": o["mask"]}),
        "darts.read_outfit": (darts.read_outfit, {"image": o["tiny"], "body": None}),
        "darts.reconstruct": (darts.reconstruct, {"image": o["tiny"], "category": None, "camera": None, "mask": None,
                                                  "accept_low_confidence": False, "garment": None, **pictures}),
        "darts.reconstruct_outfit": (darts.reconstruct_outfit, {"image": o["tiny"], "garments": None, **pictures}),
        "darts.body.read_body": (read_body, {"path": None}),
        "darts.body.export_smpl_npz": (darts.body.export_smpl_npz, {"body": read_body(), "path": "b.npz", "betas": None}),
        "darts.motion.load_motion": (darts.motion.load_motion, {"path": MOTIONS_DIR / "walk.npz"}),
        "darts.motion.save_motion": (darts.motion.save_motion, {"motion": o["short"], "path": "m.npz"}),
        "darts.motion.resample": (darts.motion.resample, {"motion": o["short"], "fps": 60.0}),
        "darts.motion.pose_sequence": (darts.motion.pose_sequence, {"model": o["body"], "motion": o["short"],
                                                                    "betas": None, "ground": False, "chunk": 64,
                                                                    "progress": False}),
        "sim.simulate": (sim.simulate, {"garment": o["coarse"], "motion": o["short"], "settings": None,
                                        "keep_frames": True, "progress": False, **run}),
        "sim.SimSettings": (sim.SimSettings, {"fps": 30.0, "substeps": None, "iterations": 2, "solver": "xpbd",
                                              "device": "cpu", "wind": (0.0, 0.0, 0.0), "gust": 0.0, "ground": True,
                                              "max_speed": 50.0, "self_contact": True, "seed": 0, "damping": 0.1}),
        "sim.SimJob.from_dict": (lambda **values: sim.SimJob.from_dict(values),
                                 {"garment": "short-skirt", "motion": "walk", "settings": {"substeps": 4}, **run}),
        "sim.run_job": (sim.run_job, {"job": sim.SimJob(o["coarse"], o["short"], frames=1, settle=0.0),
                                      "keep_frames": True, "progress": False}),
    }


def call_case(pick) -> dict:
    """One case: a drawn function called with one drawn argument replaced by a drawn wrong value.
    Returns {"function", "argument", "value", "outcome": "returned" | "input error" | "bare", ...}."""
    table = calls()
    name = pick.one(sorted(table))
    function, arguments = table[name]
    argument = pick.one(sorted(arguments))
    value = pick.one(WRONG)
    case = {"function": name, "argument": argument, "value": repr(value)[:60]}
    try:
        with tempfile.TemporaryDirectory() as scratch, contextlib.chdir(scratch):
            function(**{**arguments, argument: value})
    except DartsInputError as exc:
        return {**case, "outcome": "input error", "message": str(exc), "one_line": "\n" not in str(exc)}
    except Exception as exc:  # noqa: BLE001 - anything else escaping the API is what the fuzz looks for
        return {**case, "outcome": "bare", "error": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc(limit=-3)}
    return {**case, "outcome": "returned"}
