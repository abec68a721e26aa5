"""A picture of a posed garment (``sim.dataset.posed``): a free camera, a cluttered background, the
body with the garment and the other garment worn with it. Everything in the sample frame (Y up,
metres).

- **Camera** (``free_camera``): it looks at the middle of what it frames from any side (yaw
  uniform over the full turn about the vertical), from 10 degrees below to 30 above, 2-4 m away,
  the framed extent filling 60-90 % of the picture; it frames the whole body (70 %) or the
  garment's part of it with the head (30 %: tops, dresses from the head down to the garment's
  lowest point; pants, skirts from the head to the feet, the same as the whole body).
- **Background** (``clutter``): a two-colour gradient under 8-24 shapes (rectangles, discs,
  stripes) of random colours, sizes and places, blurred by a random amount.
- **Cloth**: the garment in the seen range of ``sim.dataset.appearance`` (colours and prints);
  the other garment in another draw of it; skin tones likewise.
- **Light** (``light_towards``): 20-60 degrees up, within 40 degrees of the camera's side.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from darts.camera import Camera
from darts.jobs import Job
from sim.dataset.appearance import direction
from sim.dataset.posed import POSED_LOOK, POSED_SIZE
from sim.dataset.recipe import generator

FULL_BODY = 0.7


def free_camera(rng: np.random.Generator, body: np.ndarray, garment: np.ndarray, family: str, size: int) -> Camera:
    """A free camera (module docstring) for a body [B,3] wearing ``garment`` [V,3]."""
    if rng.uniform() < FULL_BODY or family in ("pants", "skirt"):
        low, high = body.min(0), body.max(0)
    else:
        low = np.minimum(body[body[:, 1] > garment[:, 1].min()].min(0), garment.min(0))
        high = body.max(0)
    target = (low + high) / 2
    extent = float(np.max(high - low))
    yaw = rng.uniform(-np.pi, np.pi)
    pitch = np.deg2rad(rng.uniform(-10, 30))
    distance = rng.uniform(2.0, 4.0)
    eye = target + distance * direction(yaw, pitch)
    focal = size * rng.uniform(0.6, 0.9) * distance / extent
    return Camera.look_at(eye, target, size, size, focal)


def light_towards(rng: np.random.Generator, camera: Camera, target: np.ndarray) -> np.ndarray:
    """A unit direction towards the light (module docstring), seen from ``target``."""
    view = camera.centre - target
    yaw = np.arctan2(view[0], view[2]) + np.deg2rad(rng.uniform(-40, 40))
    up = np.deg2rad(rng.uniform(20, 60))
    return direction(yaw, up)


def clutter(rng: np.random.Generator, size: int) -> np.ndarray:
    """A cluttered background [size, size, 3] in [0, 1] (module docstring)."""
    from PIL import Image, ImageDraw, ImageFilter

    top, bottom = rng.uniform(0, 1, 3), rng.uniform(0, 1, 3)
    t = np.linspace(0, 1, size)[:, None, None]
    base = np.broadcast_to((1 - t) * top + t * bottom, (size, size, 3))
    picture = Image.fromarray((base * 255).astype(np.uint8))
    draw = ImageDraw.Draw(picture)
    for _ in range(int(rng.integers(8, 25))):
        colour = tuple(int(c) for c in rng.integers(0, 256, 3))
        x0, y0 = rng.uniform(-0.2, 1.0, 2) * size
        w, h = rng.uniform(0.05, 0.6, 2) * size
        kind = rng.integers(3)
        if kind == 0:
            draw.rectangle([x0, y0, x0 + w, y0 + h], fill=colour)
        elif kind == 1:
            draw.ellipse([x0, y0, x0 + w, y0 + w], fill=colour)
        else:
            for k in range(int(rng.integers(3, 8))):
                draw.rectangle([x0 + k * w / 4, y0, x0 + k * w / 4 + w / 10, y0 + h], fill=colour)
    picture = picture.filter(ImageFilter.GaussianBlur(float(rng.uniform(0, 2.5))))
    return np.asarray(picture, np.float64) / 255.0


def render_posed_sample(job: Job, folder: Path) -> dict:
    """A posed sample job (``sim.dataset.posed``); returns the render time and what is in view."""
    from PIL import Image

    from darts.body.io import load_body
    from darts.fileio import read_npz, save_npz
    from darts.templates.categories import CATEGORIES
    from sim.dataset.appearance import sample_appearance
    from sim.dataset.render import SceneMesh, cloth, render_scene, skin

    source = folder.parent.parent / job.inputs["garment_folder"]
    meta = json.loads((source / "meta.json").read_text())
    scene = read_npz(source / "posed.npz")
    started = time.perf_counter()
    rng = generator(meta["seed"], meta["index"], POSED_LOOK, job.inputs["view"])
    family = CATEGORIES[meta["category"]].family
    camera = free_camera(rng, scene["body"], scene["garment"], family, POSED_SIZE)
    look = sample_appearance(rng, meta["category"], False)
    worn = sample_appearance(rng, meta["other"] or meta["category"], False)
    body = load_body(None)
    meshes = [SceneMesh(scene["body"], body.faces, skin(look.skin), specular=0.04),
              SceneMesh(scene["garment"], scene["garment_faces"], cloth(look))]
    if len(scene["other"]):
        meshes.append(SceneMesh(scene["other"], scene["other_faces"], cloth(worn)))
    light = light_towards(rng, camera, scene["body"].mean(0))
    image, masks = render_scene(camera, meshes, clutter(rng, POSED_SIZE), light, look.noise, rng)
    rendered = time.perf_counter() - started
    body_mask, garment_mask = masks[0], masks[1]
    other_mask = masks[2] if len(masks) > 2 else np.zeros_like(garment_mask)
    joints = scene["joints"].astype(np.float64)
    pixels, depth = camera.project(joints)
    in_view = (depth > 0) & (pixels >= 0).all(1) & (pixels < POSED_SIZE).all(1)
    Image.fromarray(image).save(folder / "image.png")
    for name, mask in (("mask", garment_mask), ("person_mask", body_mask | garment_mask | other_mask),
                       ("other_mask", other_mask)):
        Image.fromarray(mask.astype(np.uint8) * 255).save(folder / f"{name}.png")
    (folder / "camera.json").write_text(json.dumps(camera.as_dict(), indent=1))
    save_npz(folder / "keypoints.npz", joints_px=pixels.astype(np.float32), joints=joints.astype(np.float32), in_view=in_view)
    sample = {k: meta[k] for k in ("seed", "index", "id", "category", "betas", "edits", "motion", "frame", "other")}
    (folder / "meta.json").write_text(json.dumps({**sample, "split": job.inputs["split"], "view": job.inputs["view"],
                                                  "garment_folder": job.inputs["garment_folder"],
                                                  "appearance": look.as_dict(), "render_s": round(rendered, 3)}, indent=1))
    return {"category": meta["category"], "garment": meta["id"], "render_s": round(rendered, 3),
            "garment_pixels": int(garment_mask.sum()), "joints_in_view": float(in_view.mean())}
