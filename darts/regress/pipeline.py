"""From one picture to a DART: classify, regress the feature lines, fit the template with the CRDL.

    picture (+ mask, camera) -> without a camera: the person and the body fitted to it (darts.photo)
                             -> category (classifier, or given)
                             -> feature lines (regressor, from the category's F_g and the camera;
                                on a fitted body with a mask: the posed regressor's, taken back
                                to the rest pose)
                             -> the category's template on the body, deformed by the CRDL so its
                                lines reach the regressed ones, outside the body, and (with a mask)
                                its silhouette matches the mask
                             -> a DART (panels, seams, springs of the template)

Pictures of another size than the networks' (224 x 224) are resized for the networks; the camera's
intrinsics are scaled with them. Without a camera, the camera fitted with the person's body when
a mask is given and a person found, else the category's default camera (``Camera.default``: the
dataset's, level and from the front) at the picture's size. Everything is in the body's canonical
frame (Y up, metres).
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from darts.camera import IMAGE_SIZE, Camera
from darts.errors import DartsInputError
from darts.regress.data import CATEGORY_IDS, camera_batch, initial_lines, padded
from darts.regress.shipped import shipped_model
from darts.templates.categories import CATEGORIES
from darts.templates.defaults import DATASET_EASE, DATASET_EDGE_LENGTH


def network_input(image: np.ndarray) -> torch.Tensor:
    """uint8 [H,W,3] -> float [1,3,224,224] in [0,1] (bilinear resize when the size differs)."""
    x = torch.from_numpy(np.array(image, np.float32)).permute(2, 0, 1)[None] / 255
    if x.shape[-2:] != (IMAGE_SIZE, IMAGE_SIZE):
        x = torch.nn.functional.interpolate(x, size=(IMAGE_SIZE, IMAGE_SIZE), mode="bilinear", align_corners=False)
    return x


def network_mask(mask: np.ndarray) -> torch.Tensor:
    """bool [H,W] -> bool [1,224,224] (nearest resize when the size differs)."""
    m = torch.from_numpy(np.array(mask, np.float32))[None, None]
    if m.shape[-2:] != (IMAGE_SIZE, IMAGE_SIZE):
        m = torch.nn.functional.interpolate(m, size=(IMAGE_SIZE, IMAGE_SIZE), mode="nearest")
    return m[0] > 0.5


@torch.no_grad()
def classify_image(image: np.ndarray, mask: np.ndarray | None = None) -> list[tuple[str, float]]:
    """Every category with its probability, most likely first; with the garment's ``mask`` [H,W]
    the classifier sees the garment alone on grey (``darts.regress.train.garment_only``)."""
    from darts.regress.train import garment_only

    model, _ = shipped_model("classifier", "classifier")
    x = network_input(image)
    if mask is not None:
        x = garment_only(x, network_mask(mask))
    probabilities = torch.softmax(model(x), 1)[0].numpy()
    order = np.argsort(-probabilities)
    return [(CATEGORY_IDS[i], float(probabilities[i])) for i in order]


@torch.no_grad()
def regress_lines(image: np.ndarray, camera: Camera, category: str, variant: str = "ours") -> dict[str, np.ndarray]:
    """The feature lines of ``category`` seen in ``image`` through ``camera``: {name: [K,3]}."""
    model, _ = shipped_model("lines", f"lines_{variant}")
    lines, mask, creases = padded(category, initial_lines(category))
    small = camera.resized(IMAGE_SIZE, IMAGE_SIZE)
    out = model(network_input(image), camera_batch([small]), torch.from_numpy(lines)[None],
                torch.from_numpy(creases)[None])[-1][0].numpy().astype(np.float64)
    return {name: out[k] for k, name in enumerate(CATEGORIES[category].line_names)}


@dataclass
class Photograph:
    """What a photograph given alone shows: its ``person`` (None: none found), the ``body_fit`` to
    them, their ``outfit`` (every garment parsed, ``darts.photo.outfit``; None when not parsed) and
    the ``times`` of these stages."""

    person: object | None
    body_fit: object | None
    outfit: object | None
    times: dict


def read_photograph(image: np.ndarray, body, parse: bool = True, progress: bool = False) -> Photograph:
    """The person in ``image`` [H,W,3] uint8, ``body`` (a ``BodyModel``) fitted to them and, with
    ``parse``, every garment they wear; ``progress`` shows the stages after a person is found (the
    body fit, the parsing)."""
    from tqdm import tqdm

    from darts.photo.fit import fit_body
    from darts.photo.person import find_person

    times: dict = {}
    mark = time.perf_counter()
    person = find_person(image)
    times["person_s"] = time.perf_counter() - mark
    if person is None:
        return Photograph(None, None, None, times)
    with tqdm(total=2 if parse else 1, desc="photograph", unit="stage", disable=not progress, leave=False) as bar:
        mark = time.perf_counter()
        body_fit = fit_body(person, body, image.shape[1], image.shape[0])
        times["body_fit_s"] = time.perf_counter() - mark
        bar.update()
        outfit = None
        if parse:
            from darts.photo.outfit import read_outfit

            mark = time.perf_counter()
            outfit = read_outfit(image, person, body_fit, body)
            times["parsing_s"] = time.perf_counter() - mark
            bar.update()
    return Photograph(person, body_fit, outfit, times)


@dataclass
class Reconstruction:
    dart: object
    report: dict
    mask: np.ndarray | None = None  # [H,W] bool: the garment mask the silhouette term used (given or estimated)


def reconstruct(*args, **kwargs) -> Reconstruction:
    """``_reconstruct`` on one torch thread (``darts.threads.one_torch_thread``)."""
    from darts.threads import one_torch_thread

    with one_torch_thread():
        return _reconstruct(*args, **kwargs)


def _reconstruct(image: np.ndarray, body, category: str | None = None, camera: Camera | None = None,
                mask: np.ndarray | None = None, betas=None, edge_length: float = DATASET_EDGE_LENGTH,
                progress: bool = False, silhouette_term: str = "outline",
                silhouette_weight: float | None = None, accept_low_confidence: bool = False,
                garment: str | None = None, photograph: Photograph | None = None,
                lengths: bool = False) -> Reconstruction:
    """The DART of the garment in ``image`` [H,W,3] uint8 (module docstring); ``mask`` [H,W] bool
    switches the CRDL's silhouette term on and shows the classifier the garment alone; ``progress``
    shows the CRDL's steps; ``silhouette_term``: which (``darts.crdl.SILHOUETTE_WEIGHTS``),
    at ``silhouette_weight`` (default: the term's). A picture that is too small, blurred or blank, or
    whose garment the classifier is not sure of (``darts.regress.checks``; the latter unless
    ``accept_low_confidence``) raises ``DartsInputError`` before anything is built.

    Without a camera the picture is taken for a photograph: the person in it is looked for
    (``darts.photo.person``) and the body fitted to its landmarks (``darts.photo.fit``: pose, shape,
    camera); without a mask too, a picture with no person is refused (unless
    ``accept_low_confidence``). With a mask and a person, the garment is fitted on that body: the
    template on the fitted shape (unless ``betas``), the lines of the posed regressor
    (``darts.regress.posed_lines``) taken back to the rest pose, the silhouette term seen through
    the fitted pose and camera (``darts.crdl.posed.PosedTerm``); the report's ``camera`` is then the
    rest-posed body's. A photograph given without a mask is parsed (``darts.photo.outfit``): every
    garment it shows is read, with its category from what is seen (sleeve length, the legs); the
    one reconstructed is ``garment`` (upper, lower, dress; default the outer one: the top or the
    dress), or the one of ``category``'s kind, with its parsed mask; the report's ``outfit`` lists
    them all. ``photograph``: the photograph already read (``read_photograph``), so that its
    garments are reconstructed one by one without reading it again. The lengths read in a
    photograph (``darts.photo.lengths``) are always measured and reported (``lengths``: each line's
    s, the move it asks for and how far the result is from it); with ``lengths`` the lines are moved
    there before the CRDL (off by default: on the posed renders they made the lines worse,
    docs/reconstruction.md)."""
    from darts.crdl import SILHOUETTE_WEIGHTS
    from darts.crdl.deform import deform_dart
    from darts.crdl.layer import CrdlWeights
    from darts.crdl.posed import PosedTerm
    from darts.crdl.silhouette import silhouette_term as make_term
    from darts.dart.build import make_dart
    from darts.regress.checks import confidence_problem, garment_problem, person_problem, picture_problem
    from darts.regress.posed_lines import regress_posed_lines, template_lines

    problem = picture_problem(image, mask)
    if problem:
        raise DartsInputError(None, f"the picture {problem}")
    started = time.perf_counter()
    classified, looked = category is None, camera is None
    if looked and photograph is None:
        photograph = read_photograph(image, body, parse=mask is None, progress=progress)
    person, body_fit, outfit = (photograph.person, photograph.body_fit, photograph.outfit) if looked else (None, None, None)
    times = dict(photograph.times) if looked else {}
    if looked and person is None and mask is None and not accept_low_confidence:
        raise DartsInputError(None, f"the picture {person_problem()}")
    low_confidence = looked and mask is None and person is None
    given_mask, garment_ranked, kind, chosen = mask is not None, None, None, None
    if person is not None and mask is None:  # a photograph given alone: every garment it shows
        from darts.photo.outfit import A_KIND, KIND_OF

        kind = garment or (KIND_OF[category] if category else None)
        if kind is None:  # the outer garment: the top or the dress, else what there is
            kind = next((g.kind for g in reversed(outfit.garments)), "upper") if outfit else "upper"
        chosen = outfit.garment(kind) if outfit else None
        if chosen is None and category is None and not accept_low_confidence:
            seen = ", ".join(f"{g.kind} ({g.category})" for g in outfit.garments) if outfit and outfit.garments else "none"
            raise DartsInputError(None, f"the picture shows a person but no {kind} garment (garments seen: {seen}); "
                                        "choose another with --garment, or give --mask")
        garment_ranked = chosen.ranked if chosen is not None else None
        mask = outfit.mask(kind) if outfit else None
        problem = None if mask is None else garment_problem(mask)
        if problem and not accept_low_confidence:
            found = "no garment" if problem == "empty" else f"a garment that {problem}"
            raise DartsInputError(None, f"the picture shows a person but its {kind} garment's parsing finds {found}; "
                                        "give --mask, or --accept-low-confidence to go on")
        if problem or mask is None:
            mask, low_confidence = None, True
    if classified:
        mark = time.perf_counter()
        ranked = garment_ranked or classify_image(image, mask)
        category, probability = ranked[0]
        if garment_ranked is None:
            times["classify_s"] = time.perf_counter() - mark
        problem = confidence_problem(ranked)
        if problem and not accept_low_confidence:
            if garment_ranked is not None:  # the parsing saw the garment; its category is what is unsure
                others = ", ".join(f"{c} {100 * p:.0f} %" for c, p in ranked[:3])
                problem = (f"shows {A_KIND[kind]} whose category is unsure ({others}; at least 50 % needed); give "
                           "--category, or --accept-low-confidence to go on")
            raise DartsInputError(None, f"the picture {problem}")
        low_confidence = low_confidence or problem is not None
    else:
        ranked, probability = [(category, 1.0)], 1.0
    height, width = image.shape[:2]
    given_camera, given_betas = camera is not None, bool(betas)
    posed = body_fit is not None and mask is not None
    if posed:  # the person's body, pose and camera fitted to the photograph
        camera, betas = body_fit.camera, betas or body_fit.betas.tolist()
    # Without a camera: the dataset's, for the picture as the networks see it (stretched to a square).
    camera = camera or Camera.default(category).resized(width, height)
    if (camera.width, camera.height) != (width, height):
        raise DartsInputError(None, f"the camera is {camera.width}x{camera.height} pixels but the image is {width}x{height}")
    mark = time.perf_counter()
    template = make_dart(category, body, betas=None if not betas else np.asarray(betas), edge_length=edge_length,
                         ease=DATASET_EASE)  # the cut its networks were trained on
    times["template_s"] = time.perf_counter() - mark
    mark = time.perf_counter()
    length_report, length_targets = None, None
    if posed:  # the lines as the posed body shows them, taken back to its rest pose
        lines = regress_posed_lines(image, mask, body_fit.camera, body, body_fit.pose, betas, category,
                                    template_lines(template, category))
        if chosen is not None:  # the lengths the photograph shows, where the garment ends along the body
            from darts.photo.lengths import length_targets as targets_of
            from darts.photo.lengths import place_lines

            length_targets = targets_of(category, chosen.attributes, body, betas)
            placed, length_report = place_lines(lines, length_targets, template.vertices.mean(0))
            if lengths:
                lines = placed
            length_report = {name: {**entry, "applied": lengths} for name, entry in length_report.items()}
    else:
        lines = regress_lines(image, camera, category)
    times["regress_s"] = time.perf_counter() - mark
    silhouette = None
    if mask is not None:
        silhouette = make_term(silhouette_term, mask, body_fit.posed_camera if posed else camera)
        if posed:
            silhouette = PosedTerm(silhouette, body, body_fit.pose, betas)
    weight = SILHOUETTE_WEIGHTS[silhouette_term] if silhouette_weight is None else silhouette_weight
    weights = CrdlWeights(silhouette=weight if silhouette is not None else 0.0)
    mark = time.perf_counter()
    dart, crdl = deform_dart(template, body, lines, "local-global", weights, silhouette, progress=progress)
    times["crdl_s"] = time.perf_counter() - mark
    if length_report:
        from darts.photo.lengths import reached

        final = dict(zip(CATEGORIES[category].line_names, template_lines(dart, category)))
        length_report = reached(final, length_targets, length_report, template.vertices.mean(0))
    times["total_s"] = time.perf_counter() - started
    report = {"category": category, "probability": probability,
              "top_categories": [{"category": c, "probability": p} for c, p in ranked[:3]],
              "probabilities": dict(ranked) if classified else None, "low_confidence": low_confidence,
              "person": None if person is None else person.as_dict(), "person_looked_for": looked,
              "body_fit": None if body_fit is None else body_fit.as_dict(), "posed": posed,
              "lines_from": "posed regressor" if posed else "regressor",
              "given": {"category": not classified, "camera": given_camera, "mask": given_mask,
                        "betas": given_betas},
              "category_from": None if not classified else "photo parsing" if garment_ranked else "classifier",
              "garment": kind, "outfit": None if outfit is None else outfit.as_dict(), "lengths": length_report,
              "mask_estimated": mask is not None and not given_mask,
              "camera": camera.as_dict(), "silhouette": silhouette is not None,
              "lines": {name: points.round(5).tolist() for name, points in lines.items()},
              "crdl": {k: v for k, v in crdl.items() if k != "objective_history"},
              "vertices": len(dart.vertices), "times": {k: round(v, 3) for k, v in times.items()}}
    return Reconstruction(dart, report, mask)



@dataclass
class OutfitReconstruction:
    """Every garment reconstructed from one photograph: the ``outfit`` read (``darts.photo.outfit``),
    the ``garments`` (``Reconstruction`` each, inner layer first)."""

    outfit: object
    garments: list[Reconstruction]

    def file_names(self) -> list[str]:
        """Each garment's file in an outfit folder: its category."""
        return [f"{g.report['category']}.npz" for g in self.garments]

    def save(self, folder, source: str | None = None) -> list:
        """Write the outfit folder (``darts.outfit_folder``): each DART, ``report.json`` (every
        garment's report) and ``outfit.json``; the paths written."""
        import json

        from darts.fileio import atomic_path
        from darts.outfit_folder import write_outfit_folder

        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        with atomic_path(folder / "report.json") as tmp:
            tmp.write_text(json.dumps(self.report(), indent=1))
        index = {"layers": "inner first", "source": source, "categories": [g.report["category"] for g in self.garments],
                 "kinds": [g.report["garment"] for g in self.garments], "notes": self.outfit.notes,
                 "betas": self.garments[0].dart.body_betas.tolist() if self.garments else None}
        return write_outfit_folder(folder, list(zip(self.file_names(), (g.dart for g in self.garments))), index) + [
            folder / "report.json"]

    def report(self) -> dict:
        return {"outfit": self.outfit.as_dict(), "garments": [g.report for g in self.garments]}


def reconstruct_outfit(image: np.ndarray, body, kinds: list[str] | None = None, **options) -> OutfitReconstruction:
    """Every garment of the photograph ``image`` [H,W,3] uint8 (or those of ``kinds``: upper, lower,
    dress), each reconstructed on the body fitted once to the person (``reconstruct``'s
    ``options``: betas, edge_length, progress, silhouette_term, silhouette_weight, lengths), inner
    layer first; a garment whose category is unsure (under 50 %) takes its most likely one and its
    report says ``low_confidence``. No person, or no garment of ``kinds`` seen, raises
    ``DartsInputError``."""
    from darts.photo.outfit import A_KIND
    from darts.regress.checks import person_problem, picture_problem

    problem = picture_problem(image, None)
    if problem:
        raise DartsInputError(None, f"the picture {problem}")
    photograph = read_photograph(image, body, progress=options.get("progress", False))
    if photograph.person is None:
        raise DartsInputError(None, f"the picture {person_problem(given_alone='give --mask for a picture of a garment alone')}")
    seen = [g.kind for g in photograph.outfit.garments] if photograph.outfit else []
    wanted = [k for k in seen if kinds is None or k in kinds]
    if not wanted:
        said = ", ".join(f"{g.kind} ({g.category})" for g in photograph.outfit.garments) if seen else "none"
        missing = f"not {' or '.join(A_KIND[k] for k in kinds)}" if kinds else "no garment"
        raise DartsInputError(None, f"the picture shows a person but {missing} (garments seen: {said})")
    # Every garment seen is reconstructed: one whose category is unsure (under 50 %) takes its most
    # likely one, and its report says low_confidence.
    options = {**options, "accept_low_confidence": True}
    return OutfitReconstruction(photograph.outfit,
                                [reconstruct(image, body, garment=kind, photograph=photograph, **options) for kind in wanted])
