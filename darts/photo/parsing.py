"""Garment parsing of a photographed person: a label per pixel inside the person — upper garment,
lower garment, one-piece (dress), skin, face and hair, other — from what the body fit knows.

    person mask (BlazePose)  +  the fitted body's projected parts (``darts.body.segmentation``)
      -> every person pixel takes the body part nearest to it (its *zone*: a skirt between the legs
         is nearest the thighs, a loose sleeve nearest the arm)
      -> colour models in CIELAB (``darts.photo.colour``): **skin** from the face (between the eyes
         and the mouth, BlazePose's face landmarks) and the hands; **upper cloth** from the torso and
         upper arms, **lower cloth** from the thighs (then the shins), each without the colours the
         skin model explains; **hair** from the head's other colours (long hair falls over the
         shoulders)
      -> per pixel, log p(colour | class) + log prior(class | zone) (``ZONE_PRIORS``: a thigh is
         lower cloth or skin, an upper arm upper cloth or skin, ...), smoothed over the picture
         (Gaussian, ``SMOOTH`` pixels) and the best class taken
      -> **the colour test of one piece or two** (evidence, not the decision): the lower cloth's
         colours explained by the upper cloth's model within ``ONE_PIECE_NATS`` a pixel (median)
         of its own, and the upper's by the lower's within twice that (a top may show more colours
         than a skirt): one colour. The labels keep the upper and lower cloth apart;
         ``darts.photo.attributes`` reads them both ways and decides (``Parsing.merged``: one).

Everything runs on a square crop around the person resampled to ``SIZE`` pixels (the labels are
drawn back to the picture's pixels); arrays are [row, column], the picture's axes.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from darts.body.segmentation import PART_NAMES
from darts.photo.colour import ColourModel, lab
from darts.photo.crop import Crop

SIZE = 256
MARGIN = 0.04
SMOOTH = 1.5
#: pixel labels
BACKGROUND, UPPER, LOWER, DRESS, SKIN, FACE_HAIR, OTHER = range(7)
LABEL_NAMES = ("background", "upper", "lower", "dress", "skin", "face_hair", "other")
#: the classes a pixel of each body zone may take and their log prior (nats); absent: not allowed
ZONE_PRIORS = {
    "head": {FACE_HAIR: 0.0},
    "neck": {SKIN: 0.0, UPPER: 0.0, FACE_HAIR: -1.0},
    "upper_torso": {UPPER: 0.0, SKIN: 0.0, LOWER: -3.0, FACE_HAIR: -1.5},
    "lower_torso": {UPPER: 0.0, SKIN: 0.0, LOWER: -0.5},
    "hips": {UPPER: 0.0, LOWER: 0.0, SKIN: -1.0},
    "upper_arm": {UPPER: 0.0, SKIN: 0.0, FACE_HAIR: -1.5},
    "forearm": {UPPER: 0.0, SKIN: 0.0},
    "hand": {SKIN: 0.0, UPPER: -2.0, OTHER: -1.0},
    "thigh": {LOWER: 0.0, SKIN: 0.0, UPPER: -2.0},
    "calf": {LOWER: 0.0, SKIN: 0.0, UPPER: -4.0},
    "foot": {OTHER: 0.0, SKIN: -1.0, LOWER: -1.0},
}
#: log-density of the "other" class: a uniform density over the Lab box (100 x 200 x 200)
#: skin's chroma (Lab units) and hue range (degrees): ``skin_coloured``
SKIN_CHROMA = 6.0
SKIN_HUE = (15.0, 95.0)
GREY_CHROMA = 2.0
OTHER_LOG_DENSITY = -float(np.log(100 * 200 * 200))
#: the lower cloth is the upper's when the upper's model explains its colours within this many nats
#: a pixel of its own model (and the other way round)
ONE_PIECE_NATS = 2.5


def zone_of(part: str) -> str:
    """The zone of body part ``part`` (``PART_NAMES``): the part without its side."""
    return part.removeprefix("left_").removeprefix("right_")


ZONES = tuple(ZONE_PRIORS)
PART_ZONE = np.array([ZONES.index(zone_of(name)) for name in PART_NAMES])


@dataclass
class Parsing:
    """The labels of a person's pixels on the crop (``crop``, ``SIZE`` pixels): ``labels`` [S,S]
    (``LABEL_NAMES``), ``parts`` [S,S] the nearest body part of each person pixel (-1 off the
    person), ``body_parts`` the fitted body's own silhouette by part, and the evidence of the
    one-piece decision."""

    crop: Crop
    labels: np.ndarray
    parts: np.ndarray
    body_parts: np.ndarray  # [S,S] the fitted body's part seen at each pixel (-1: off the body)
    one_piece: bool  # the colour test: the upper and lower cloth one colour (``_one_piece``)
    picture_size: tuple[int, int]  # (width, height) of the picture the crop was taken from
    evidence: dict = field(default_factory=dict)

    def merged(self) -> Parsing:
        """The same parsing with its upper and lower cloth one garment (``DRESS``)."""
        labels = np.where((self.labels == UPPER) | (self.labels == LOWER), DRESS, self.labels).astype(self.labels.dtype)
        return replace(self, labels=labels)

    def split_one_piece(self) -> Parsing:
        """The same parsing with the one-piece cloth taken as two garments of one colour (a suit):
        its pixels on the hips and legs lower, the rest upper."""
        labels = self.labels.copy()
        legs = _zone_mask(self.parts, "hips", "thigh", "calf", "foot")
        labels[(labels == DRESS) & legs] = LOWER
        labels[labels == DRESS] = UPPER
        return replace(self, labels=labels, one_piece=False)

    def mask(self, label: int, width: int, height: int) -> np.ndarray:
        """The pixels of ``label`` in the picture [height, width] bool."""
        return self.crop.to_picture((self.labels == label).astype(np.float32), width, height) > 0.5

    def in_picture(self) -> np.ndarray:
        """[S,S] bool: the crop's pixels that lie in the picture (a crop may reach past its edges)."""
        k = self.crop.side / SIZE
        u = self.crop.x + (np.arange(SIZE) + 0.5) * k
        v = self.crop.y + (np.arange(SIZE) + 0.5) * k
        return ((v >= 0) & (v < self.picture_size[1]))[:, None] & ((u >= 0) & (u < self.picture_size[0]))[None, :]

    def at_picture_bottom(self, pixels: np.ndarray) -> bool:
        """Whether any of ``pixels`` [S,S] bool lies on the picture's bottom rows (within 1 % of the
        crop): the region goes on out of frame."""
        bottom = (self.picture_size[1] - self.crop.y) * SIZE / self.crop.side
        rows = np.nonzero(pixels.any(1))[0]
        return bool(len(rows)) and rows.max() + 1 >= bottom - 0.01 * SIZE

    def to_crop(self, points: np.ndarray) -> np.ndarray:
        """Picture pixels [N,2] (u, v) -> crop pixels (u, v)."""
        return (np.asarray(points, np.float64) - [self.crop.x, self.crop.y]) * SIZE / self.crop.side


def part_image(vertices: np.ndarray, faces: np.ndarray, part_labels: np.ndarray, camera) -> np.ndarray:
    """The body part seen at each pixel [H,W] (-1: none) of the body ``vertices`` [V,3] (the frame
    ``camera`` sees) with per-vertex ``part_labels`` (a face takes its first corner's)."""
    from darts.raycast import cast

    hits = cast(camera, [(vertices, faces)])
    part = np.where(hits.which >= 0, part_labels[np.asarray(faces)[hits.face, 0]], -1)
    return part.reshape(camera.height, camera.width)


def _nearest_parts(seen: np.ndarray, person: np.ndarray) -> np.ndarray:
    """Each person pixel's nearest body part [S,S] (-1 off the person) from the parts ``seen`` [S,S]."""
    from scipy import ndimage

    if (seen < 0).all():
        return np.full(seen.shape, -1)
    _, (rows, cols) = ndimage.distance_transform_edt(seen < 0, return_indices=True)
    return np.where(person, seen[rows, cols], -1)


def _face_pixels(landmarks: np.ndarray, visibility: np.ndarray, shape) -> np.ndarray:
    """[S,S] bool: a disc between the eyes and the mouth (crop pixels ``landmarks`` [33,2]), empty when
    the face is not seen (nose or mouth under 0.5 visibility)."""
    from darts.photo.person import LANDMARKS

    index = {name: k for k, name in enumerate(LANDMARKS)}
    face = [index[n] for n in ("nose", "mouth_left", "mouth_right", "left_eye_inner", "right_eye_inner")]
    if visibility[[index["nose"], index["mouth_left"], index["mouth_right"]]].min() < 0.5:
        return np.zeros(shape, bool)
    centre = landmarks[face].mean(0)
    eyes = np.linalg.norm(landmarks[index["left_eye"]] - landmarks[index["right_eye"]])
    radius = max(0.6 * eyes, 1.5)
    rows, cols = np.mgrid[:shape[0], :shape[1]]
    return (cols + 0.5 - centre[0]) ** 2 + (rows + 0.5 - centre[1]) ** 2 < radius ** 2


def _erode(mask: np.ndarray, pixels: int) -> np.ndarray:
    from scipy import ndimage

    return ndimage.binary_erosion(mask, iterations=pixels) if pixels > 0 else mask


def _zone_mask(parts: np.ndarray, *zones: str) -> np.ndarray:
    wanted = [ZONES.index(z) for z in zones]
    return np.isin(np.where(parts >= 0, PART_ZONE[np.maximum(parts, 0)], -1), wanted)


def skin_coloured(colours: np.ndarray) -> np.ndarray:
    """[...] bool: Lab ``colours`` [..., 3] in the range of human skin: chroma sqrt(a^2 + b^2) at
    least ``SKIN_CHROMA`` and hue atan2(b, a) within ``SKIN_HUE`` degrees (pale to dark skin sit
    within it; hair, grey, black and white cloth fall under the chroma)."""
    a, b = colours[..., 1], colours[..., 2]
    hue = np.degrees(np.arctan2(b, a))
    return (np.hypot(a, b) >= SKIN_CHROMA) & (hue >= SKIN_HUE[0]) & (hue <= SKIN_HUE[1]) & (colours[..., 0] > 15)


def _skin_model(colours: np.ndarray, face: np.ndarray, parts: np.ndarray) -> tuple[ColourModel | None, np.ndarray]:
    """(skin's colour model, the pixels it was fitted to): the face disc (unless under half of it is
    skin-coloured: a head seen from behind) and the hands, skin-coloured pixels only, the farthest
    30 % from their median (chroma) left out: shadows, lips, a bag. In a grey picture (the person's
    median chroma under ``GREY_CHROMA``) no colour is skin's: the face and hands as they are."""
    source = (face & (parts >= 0)) | _zone_mask(parts, "hand")
    if np.median(np.hypot(colours[parts >= 0][:, 1], colours[parts >= 0][:, 2])) >= GREY_CHROMA:
        if face.any() and skin_coloured(colours[face]).mean() < 0.5:
            source = _zone_mask(parts, "hand")
        source &= skin_coloured(colours)
    samples = colours[source]
    if len(samples) < 8:
        return None, source
    chroma = np.linalg.norm(samples[:, 1:] - np.median(samples[:, 1:], 0), axis=1)
    kept = chroma <= np.quantile(chroma, 0.7)
    rows, cols = np.nonzero(source)
    source = np.zeros_like(source)
    source[rows[kept], cols[kept]] = True
    return ColourModel.fit(samples[kept], components=1), source


def _cloth_model(colours: np.ndarray, region: np.ndarray, skin_like: np.ndarray) -> tuple[ColourModel | None, np.ndarray]:
    """(the colour model of the cloth in ``region`` [S,S] without ``skin_like`` pixels, its samples' mask)."""
    samples = region & ~skin_like
    return ColourModel.fit(colours[samples], components=3), samples


def parse_person(image: np.ndarray, person_mask: np.ndarray, landmarks: np.ndarray, visibility: np.ndarray,
                 body_vertices: np.ndarray, body_faces: np.ndarray, part_labels: np.ndarray, camera) -> Parsing | None:
    """The labels of the person in ``image`` [H,W,3] uint8 (module docstring): ``person_mask`` [H,W]
    0..1, BlazePose's ``landmarks`` [33,2] (picture pixels) and ``visibility`` [33], the fitted body
    (``body_vertices`` [V,3] in the frame ``camera`` sees, ``body_faces``, per-vertex ``part_labels``).
    None when the person mask is empty."""
    from scipy import ndimage

    crop = Crop.around(np.asarray(person_mask) > 0.5, MARGIN)
    if crop is None:
        return None
    person = crop.resample(np.asarray(person_mask, np.float32), SIZE) > 0.5
    rgb = crop.resample(np.asarray(image, np.uint8), SIZE)
    colours = lab(ndimage.gaussian_filter(rgb.astype(np.float32), (0.7, 0.7, 0)).clip(0, 255).astype(np.uint8))
    seen = part_image(body_vertices, body_faces, part_labels, crop.camera(camera, SIZE))
    parts = _nearest_parts(np.where(person, seen, -1) if (person & (seen >= 0)).any() else seen, person)
    crop_landmarks = (np.asarray(landmarks) - [crop.x, crop.y]) * SIZE / crop.side
    face = _face_pixels(crop_landmarks, np.asarray(visibility), person.shape) & person

    skin, skin_source = _skin_model(colours, face, parts)
    flat = colours.reshape(-1, 3)
    skin_density = skin.log_density(flat).reshape(person.shape) if skin else np.full(person.shape, -np.inf)
    if skin is not None:
        own = skin.log_density(colours[skin_source])
        # skin as the cloth models must not learn it: the skin model's own range; on the legs also
        # skin-coloured pixels somewhat off it (bare legs lit otherwise than the face; on the torso
        # such a colour is far more often cloth: a peach suit, a beige shirt)
        skin_like = skin_density > np.quantile(own, 0.05)
        leg_skin_like = skin_like | (skin_coloured(colours) & (skin_density > own.min() - 8.0))
    else:
        skin_like = leg_skin_like = np.zeros(person.shape, bool)
    upper, upper_samples = _cloth_model(colours, _erode(_zone_mask(parts, "upper_torso", "lower_torso", "upper_arm"), 2),
                                        skin_like)
    lower_region = _erode(_zone_mask(parts, "thigh"), 2)
    if (lower_region & ~leg_skin_like).sum() < 40:
        lower_region = _erode(_zone_mask(parts, "thigh", "calf"), 2)
    lower, lower_samples = _cloth_model(colours, lower_region, leg_skin_like)

    hair = ColourModel.fit(colours[_erode(_zone_mask(parts, "head"), 1) & ~skin_like & ~face], components=2)
    uniform = np.full(person.shape, OTHER_LOG_DENSITY)
    densities = {SKIN: skin_density, OTHER: uniform,
                 FACE_HAIR: np.maximum(hair.log_density(flat).reshape(person.shape), uniform) if hair else uniform}
    for label, model in ((UPPER, upper), (LOWER, lower)):
        densities[label] = model.log_density(flat).reshape(person.shape) if model else np.full(person.shape, -np.inf)

    one_piece, evidence = _one_piece(upper, lower, colours, upper_samples, lower_samples)
    scores = np.full((len(LABEL_NAMES),) + person.shape, -np.inf)
    zone = np.where(parts >= 0, PART_ZONE[np.maximum(parts, 0)], -1)
    for z, name in enumerate(ZONES):
        here = zone == z
        for label, prior in ZONE_PRIORS[name].items():
            scores[label][here] = np.maximum(densities[label][here], -60.0) + prior
    scores = np.stack([ndimage.gaussian_filter(np.where(np.isfinite(s), s, -200.0), SMOOTH) for s in scores])
    labels = np.where(person, scores.argmax(0), BACKGROUND).astype(np.uint8)
    evidence["skin_samples"] = int(skin_source.sum())
    return Parsing(crop, labels, parts, seen, one_piece, (image.shape[1], image.shape[0]), evidence)


def _one_piece(upper: ColourModel | None, lower: ColourModel | None, colours: np.ndarray, upper_samples: np.ndarray,
               lower_samples: np.ndarray) -> tuple[bool, dict]:
    """Whether the lower cloth is the upper's (module docstring), and the numbers that say so."""
    if upper is None or lower is None:
        return False, {"lower_by_upper_nats": None, "upper_by_lower_nats": None}
    a, b = colours[lower_samples], colours[upper_samples]
    lower_by_upper = float(np.median(lower.log_density(a) - upper.log_density(a)))
    upper_by_lower = float(np.median(upper.log_density(b) - lower.log_density(b)))
    same = lower_by_upper < ONE_PIECE_NATS and upper_by_lower < 2 * ONE_PIECE_NATS
    return same, {"lower_by_upper_nats": round(lower_by_upper, 2), "upper_by_lower_nats": round(upper_by_lower, 2)}
