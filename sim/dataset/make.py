"""The two kinds of dataset job (``darts.jobs``): make a garment, render a sample of it.

A **garment** job (``OUT_DIR/garments/<gid>/``): the category's template on the recipe's body
shape, deformed by the CRDL towards the recipe's edits, draped 0.5 s on the still body (status
"unstable", and no samples, if the drape blew up or its waist or neckline slid more than MAX_DROP
down the body: a deterministic outcome, kept and not made again); it writes
``garment.npz`` (the DART before the drape), ``draped.npz`` (``vertices`` [V,3] float32 canonical
frame, ``faces`` [F,3]: the DART's own mesh after the drape), ``lines.npz`` (each feature line of the
draped garment, LINE_POINTS points evenly spaced along its arc) and ``meta.json``.

A **sample** job (``OUT_DIR/<split>/<gid>-<view>/``): one picture of a finished garment, with
``image.png``, ``mask.png`` (garment, 0/255), ``body_mask.png``, ``camera.json``, ``lines.npz``
(canonical frame, the CRDL's ``--lines`` format), ``lines_px.npz`` (the same points projected: [K,2]
pixel (u, v) per line), ``garment.npz``, ``draped.npz`` (hard links to the garment's files) and
``meta.json``.
"""
from __future__ import annotations

import json
import os
import shutil
import time
from functools import lru_cache
from pathlib import Path

import numpy as np

from darts.geometry.loops import feature_lines
from darts.jobs import Job
from sim.dataset.recipe import DRAPE_SECONDS, garment_recipe, generator, recipe_garment, write_json

GARMENTS = "garments"
_RENDER = 4  # the generator purpose of a picture's appearance
#: A garment whose waist (skirts, pants) or neckline sits lower than this after the drape (m) has
#: slid off the body: it is not a sample. (A waistband that starts with the template's 6 mm of
#: ease settles 3-8 cm lower, on the hips: that is kept.)
MAX_DROP = 0.10
#: A mesh hides a line point when the ray to it hits the mesh this far (m) before the point or more
#: (the point lies on the garment's edge: nearer hits are its own faces).
HIDDEN_BY = 0.005


@lru_cache(maxsize=1)
def _body():
    from darts.body.io import load_body

    return load_body(None)


def make_garments(jobs: list[Job], folders: list[Path], device: str = "cpu") -> list[dict]:
    """Garment jobs (module docstring), their drapes stepped together as worlds of one solver
    (``sim.dataset.drape.drape_many``, on ``device``); each job's times of each stage and what its
    drape measured (``drape_s``: the whole group's drape, wall time)."""
    from darts.dart.io import save_dart
    from darts.fileio import save_npz
    from darts.templates.categories import CATEGORIES
    from sim.dataset.drape import drape_many

    body = _body()
    recipes = [garment_recipe(job.inputs["seed"], job.inputs["index"], tuple(job.inputs["categories"]),
                              job.inputs["recipe"]) for job in jobs]
    built = [recipe_garment(recipe, body) for recipe in recipes]
    drapes = drape_many([(dart, body, CATEGORIES[recipe.category].family) for recipe, (dart, _, _) in zip(recipes, built)],
                        DRAPE_SECONDS, device=device)
    rows = []
    for recipe, (dart, report, times), draped, folder in zip(recipes, built, drapes, folders):
        lines = feature_lines(dart, draped.vertices)
        top = "waist" if "waist" in dart.lines else "neckline"
        drop = float(np.asarray(dart.vertices, np.float64)[dart.lines[top], 1].mean()
                     - draped.vertices[dart.lines[top], 1].mean())
        save_dart(dart, folder / "garment.npz")
        save_npz(folder / "draped.npz", vertices=draped.vertices.astype(np.float32), faces=dart.faces.astype(np.int32),
                 frame=np.array("canonical: Y up, front +Z, metres"))
        save_npz(folder / "lines.npz", **{name: points.astype(np.float32) for name, points in lines.items()})
        times["drape_s"] = round(draped.seconds, 3)
        meta = {**recipe.as_dict(), "vertices": len(dart.vertices),
                "crdl": {k: report[k] for k in ("arap_energy", "handle_rmse", "penetration", "iterations")},
                "drape": {"seconds": DRAPE_SECONDS, "stable": draped.stable, "max_penetration": draped.max_penetration,
                          "message": draped.message}, "times": times}
        write_json(folder / "meta.json", meta)
        slid = (f"the {top} slid {100 * drop:.1f} cm down in the drape (at most {100 * MAX_DROP:.0f} cm)"
                if drop > MAX_DROP else "")
        rows.append({"status": "ok" if draped.stable and not slid else "unstable", "error": draped.message or slid,
                     "category": recipe.category, "split": recipe.split, "vertices": len(dart.vertices),
                     "drape_penetration": draped.max_penetration, "drape_drop": drop,
                     "crdl_handle_rmse": report["handle_rmse"], **times})
    return rows


def make_garment(job: Job, folder: Path, device: str = "cpu") -> dict:
    """A garment job alone (``make_garments`` of one)."""
    return make_garments([job], [folder], device)[0]


def line_mask_distances(pixels: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distance to the mask's boundary [N], distance to the mask [N], 0 inside it), in pixels, of
    image points ``pixels`` [N,2] (u, v), each taken at the centre of the pixel it falls in."""
    from scipy import ndimage

    boundary = mask & ~ndimage.binary_erosion(mask, border_value=0)
    to_boundary = ndimage.distance_transform_edt(~boundary)
    to_mask = ndimage.distance_transform_edt(~mask)
    h, w = mask.shape
    col = np.clip(np.floor(pixels[:, 0]).astype(int), 0, w - 1)
    row = np.clip(np.floor(pixels[:, 1]).astype(int), 0, h - 1)
    outside = (pixels[:, 0] < 0) | (pixels[:, 0] >= w) | (pixels[:, 1] < 0) | (pixels[:, 1] >= h)
    extra = np.where(outside, np.maximum.reduce([-pixels[:, 0], pixels[:, 0] - w, -pixels[:, 1], pixels[:, 1] - h,
                                                 np.zeros(len(pixels))]), 0)
    return to_boundary[row, col] + extra, to_mask[row, col] + extra


def hidden_by(points: np.ndarray, eye: np.ndarray, *meshes) -> np.ndarray:
    """For each point [N,3]: the index of the first of ``meshes`` that hides it from ``eye`` (a hit
    more than HIDDEN_BY m before it on the ray from the eye), or -1 if it is in view."""
    from darts.raycast import cast_rays

    offset = points - eye
    distance = np.linalg.norm(offset, axis=1)
    return cast_rays(list(meshes), eye, offset / distance[:, None], distance - HIDDEN_BY).which


def _link(source: Path, target: Path) -> None:
    try:
        os.link(source, target)
    except OSError:  # another file system, or one without hard links
        shutil.copyfile(source, target)


def render_sample(job: Job, folder: Path) -> dict:
    """A sample job (module docstring); returns the render time and how the lines sit on the mask."""
    from PIL import Image

    from darts.fileio import read_npz, save_npz
    from sim.dataset.appearance import sample_appearance
    from sim.dataset.render import render

    source = folder.parent.parent / job.inputs["garment_folder"]  # folder: OUT_DIR/<split>/<temporary>
    unseen = job.inputs["split"] == "test_unseen"
    meta = json.loads((source / "meta.json").read_text())
    started = time.perf_counter()
    rng = generator(meta["seed"], meta["index"], _RENDER, 2 * job.inputs["view"] + unseen)
    look = sample_appearance(rng, meta["category"], unseen)
    body = _body()
    draped = read_npz(source / "draped.npz")
    body_vertices = body.shaped(np.asarray(meta["betas"]))[0][0].double().numpy()
    picture = render((draped["vertices"], draped["faces"]), (body_vertices, body.faces), look, rng, unseen)
    rendered = time.perf_counter() - started
    lines = read_npz(source / "lines.npz")
    pixels = {name: look.camera.project(points.astype(np.float64))[0] for name, points in lines.items()}
    to_boundary, to_mask = line_mask_distances(np.concatenate(list(pixels.values())), picture.garment_mask)
    behind_body = hidden_by(np.concatenate(list(lines.values())).astype(np.float64), look.camera.centre,
                            (body_vertices, body.faces), (draped["vertices"], draped["faces"])) == 0
    Image.fromarray(picture.image).save(folder / "image.png")
    Image.fromarray(picture.garment_mask.astype(np.uint8) * 255).save(folder / "mask.png")
    Image.fromarray(picture.body_mask.astype(np.uint8) * 255).save(folder / "body_mask.png")
    write_json(folder / "camera.json", look.camera.as_dict())
    save_npz(folder / "lines_px.npz", **{name: p.astype(np.float32) for name, p in pixels.items()})
    for name in ("lines.npz", "garment.npz", "draped.npz"):
        _link(source / name, folder / name)
    write_json(folder / "meta.json", {**{k: meta[k] for k in ("seed", "index", "id", "category", "betas", "edits")},
                                       "split": job.inputs["split"], "view": job.inputs["view"],
                                       "appearance": look.as_dict(), "render_s": round(rendered, 3)})
    return {"category": meta["category"], "garment": meta["id"], "render_s": round(rendered, 3),
            "line_boundary_median_px": float(np.median(to_boundary)),
            "line_off_mask_max_px": float(to_mask[~behind_body].max(initial=0.0)),
            "line_behind_body": float(behind_body.mean())}
