"""The library entry points of ``darts`` (``docs/api.md``): bodies, motions and garments loaded by
path or shipped name, templates built, garments deformed and reconstructed, as the commands do.

Every function takes a path, a shipped name or the object itself, validates it once (a
``DartsInputError`` naming the file and the problem; an argument of the wrong type or out of range
raises one naming the argument, ``darts.arguments``), and returns plain objects and numpy arrays:
``BodyModel``, ``Motion``, ``Dart``. Frames: garments and bodies at rest are in the canonical frame
(Y up); posed bodies are in the AMASS world frame (Z up); metres throughout. Simulation is
``sim.simulate`` (``darts`` itself never imports the simulator).
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from darts import arguments as check
from darts.errors import DartsInputError
from darts.shipped import resolve_garment, resolve_motion
from darts.templates.defaults import DATASET_EDGE_LENGTH, DEFAULT_EDGE_LENGTH, EASE_RANGE, EDGE_LENGTH_RANGE

PathLike = str | os.PathLike


def load_body(body=None):
    """The SMPL-format ``BodyModel`` in the file ``body`` (official SMPL/SMPL-H/SMPL-X .pkl/.npz),
    the bundled default body when None, or ``body`` itself when it is one."""
    from darts.body.io import load_body as load
    from darts.body.model import BodyModel

    if body is None:
        return load(None)
    check.path_or(body, "body", (BodyModel,), "None, a path or a BodyModel")
    return body if isinstance(body, BodyModel) else load(body)


def load_motion(motion, fps: float | None = None):
    """The AMASS-format ``Motion`` of a ``.npz`` path or a shipped name (``walk``, ``squat`` ...),
    resampled to ``fps`` when given."""
    from darts.motion.amass import FPS_RANGE, Motion
    from darts.motion.amass import load_motion as load
    from darts.motion.resampling import resample

    check.path_or(motion, "motion", (Motion,), "a path, a shipped motion's name or a Motion")
    fps = check.optional_number(fps, "fps", *FPS_RANGE)
    motion = motion if isinstance(motion, Motion) else load(resolve_motion(motion))
    if fps is not None and abs(motion.fps - fps) > 1e-9:
        motion = resample(motion, fps)
    return motion


def load_garment(garment):
    """The ``Dart`` in a ``garment.npz`` path or of a shipped name (``short-sleeve-top`` ...)."""
    from darts.dart.io import load_dart
    from darts.dart.model import Dart

    check.path_or(garment, "garment", (Dart,), "a path, a shipped garment's name or a Dart")
    return garment if isinstance(garment, Dart) else load_dart(resolve_garment(garment))


def save_garment(garment, path: PathLike) -> Path:
    """Write ``garment`` (a ``Dart``) to ``path`` (``.npz``; checked, written atomically)."""
    from darts.dart.io import save_dart
    from darts.dart.model import Dart
    from darts.fileio import check_output

    if not isinstance(garment, Dart):
        raise check.refuse("garment", "a Dart", garment)
    path = check.path_or(path, "path")
    path = check_output(path, (".npz",))
    save_dart(garment, path)
    return path


def pose(motion, body=None, betas: Sequence[float] | None = None, ground: bool = False,
         progress: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The body posed by ``motion``: vertices [F,V,3] and joints [F,J,3] (float32, world frame, Z
    up, metres); ``betas`` the shape, [K] or one per frame [F,K] (default: the motion's own, else the mean shape); ``ground``
    shifts the sequence so that its lowest point touches z = 0."""
    from darts.motion.posing import pose_sequence

    return pose_sequence(load_body(body), load_motion(motion), betas=betas, ground=ground, progress=progress)


def template(category: str, body=None, betas: Sequence[float] | None = None, edge_length: float = DEFAULT_EDGE_LENGTH,
             seams: Sequence[str] = (), accessories: Sequence[str] = (), material: str = "cotton",
             seat_ease: float | None = None, ease: float | None = None):
    """The DART of ``category`` (``darts.templates.categories.CATEGORIES``) cut from the body shaped
    by ``betas``: target edge length in metres, seam settings ``NAME=REGIME[:STIFFNESS]`` (NAME
    ``all`` for every seam), accessories (``collar``, ``tie``), a material name, the ease in metres
    (the cloth's distance off the body; None: the category's, ``WEARING_EASE`` for tops and
    dresses, ``DEFAULT_EASE`` for skirts and trousers) and, for trousers, the ease below the
    waistband in metres (None: the sitting allowance, ``SEAT_EASE``; 0.006 cuts them as close as a
    skirt)."""
    from darts.dart.build import make_dart
    from darts.dart.model import parse_seam_setting
    from darts.templates.categories import CATEGORIES

    check.text(category, "category", CATEGORIES)
    edge_length = check.number(edge_length, "edge_length", *EDGE_LENGTH_RANGE)
    settings = [parse_seam_setting(text) for text in check.text_list(seams, "seams", "all=loose")]
    accessories = check.text_list(accessories, "accessories", "collar")
    check.text(material, "material")
    if seat_ease is not None:
        seat_ease = check.number(seat_ease, "seat_ease", *EASE_RANGE)  # trousers only: build_template refuses others
    if ease is not None:
        ease = check.number(ease, "ease", *EASE_RANGE)
    return make_dart(category, _body_for(body, betas), betas, edge_length, settings, list(accessories), material,
                     seat_ease, ease)


def deform(garment, lines=None, edits: Sequence[str] = (), body=None, mask=None, camera=None,
           solver: str = "local-global", silhouette_weight: float | None = None, progress: bool = False,
           silhouette: str = "outline"):
    """``garment`` deformed by the CRDL so that its feature lines reach targets: ``lines`` (a
    ``lines.npz`` path, or a dict of line name -> [K,3] loop, canonical frame, metres) or ``edits``
    (``NAME=METRES``: ``hem=0.1`` lengthens the hem 10 cm; names in ``darts.crdl.targets.EDITS``).
    With ``mask`` (a path or [H,W] bool) and ``camera`` (a ``Camera`` or a camera.json) the
    silhouette term ``silhouette`` (``darts.crdl.SILHOUETTE_WEIGHTS``) joins, at ``silhouette_weight``
    (default: the term's). Returns (the deformed ``Dart``, its report: arap_energy, handle_rmse (m),
    penetration (fraction of vertices inside the body), iterations, wall_seconds)."""
    from darts.camera import Camera
    from darts.crdl import SILHOUETTE_WEIGHTS, SOLVERS, check_silhouette
    from darts.crdl.deform import deform_dart, weld_garment
    from darts.crdl.layer import CrdlWeights
    from darts.crdl.silhouette import read_mask, silhouette_term
    from darts.crdl.targets import edit_targets, parse_edit, read_target_lines, target_lines
    from darts.templates.defaults import DEFAULT_EASE

    edits = check.text_list(edits, "edits", "hem=0.1")
    if lines is not None and not isinstance(lines, dict):
        check.path_or(lines, "lines", what="None, a lines.npz path or a dict of line name -> [K,3] loop")
    if (lines is None) == (not edits):
        raise DartsInputError(None, "deform needs either target lines or one or more edits NAME=METRES")
    if (mask is None) != (camera is None):
        raise DartsInputError(None, "a mask and its camera go together")
    check.text(solver, "solver", SOLVERS)
    silhouette_weight = check.optional_number(silhouette_weight, "silhouette_weight", 0.0)
    progress = check.switch(progress, "progress")
    check_silhouette(check.text(silhouette, "silhouette"))
    dart = load_garment(garment)
    model = load_body(body)
    if model.name != dart.body_model:
        raise DartsInputError(garment if isinstance(garment, (str, os.PathLike)) else None,
                              f"was made for the body '{dart.body_model}', not '{model.name}' (pass that body)")
    term = None
    if mask is not None:
        camera = camera if isinstance(camera, Camera) else Camera.from_json(
            check.path_or(camera, "camera", (Camera,), "a Camera or a camera.json path"))
        if not isinstance(mask, np.ndarray):
            mask = read_mask(check.path_or(mask, "mask", what="a mask picture's path or an [H,W] bool array"),
                             camera.width, camera.height)
        elif mask.shape != (camera.height, camera.width):
            raise DartsInputError(None, f"the mask is {_size(mask.shape)}, the camera's picture {camera.width}x{camera.height}")
        elif not mask.any():
            raise DartsInputError(None, "the mask is empty (no garment pixel)")
        term = silhouette_term(silhouette, np.asarray(mask, bool), camera)
    if lines is not None:
        names = list(dart.lines)
        targets = (target_lines(lines, dart.category, names) if isinstance(lines, dict)
                   else read_target_lines(lines, dart.category, names))
        clearance = None
    else:
        welded = weld_garment(dart)
        targets = edit_targets(dart.category, welded.vertices, welded.lines, [parse_edit(text) for text in edits])
        clearance = DEFAULT_EASE
    weight = SILHOUETTE_WEIGHTS[silhouette] if silhouette_weight is None else silhouette_weight
    weights = CrdlWeights(silhouette=weight if term is not None else 0.0)
    return deform_dart(dart, model, targets, solver, weights, term, clearance=clearance, progress=progress)


def read_picture(image):
    """An RGB picture [H,W,3] uint8 from a path (PNG/JPEG; refused when not an image or too large)
    or an array."""
    from darts.fileio import read_image

    if isinstance(image, np.ndarray):
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise DartsInputError(None, f"an image array must be [H,W,3] uint8, got {image.shape} {image.dtype}")
        return image
    return read_image(check.path_or(image, "image", what="a picture's path or an [H,W,3] uint8 array"))


def classify(image, mask=None) -> list[tuple[str, float]]:
    """The garment categories of ``image`` (a path or [H,W,3] uint8) with their probabilities, most
    likely first; ``mask`` (a path or [H,W] bool) shows the classifier the garment alone. Without a
    mask the picture is a photograph (``read_outfit``): the categories of its outer garment (the top
    or the dress). A picture too small, blurred or blank, or a photograph without a person, raises
    ``DartsInputError``."""
    from darts.regress.checks import picture_problem
    from darts.regress.pipeline import classify_image

    picture = read_picture(image)
    garment_mask = _picture_mask(mask, picture)
    if garment_mask is None:
        outfit = _read_outfit(image, picture, load_body(None))
        return outfit.garments[-1].ranked if outfit.garments else []
    _refuse(image, picture_problem(picture, garment_mask))
    return classify_image(picture, garment_mask)


def read_outfit(image, body=None):
    """Every garment the person in the photograph ``image`` (a path or [H,W,3] uint8) wears
    (``darts.photo.outfit.PhotoOutfit``: ``.garments``, inner layer first, each with its kind, category,
    probabilities and the attributes measured; ``.notes``; ``.mask(kind)``), on the body ``body``
    (default: the bundled one) fitted to the person. A picture too small, blurred or blank, or
    without a person, raises ``DartsInputError``."""
    return _read_outfit(image, read_picture(image), load_body(body))


def _read_outfit(image, picture: np.ndarray, model):
    """``read_outfit`` of ``picture`` (read from ``image``, which names it in errors) on ``model``."""
    from darts.photo.fit import fit_body
    from darts.photo.outfit import read_outfit as read
    from darts.photo.person import find_person
    from darts.regress.checks import person_problem, picture_problem

    _refuse(image, picture_problem(picture, None))
    person = find_person(picture)
    if person is None:
        _refuse(image, person_problem(given_alone="give --mask for a picture of a garment alone"))
    outfit = read(picture, person, fit_body(person, model, picture.shape[1], picture.shape[0]), model)
    if outfit is None:
        _refuse(image, person_problem(given_alone="give --mask for a picture of a garment alone"))
    return outfit


def reconstruct_outfit(image, body=None, garments: Sequence[str] | None = None, betas: Sequence[float] | None = None,
                       edge_length: float = DATASET_EDGE_LENGTH, progress: bool = False, silhouette: str = "outline",
                       silhouette_weight: float | None = None, lengths: bool = False):
    """Every garment the person in the photograph ``image`` (a path or [H,W,3] uint8) wears, each a
    DART fitted through the pose to its own parsed mask on the body fitted once to the person
    (``garments``: only these kinds, of upper, lower, dress). Returns an ``OutfitReconstruction``:
    ``.outfit`` (what was read, ``read_outfit``), ``.garments`` (a ``Reconstruction`` each, inner
    layer first; one whose category is unsure, under 50 %, takes the most likely and its report
    says ``low_confidence``) and ``.save(folder)`` (the outfit folder ``darts-sim`` runs). A picture that is too
    small, blurred or blank, without a person or without such a garment raises ``DartsInputError``."""
    from darts.photo.outfit import KINDS
    from darts.regress.pipeline import reconstruct_outfit as run

    garments = None if garments is None else check.text_list(garments, "garments", "upper")
    lengths, progress = check.switch(lengths, "lengths"), check.switch(progress, "progress")
    silhouette_weight = check.optional_number(silhouette_weight, "silhouette_weight", 0.0)
    wrong = [g for g in garments or [] if g not in KINDS]
    if wrong:
        raise DartsInputError(None, f"garments must be of {', '.join(KINDS)}, got {', '.join(map(repr, wrong))}")
    _check_fit_options(silhouette, edge_length)
    picture = read_picture(image)
    model = _body_for(body, betas)
    with _errors_named_after(image):
        return run(picture, model, list(garments) if garments else None, betas=betas, edge_length=edge_length,
                   progress=progress, silhouette_term=silhouette, silhouette_weight=silhouette_weight,
                   lengths=lengths)


def _check_fit_options(silhouette: str, edge_length: float) -> None:
    """The silhouette term's name and the template's edge length of a reconstruction, checked."""
    from darts.crdl import check_silhouette

    check_silhouette(check.text(silhouette, "silhouette"))
    check.number(edge_length, "edge_length", *EDGE_LENGTH_RANGE)


def _body_for(body, betas):
    """The ``BodyModel`` of ``body``, checked to have room for ``betas`` (a list of numbers)."""
    model = load_body(body)
    if betas is not None:
        check.betas(betas, model.num_betas)
    return model


@contextmanager
def _errors_named_after(image):
    """An unnamed ``DartsInputError`` about "the picture" raised in the block, named after the
    picture's path when ``image`` is one."""
    try:
        yield
    except DartsInputError as error:
        if error.source is None and isinstance(image, (str, os.PathLike)):
            raise DartsInputError(image, error.problem.removeprefix("the picture ")) from None
        raise


def _refuse(image, problem: str | None) -> None:
    """Raise ``DartsInputError`` for the picture ``image`` (a path or an array) when there is a ``problem``."""
    if problem is None:
        return
    if isinstance(image, (str, os.PathLike)):
        raise DartsInputError(image, problem)
    raise DartsInputError(None, f"the picture {problem}")


def _size(shape: tuple) -> str:
    """An array's shape as a picture's size, WIDTHxHEIGHT (or the shape when it is not [H,W])."""
    return f"{shape[1]}x{shape[0]}" if len(shape) == 2 else f"of shape {shape} (not [H,W])"


def _picture_mask(mask, picture: np.ndarray):
    """``mask`` (None, a path or an [H,W] array the size of ``picture``) as a bool array, or None."""
    from darts.crdl.silhouette import read_mask

    if mask is None or isinstance(mask, np.ndarray):
        if mask is not None and mask.shape != picture.shape[:2]:
            raise DartsInputError(None, f"the mask is {_size(mask.shape)}, the image {picture.shape[1]}x{picture.shape[0]}")
        return None if mask is None else np.asarray(mask, bool)
    check.path_or(mask, "mask", what="None, a mask picture's path or an [H,W] bool array")
    return read_mask(mask, picture.shape[1], picture.shape[0], "the image")


def reconstruct(image, category: str | None = None, camera=None, mask=None, body=None,
                betas: Sequence[float] | None = None, edge_length: float = DATASET_EDGE_LENGTH, progress: bool = False,
                silhouette: str = "outline", silhouette_weight: float | None = None, accept_low_confidence: bool = False,
                garment: str | None = None, lengths: bool = False):
    """The DART of the garment in ``image`` (a path or [H,W,3] uint8): classifier (unless
    ``category``), feature-line regressor, CRDL (with the silhouette term ``silhouette``, at
    ``silhouette_weight`` (default: the term's, ``darts.crdl.SILHOUETTE_WEIGHTS``), when ``mask`` is given).
    ``camera``: a ``Camera`` or camera.json (default: the dataset's camera of the category). Returns
    a ``Reconstruction``: ``.dart``, ``.report`` (category, probabilities, lines, CRDL numbers,
    seconds per stage) and ``.mask`` (the garment mask the silhouette term used). A picture too
    small, blurred or blank, or whose garment the classifier is not
    sure of, or given alone (no mask, no camera) without a person in it (``darts.photo``; these two
    unless ``accept_low_confidence``), raises ``DartsInputError`` (``darts.regress.checks``). A
    photograph given alone is parsed into every garment it shows (``darts.photo.outfit``): ``garment``
    (upper, lower or dress) picks the one reconstructed (default: the outer one); the report's
    ``outfit`` lists them all and its ``lengths`` what the photograph shows of the garment's
    lengths; ``lengths`` moves the lines there before the CRDL (``darts.regress.pipeline``)."""
    from darts.camera import Camera
    from darts.regress.pipeline import reconstruct as run
    from darts.templates.categories import CATEGORIES

    if category is not None:
        check.text(category, "category", CATEGORIES)
    accept_low_confidence = check.switch(accept_low_confidence, "accept_low_confidence")
    lengths, progress = check.switch(lengths, "lengths"), check.switch(progress, "progress")
    silhouette_weight = check.optional_number(silhouette_weight, "silhouette_weight", 0.0)
    if garment is not None:
        from darts.photo.outfit import A_KIND, KIND_OF, KINDS

        check.text(garment, "garment", KINDS)
        if category is not None and KIND_OF[category] != garment:
            raise DartsInputError(None, f"category {category} is {A_KIND[KIND_OF[category]]}, not {A_KIND[garment]}")
    _check_fit_options(silhouette, edge_length)
    picture = read_picture(image)
    source = None if camera is None or isinstance(camera, Camera) else check.path_or(
        camera, "camera", what="None, a Camera or a camera.json path")
    if source is not None:
        camera = Camera.from_json(source)
    if camera is not None and (camera.width, camera.height) != (picture.shape[1], picture.shape[0]):
        raise DartsInputError(source, f"is {camera.width}x{camera.height} pixels but the image is "
                                      f"{picture.shape[1]}x{picture.shape[0]}")
    model = _body_for(body, betas)
    with _errors_named_after(image):
        return run(picture, model, category, camera, _picture_mask(mask, picture), betas=betas, edge_length=edge_length,
                   progress=progress, silhouette_term=silhouette, silhouette_weight=silhouette_weight,
                   accept_low_confidence=accept_low_confidence, garment=garment, lengths=lengths)
