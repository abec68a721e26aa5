"""The posed dataset (``darts dataset make --posed``, issue 32): garments simulated on a body in motion,
pictured by a free camera with the body, another garment worn with it and a cluttered background.

A **posed garment** job (``OUT_DIR/garments/<gid>/``): the recipe's garment (category, body shape,
CRDL edits: ``sim.dataset.recipe``, as the rest-pose dataset makes it) simulated on one of the
shipped motions (``POSED_MOTIONS``) from the rest pose through the 0.5 s settle and on to a frame
drawn from the motion's first ``MAX_FRAME`` + 1 (``posed_recipe``); the other garment (a top under
pants or a skirt, pants or a skirt under a top; none with a dress) is its category's template on
the same body, carried to the pose on the body's surface (``carry``). It writes ``garment.npz``
(the DART, rest pose), ``posed.npz`` and ``meta.json``. A garment whose run blew up is dropped
(status "unstable").

``posed.npz`` holds, in the **sample frame** (the body's canonical frame carried by the motion:
Y up, metres; the world frame of the run, Z up, taken back by the rest placement,
x = R_rest^T (x_world - t_rest) + o_rest, so that at the motion's start the body stands where its
rest pose does): ``garment`` [V,3] (the DART's vertices), ``garment_faces``, ``body`` [B,3],
``other`` [W,3] and ``other_faces`` (empty without one), ``joints`` [J,3] (the body's joint
regressor applied to its posed vertices) and ``lines_*`` (each feature line of the posed garment,
``LINE_POINTS`` points).

A **posed sample** job (``OUT_DIR/<split>/<gid>-<view>/``): ``image.png``, ``mask.png`` (the
garment's visible pixels), ``person_mask.png`` (body and both garments), ``other_mask.png``,
``camera.json`` (sample frame), ``keypoints.npz`` (``joints_px`` [J,2], ``joints`` [J,3],
``in_view`` [J] bool) and ``meta.json``; the camera is free (``free_camera``): any side of the
body, from a little below to well above, framing the whole body or the garment's part of it.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from darts.jobs import Job
from sim.dataset.recipe import DRAPE_SECONDS, garment_recipe, generator, recipe_garment, write_json

#: The shipped motions the poses come from.
POSED_MOTIONS = ("walk", "run", "squat", "twist", "wave", "jumping_jacks")
#: The sample is taken at most this many frames (30 fps) into the motion.
MAX_FRAME = 60
#: What is worn with a garment of each family: (categories to draw from).
OTHER_GARMENT = {"top": ("long-pants", "short-pants", "long-skirt", "short-skirt"),
                 "pants": ("long-sleeve-top", "short-sleeve-top", "sleeveless-top"),
                 "skirt": ("long-sleeve-top", "short-sleeve-top", "sleeveless-top"), "dress": ()}
POSED_SIZE = 256  # pixels, square
_POSE, POSED_LOOK = 10, 11  # generator purposes (recipe.py uses 0-4)


def posed_recipe(seed: int, index: int, family: str) -> dict:
    """The motion, frame and other garment of posed garment ``index`` (each its own generator)."""
    rng = generator(seed, index, _POSE)
    motion = POSED_MOTIONS[int(rng.integers(len(POSED_MOTIONS)))]
    frame = int(rng.integers(MAX_FRAME + 1))
    choices = OTHER_GARMENT[family]
    other = str(choices[int(rng.integers(len(choices)))]) if choices else None
    return {"motion": motion, "frame": frame, "other": other}


def to_sample_frame(track, points: np.ndarray) -> np.ndarray:
    """World points [N,3] (Z up) of ``track``'s run in the sample frame (module docstring)."""
    return (np.asarray(points, np.float64) - track.rest_translation) @ track.rest_rotation + track.rest_origin


def _frames(corners: np.ndarray) -> np.ndarray:
    """Orthonormal frames [N,3,3] (rows: first edge, the normal crossed with it, the normal) of triangles [N,3,3]."""
    edge = corners[:, 1] - corners[:, 0]
    normal = np.cross(edge, corners[:, 2] - corners[:, 0])
    edge /= np.maximum(np.linalg.norm(edge, axis=1, keepdims=True), 1e-12)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    return np.stack([edge, np.cross(normal, edge), normal], 1)


def carry(rest_body: np.ndarray, posed_body: np.ndarray, faces: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``points`` [N,3] near the rest body (vertices ``rest_body`` [B,3], ``faces``) carried to the
    posed body ``posed_body`` [B,3]: each point keeps its closest rest triangle, the barycentrics of
    its closest point there, and its offset from that point in the triangle's frame (``_frames``),
    so that a body moved rigidly moves the points with it."""
    from darts.geometry.distance import SurfaceDistance

    triangle, bary = SurfaceDistance(rest_body, faces).closest_faces(points)
    rest, posed = rest_body[faces[triangle]], posed_body[faces[triangle]]
    local = np.einsum("nij,nj->ni", _frames(rest), points - np.einsum("nk,nkd->nd", bary, rest))
    return np.einsum("nk,nkd->nd", bary, posed) + np.einsum("nij,ni->nj", _frames(posed), local)


def make_posed_garments(jobs: list[Job], folders: list[Path], device: str = "cpu") -> list[dict]:
    """Posed garment jobs (module docstring), their runs stepped together as worlds of one solver
    (``sim.worlds.simulate_grouped``, on ``device``; those of one drape solver together); each job's
    times (``simulate_s``: its group's run, wall time) and what its run measured."""
    from darts.body.io import load_body
    from darts.motion.amass import load_motion
    from darts.shipped import resolve_motion
    from darts.templates.categories import CATEGORIES
    from sim.body_track import build_body_track
    from sim.dataset.drape import DRAPE_SOLVER
    from sim.engine.settings import SimSettings
    from sim.worlds import World, simulate_grouped

    body = load_body(None)
    made, worlds = [], []
    for job in jobs:
        recipe = garment_recipe(job.inputs["seed"], job.inputs["index"], tuple(job.inputs["categories"]),
                              job.inputs["recipe"])
        family = CATEGORIES[recipe.category].family
        posed = posed_recipe(recipe.seed, recipe.index, family)
        started = time.perf_counter()
        dart, _, _ = recipe_garment(recipe, body)
        built = time.perf_counter() - started
        motion = load_motion(resolve_motion(posed["motion"]))
        frames = posed["frame"] + 1
        motion = motion.with_frames(trans=motion.trans[:frames], **{k: v[:frames] for k, v in motion.parts().items()})
        settings = SimSettings(solver=DRAPE_SOLVER[family], device=device)
        track = build_body_track(body, motion, settings.fps, DRAPE_SECONDS, betas=np.asarray(recipe.betas),
                                 gap=settings.body_gap)
        last = {}
        made.append((recipe, posed, dart, track, last, built))
        worlds.append(World(dart, track, lambda g, b, last=last: last.update(garment=g, body=b), settings))
    started = time.perf_counter()
    results = simulate_grouped(worlds)
    simulated = time.perf_counter() - started
    return [_posed_garment(body, *item, result, simulated, folder) for item, result, folder in zip(made, results, folders)]


def make_posed_garment(job: Job, folder: Path, device: str = "cpu") -> dict:
    """A posed garment job alone (``make_posed_garments`` of one)."""
    return make_posed_garments([job], [folder], device)[0]


def _posed_garment(body, recipe, posed, dart, track, last: dict, built: float, result, simulated: float,
                   folder: Path) -> dict:
    """A posed garment's files in ``folder`` from its run's last frame (``last``), and its manifest row."""
    from darts.dart.build import make_dart
    from darts.dart.io import save_dart
    from darts.fileio import save_npz
    from darts.geometry.loops import feature_lines
    from darts.templates.defaults import DATASET_EASE, DATASET_EDGE_LENGTH

    if not result.stable or "garment" not in last:
        return {"status": "unstable", "error": result.message or "no frame", "category": recipe.category,
                "split": recipe.split, "motion": posed["motion"], "frame": posed["frame"]}
    betas = np.asarray(recipe.betas)
    rest_body = body.shaped(betas[None])[0][0].double().numpy()
    posed_body = to_sample_frame(track, last["body"])
    garment = to_sample_frame(track, last["garment"])
    other, other_faces = np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    if posed["other"] is not None:
        worn = make_dart(posed["other"], body, betas=betas, edge_length=DATASET_EDGE_LENGTH, ease=DATASET_EASE)
        other, other_faces = carry(rest_body, posed_body, body.faces, np.asarray(worn.vertices, np.float64)), worn.faces
    joints = (body.J_regressor.double().numpy() @ posed_body)
    lines = feature_lines(dart, garment)
    save_dart(dart, folder / "garment.npz")
    save_npz(folder / "posed.npz", garment=garment.astype(np.float32), garment_faces=dart.faces.astype(np.int32),
             body=posed_body.astype(np.float32), other=other.astype(np.float32), other_faces=np.asarray(other_faces, np.int32),
             joints=joints.astype(np.float32), **{f"lines_{name}": p.astype(np.float32) for name, p in lines.items()},
             frame=np.array("sample frame: the body's canonical frame (Y up, metres) carried by the motion"))
    times = {"build_s": round(built, 3), "simulate_s": round(simulated, 3)}
    penetration = max((f["penetration"] for f in result.frames), default=0.0)
    meta = {**recipe.as_dict(), **posed, "vertices": len(dart.vertices), "penetration": penetration, "times": times}
    write_json(folder / "meta.json", meta)
    return {"status": "ok", "error": "", "category": recipe.category, "split": recipe.split, "vertices": len(dart.vertices),
            "motion": posed["motion"], "frame": posed["frame"], "other": posed["other"], "penetration": penetration, **times}
