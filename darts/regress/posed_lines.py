"""Feature lines from a picture of a posed body (issue 32): the regressor of ``darts.regress.lines``
run in the frame of the posed body, and its answer taken back to the rest pose.

The rest-pose regressor moves the category's initial lines F_g (the default body, rest pose) to
where the picture shows them, pooling image features where each point projects. On a posed body
the starting lines are the template's on the body's own shape (``template_lines``: the template
the CRDL then deforms, built on the fitted betas; on the posed dataset's bodies, 4.2 cm from the
garments' lines against 6.2 cm for F_g), first posed the way the body's skinning poses a garment
(``darts.crdl.posed.Posing``:
each point q = M p + c, the LBS of the body at its closest rest point) with every joint rotated
but the root; the root's rotation goes into the camera instead (``darts.photo.fit.BodyFit.camera``
is that camera for a photograph), so the network always sees the body upright, facing +Z, and
the view from any side is the camera's business. The network is the same ("ours", with its
spatial transformers), trained on the posed dataset (``scripts/train_lines.py --posed``) to move
the posed template lines onto the posed truth, the garment's rest lines posed the same way.

The network sees a square crop around the garment's mask (its box widened by ``MARGIN`` on each
side), resized to ``IMAGE_SIZE``, with every pixel off the mask grey (``NEUTRAL``): the other
garment, the skin and the clutter are not the garment's evidence. The camera is cropped with it.

Its answer q' is taken back to the rest pose by inverting each point's posing: p' = M^-1 (q' - c),
with M, c first those of the initial point it came from, then once more those at p' (a point that
moved along the body, a hem lowered past the knee, takes the skinning of where it went).
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from darts.camera import IMAGE_SIZE, Camera
from darts.errors import DartsInputError
from darts.photo.crop import Crop
from darts.regress.data import CATEGORY_IDS, Samples, camera_batch, padded
from darts.templates.categories import CATEGORIES

#: the crop around the garment's mask (``Crop.around``): its box widened by this share of its side on each side
MARGIN = 0.2


def root_free(pose: np.ndarray) -> np.ndarray:
    """``pose`` [J,3] axis-angles with the root's rotation taken out (it is the camera's)."""
    pose = np.array(pose, np.float64)
    pose[0] = 0.0
    return pose


def garment_crop(image: np.ndarray, mask: np.ndarray, crop: Crop, size: int = IMAGE_SIZE) -> np.ndarray:
    """uint8 [size,size,3]: the ``crop`` of ``image`` [H,W,3], grey (``NEUTRAL``) off the garment's ``mask``."""
    from darts.regress.train import NEUTRAL

    grey = int(round(255 * NEUTRAL))
    rgb = crop.resample(np.asarray(image, np.uint8), size, fill=(grey, grey, grey))
    return np.where(mask_crop(mask, crop, size)[..., None], rgb, np.uint8(grey))


def mask_crop(mask: np.ndarray, crop: Crop, size: int = IMAGE_SIZE) -> np.ndarray:
    """bool [size,size]: the ``crop`` of ``mask`` [H,W] bool (bilinear, over half)."""
    return crop.resample(np.asarray(mask, np.uint8) * 255, size) > 127


def posing_of(body, pose: np.ndarray, betas, points: np.ndarray):
    """The ``Posing`` of rest ``points`` [...,3] by ``body`` at ``pose`` (root included as given)
    and ``betas``, over the points flattened."""
    from darts.crdl.posed import Posing

    return Posing.of(body, pose, betas, np.asarray(points, np.float64).reshape(-1, 3))


def posed(posing, points: np.ndarray) -> np.ndarray:
    """q = M p + c of rest ``points`` [...,3] (the shape kept)."""
    flat = torch.as_tensor(np.asarray(points, np.float64).reshape(-1, 3))
    return posing(flat).numpy().reshape(np.shape(points))


def unposed(body, pose: np.ndarray, betas, posing, points: np.ndarray) -> np.ndarray:
    """Rest points p' [...,3] of posed ``points`` q' (module docstring): p' = M^-1 (q' - c) with the
    ``posing`` the points came from, then again with the posing at p'."""
    q = torch.as_tensor(np.asarray(points, np.float64).reshape(-1, 3))
    p = torch.linalg.solve(posing.linear, (q - posing.offset)[..., None])[..., 0]
    again = posing_of(body, pose, betas, p.numpy())
    p = torch.linalg.solve(again.linear, (q - again.offset)[..., None])[..., 0]
    return p.numpy().reshape(np.shape(points))


def template_lines(template, category: str) -> np.ndarray:
    """The rest lines [L,K,3] of a ``template`` DART of ``category`` (its seams welded), in the
    category's line order, resampled as the dataset's (``feature_lines``)."""
    from darts.crdl.deform import weld_garment
    from darts.geometry.loops import feature_lines

    welded = weld_garment(template)
    lines = feature_lines(welded, welded.vertices)
    return np.stack([lines[name] for name in CATEGORIES[category].line_names])


@torch.no_grad()
def regress_posed_lines(image: np.ndarray, mask: np.ndarray, camera: Camera, body, pose: np.ndarray, betas,
                        category: str, start: np.ndarray) -> dict[str, np.ndarray]:
    """The rest-pose feature lines {name: [K,3]} (canonical frame, the body at ``betas``) of
    ``category`` seen in ``image`` [H,W,3] uint8 with the garment's ``mask`` [H,W] bool, the body
    at ``pose`` [J,3] (root included) seen through ``camera`` (root-free: ``BodyFit.camera``),
    starting from the template's lines ``start`` [L,K,3] (``template_lines``)."""
    from darts.regress.shipped import shipped_model
    from darts.regress.train import as_input

    model, _ = shipped_model("lines", "lines_posed")
    crop = Crop.around(mask, MARGIN)
    pose = root_free(pose)
    posing = posing_of(body, pose, betas, start)
    lines, _, creases = padded(category, posed(posing, start))
    images = torch.from_numpy(garment_crop(image, mask, crop)).permute(2, 0, 1)[None]
    out = model(as_input(images), camera_batch([crop.camera(camera, IMAGE_SIZE)]), torch.from_numpy(lines)[None],
                torch.from_numpy(creases)[None])[-1][0].numpy().astype(np.float64)
    names = CATEGORIES[category].line_names
    rest = unposed(body, pose, betas, posing, out[: len(names)])
    return {name: rest[k] for k, name in enumerate(names)}


def load_posed_split(root: str | Path, split: str, body, limit: int | None = None,
                     garments: dict[str, PosedGarment] | None = None) -> Samples:
    """The samples of a posed dataset's ``root/split`` (``darts dataset make --posed``) as the posed
    line regressor sees them (``darts.regress.posed_lines``): the garment's crop, grey off its mask;
    its camera cropped and turned by the body's root rotation; the template's lines on the body's
    shape and the truth (the garment's rest lines) posed by the body's other joints. ``body``: the
    dataset's body model; ``garments``: the ``PosedGarment`` of each garment folder seen so far
    (filled in, so that calls can share it); a sample whose garment is not in view is left out."""
    from darts.fileio import read_image

    folders = sorted(p for p in (Path(root) / split).glob("*") if (p / "image.png").is_file())[:limit]
    if not folders:
        raise DartsInputError(Path(root) / split, "holds no samples (make them with darts dataset make --posed)")
    garments = {} if garments is None else garments
    rows = {key: [] for key in ("ids", "folders", "images", "masks", "categories", "cameras", "lines", "initial",
                                "line_mask", "creases")}
    for folder in folders:
        meta = json.loads((folder / "meta.json").read_text())
        category, key = meta["category"], meta["garment_folder"]
        mask = read_image(folder / "mask.png", "L") > 127
        crop = Crop.around(mask, MARGIN)
        if crop is None:
            continue
        if key not in garments:
            garments[key] = posed_garment(Path(root) / key, category, body)
        garment = garments[key]
        camera = Camera.from_json(folder / "camera.json")
        # A root-free point y sits at R y + s in the sample frame: the camera takes that turn.
        turned = np.asarray(camera.rotation)
        camera = Camera(camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy, turned @ garment.rotation,
                        turned @ garment.shift + np.asarray(camera.translation))
        rows["ids"].append(folder.name)
        rows["folders"].append(folder)
        rows["images"].append(garment_crop(read_image(folder / "image.png"), mask, crop).transpose(2, 0, 1))
        rows["masks"].append(mask_crop(mask, crop))
        rows["categories"].append(CATEGORY_IDS.index(category))
        rows["cameras"].append(crop.camera(camera, IMAGE_SIZE))
        lines, line_mask, creases = padded(category, garment.truth)
        rows["lines"].append(lines)
        rows["initial"].append(padded(category, garment.initial)[0])
        rows["line_mask"].append(line_mask)
        rows["creases"].append(creases)
    masks = torch.from_numpy(np.stack(rows["masks"]))
    return Samples(rows["ids"], rows["folders"], torch.from_numpy(np.stack(rows["images"])), masks,
                   torch.ones_like(masks), torch.tensor(rows["categories"]), camera_batch(rows["cameras"]),
                   torch.from_numpy(np.stack(rows["lines"])), torch.from_numpy(np.stack(rows["initial"])),
                   torch.from_numpy(np.stack(rows["line_mask"])), torch.tensor(np.stack(rows["creases"])))


@dataclass
class PosedGarment:
    """One garment of a posed dataset as the posed regressor learns it: its ``pose`` [J,3]
    (root-free) and ``betas``; its ``rest`` lines and their ``truth`` posed, the ``start`` lines
    (``template_lines`` of its category on its body) and their ``initial`` posed
    and the ``posing`` that did it, all [L,K,3]; and the rigid map (``rotation``, ``shift``) from
    the root-free frame to the sample frame, y -> R y + s."""

    pose: np.ndarray
    betas: np.ndarray
    rest: np.ndarray
    start: np.ndarray
    truth: np.ndarray
    initial: np.ndarray
    posing: object
    rotation: np.ndarray
    shift: np.ndarray


def posed_garment(folder: Path, category: str, body) -> PosedGarment:
    """The ``PosedGarment`` of one posed garment's ``folder`` (at its motion frame and body shape;
    the rigid map fitted to the body's vertices: the root's rotation and the run's placement)."""
    from darts.dart.build import make_dart
    from darts.dart.io import load_dart
    from darts.geometry.loops import feature_lines
    from darts.meshimport.align import umeyama
    from darts.motion.amass import load_motion
    from darts.shipped import resolve_motion
    from darts.templates.defaults import DATASET_EASE, DATASET_EDGE_LENGTH

    meta = json.loads((folder / "meta.json").read_text())
    betas = np.asarray(meta["betas"], np.float64)
    pose = root_free(load_motion(resolve_motion(meta["motion"])).model_pose(body.num_joints)[meta["frame"]])
    dart = load_dart(folder / "garment.npz")
    lines = feature_lines(dart, dart.vertices)
    rest = np.stack([lines[name] for name in CATEGORIES[category].line_names])
    start = template_lines(make_dart(category, body, betas=betas, edge_length=DATASET_EDGE_LENGTH, ease=DATASET_EASE), category)
    posing = posing_of(body, pose, betas, start)
    free = body.to(torch.float64)(torch.as_tensor(pose)[None], torch.as_tensor(betas)[None]).vertices[0].numpy()
    with np.load(folder / "posed.npz") as data:
        sample = data["body"].astype(np.float64)
    _, rotation, shift = umeyama(free, sample, scale_range=(1.0, 1.0))
    return PosedGarment(pose, betas, rest, start, posed(posing_of(body, pose, betas, rest), rest), posed(posing, start), posing,
                        rotation, shift)
