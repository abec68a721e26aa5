"""What a picture must be for ``darts reconstruct`` to answer: big enough, sharp enough, and a
garment the classifier recognises; otherwise one clear line (``DartsInputError``, exit 2).

- **Size**: at least ``MIN_PICTURE`` pixels on each side, and with a mask a garment at least
  ``MIN_GARMENT`` pixels on the long side of its box (the networks see 224 x 224 pixels).
- **Sharpness**: the variance of the Laplacian of the networks' grey input (224 x 224, values in
  [0, 1]) at least ``MIN_SHARPNESS``. On 42 held-out dataset pictures it is 0.0023-0.039; blurred by
  a Gaussian of radius 1 / 2 / 3 pixels (at 224) 0.0002-0.0027 / 0.00004-0.00034 / 0.00002-0.00007;
  a blank picture has 0. The limit refuses a blur of radius 2 and more (about 1 % of the picture).
- **Confidence**: the classifier's top probability at least ``MIN_CONFIDENCE``; every held-out
  dataset picture has 0.60 or more, a half-length portrait (matplotlib's ``grace_hopper.jpg``) 0.44.
  A caller may accept a lower one (``--accept-low-confidence``); the report then says so.

- **A person**: a picture given alone (no mask, no camera: a photograph) must show a person
  (``darts.photo.person.find_person``: BlazePose's detector and its landmark model's presence);
  random noise (which the classifier calls a long-sleeve top at 89 %) and a gift box (a
  short-sleeve top at 83 %) show none. With a mask the caller has said where the garment is (the
  dataset's pictures of pants or skirts show legs without a face, which the detector, anchored on
  faces, does not find), so no person is looked for. ``--accept-low-confidence`` lets a picture
  without a person go on too; the report then says so.
"""
from __future__ import annotations

import numpy as np

MIN_PICTURE = 64
MIN_GARMENT = 32
MIN_SHARPNESS = 0.0002
MIN_CONFIDENCE = 0.5


def sharpness(image: np.ndarray) -> float:
    """Variance of the Laplacian of ``image`` [H,W,3] uint8 as the networks see it (grey, 224 x 224, [0, 1])."""
    from PIL import Image
    from scipy import ndimage

    from darts.camera import IMAGE_SIZE

    grey = Image.fromarray(np.asarray(image, np.uint8)).convert("L").resize((IMAGE_SIZE, IMAGE_SIZE), Image.BILINEAR)
    return float(ndimage.laplace(np.asarray(grey, np.float64) / 255.0).var())


def garment_problem(mask: np.ndarray) -> str | None:
    """Why a garment ``mask`` [H,W] bool is too small to reconstruct ("empty", or how far it
    spans), or None."""
    rows, cols = np.nonzero(mask)
    if len(rows) == 0:
        return "empty"
    extent = max(rows.max() - rows.min() + 1, cols.max() - cols.min() + 1)
    return f"spans {extent} pixels: too small (at least {MIN_GARMENT})" if extent < MIN_GARMENT else None


def picture_problem(image: np.ndarray, mask: np.ndarray | None) -> str | None:
    """Why ``image`` [H,W,3] (with its garment ``mask`` [H,W] bool, if any) cannot be reconstructed,
    or None: too small, too blurred or blank (module docstring)."""
    height, width = image.shape[:2]
    if min(height, width) < MIN_PICTURE:
        return f"is {width}x{height} pixels: too small (at least {MIN_PICTURE} on each side)"
    problem = None if mask is None else garment_problem(mask)
    if problem:
        return "its mask is empty: no garment to reconstruct" if problem == "empty" else f"the garment in its mask {problem}"
    value = sharpness(image)
    if value < MIN_SHARPNESS:
        return (f"is too blurred or blank to read a garment from (sharpness {value:.2g}, at least {MIN_SHARPNESS:g}: "
                "the variance of the Laplacian at 224 x 224)")
    return None


def person_problem(given_alone: str = "give --mask (and --camera) for a picture of a garment alone, or "
                                      "--accept-low-confidence to go on") -> str:
    """Why a picture given alone in which no person was found is not read: ``given_alone`` says
    what the caller can give instead."""
    return ("shows no person (the person detector found none): a photograph must show the person wearing the garment; "
            + given_alone)


def confidence_problem(ranked: list[tuple[str, float]]) -> str | None:
    """Why the classifier's answer ``ranked`` [(category, probability), ...] is not one to act on, or None."""
    category, probability = ranked[0]
    if probability < MIN_CONFIDENCE:
        others = ", ".join(f"{c} {100 * p:.0f} %" for c, p in ranked[:3])
        return (f"shows no garment the classifier recognises: its best guess is {category} at {100 * probability:.0f} % "
                f"(at least {100 * MIN_CONFIDENCE:.0f} % needed; {others}); give --category, or "
                "--accept-low-confidence to go on")
    return None
