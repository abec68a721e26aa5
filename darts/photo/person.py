"""The person in a photograph: BlazePose (Bazarevsky et al. 2020, MediaPipe Pose; Apache-2.0, the
models shipped in ``darts/photo/models/`` with their licence) run by LiteRT on the CPU.

    picture -> person detector (``darts.photo.detector``): boxes and the region of each person
            -> landmark model on the best detection's region, cropped to 256 x 256 (values in [0, 1]):
               33 body landmarks (picture pixels, x right, y down; MediaPipe's order, LANDMARKS),
               each one's visibility (probability it is in view and not hidden), the landmarks in
               metres about the middle of the hips (x right, y down, z away from the camera, as the
               picture is turned), whether the region holds a person, and the person's mask.

Nothing is downloaded; the models load once per process. The region is read once (MediaPipe's
video mode re-reads a region predicted from the landmarks; for one picture one pass is what its
static-image mode does too).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
from scipy.special import expit

from darts.photo.detector import INPUT, MIN_SCORE, Detection, Region, decode, letterbox

MODELS = Path(__file__).parent / "models"
CROP = 256
#: The landmark model's "a person is in the region" probability must reach this. Measured: three
#: real photographs 0.93-1.00, the dataset's renders of tops and dresses 0.83-1.00; a retina's fundus
#: photograph (skimage's ``retina``), the only one of 12 pictures without a person that the
#: detector took for one, 0.54. (MediaPipe's own default is 0.5.)
MIN_PRESENCE = 0.8
#: When no detection of the detector's own score (``darts.photo.detector.MIN_SCORE``, 0.5) holds a
#: person, the ``CANDIDATES`` best scoring at least ``CANDIDATE_SCORE`` are tried, each taken only at
#: a presence of ``CANDIDATE_PRESENCE`` and with a crisp mask (``mask_crispness`` at least
#: ``CANDIDATE_CRISPNESS``: a person's mask is sure of its edge). Measured: 5 of the 8 posed renders
#: (seed 101; side and back views) where BlazePose found nobody are found (presence 0.92-1.00,
#: crispness 0.90-0.93); of 22 pictures without a person (scikit-image's samples) none is taken:
#: the nearest, its logo at presence 0.97 has a crispness of 0.61, the retina 0.74 and 0.78.
CANDIDATES, CANDIDATE_SCORE, CANDIDATE_PRESENCE, CANDIDATE_CRISPNESS = 3, 0.25, 0.9, 0.85
#: MediaPipe Pose's 33 landmarks, in its order.
LANDMARKS = (
    "nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye", "right_eye_outer",
    "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder", "right_shoulder", "left_elbow",
    "right_elbow", "left_wrist", "right_wrist", "left_pinky", "right_pinky", "left_index", "right_index",
    "left_thumb", "right_thumb", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle",
    "left_heel", "right_heel", "left_foot_index", "right_foot_index",
)


@dataclass
class Person:
    """One person found in a picture (module docstring); arrays in picture pixels unless said."""

    detection: Detection
    region: Region
    presence: float  # 0..1
    landmarks: np.ndarray  # [33,2] picture pixels
    visibility: np.ndarray  # [33] 0..1
    world: np.ndarray  # [33,3] metres about the hips' middle (x right, y down, z away)
    mask: np.ndarray  # [H,W] float 0..1: the person

    def point(self, name: str) -> np.ndarray:
        return self.landmarks[LANDMARKS.index(name)]

    def as_dict(self) -> dict:
        """The report's record of the person (no mask)."""
        return {"score": round(self.detection.score, 4), "presence": round(self.presence, 4),
                "box_px": self.detection.box.round(1).tolist(),
                "landmarks_px": {n: self.landmarks[k].round(1).tolist() for k, n in enumerate(LANDMARKS)},
                "visibility": {n: round(float(self.visibility[k]), 3) for k, n in enumerate(LANDMARKS)},
                "world_m": {n: self.world[k].round(4).tolist() for k, n in enumerate(LANDMARKS)}}


@cache
def _interpreter(name: str):
    """Model ``name`` loaded into LiteRT, on one thread. LiteRT prints an INFO line on the process's
    stderr (file descriptor 2) when it sets up its CPU delegate; that stays out of our stderr."""
    import os

    from ai_edge_litert.interpreter import Interpreter

    saved = os.dup(2)
    try:
        with open(os.devnull, "wb") as sink:
            os.dup2(sink.fileno(), 2)
            interpreter = Interpreter(model_path=str(MODELS / name), num_threads=1)
            interpreter.allocate_tensors()
    finally:
        os.dup2(saved, 2)
        os.close(saved)
    return interpreter


def _run(name: str, tensor: np.ndarray) -> dict[str, np.ndarray]:
    """Outputs of model ``name`` on ``tensor`` [1,H,W,3] float32, by output name."""
    interpreter = _interpreter(name)
    interpreter.set_tensor(interpreter.get_input_details()[0]["index"], tensor)
    interpreter.invoke()
    return {d["name"]: interpreter.get_tensor(d["index"])[0] for d in interpreter.get_output_details()}


def detect_people(image: np.ndarray, min_score: float = MIN_SCORE) -> list[Detection]:
    """Every person the detector finds in ``image`` [H,W,3] uint8 scoring at least ``min_score``
    (default: the detector's ``MIN_SCORE``), best first."""
    return decode(*_detector_outputs(image), min_score)


def _detector_outputs(image: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, int]:
    """The detector model's boxes [2254,12] and logits [2254] on ``image`` letterboxed, and the
    picture's width and height (``decode``'s arguments)."""
    from PIL import Image

    height, width = image.shape[:2]
    scale, dx, dy = letterbox(width, height)
    size = (max(1, round(width * scale)), max(1, round(height * scale)))
    small = Image.fromarray(np.asarray(image, np.uint8)).resize(size, Image.BILINEAR)
    tensor = np.full((INPUT, INPUT, 3), -1.0, np.float32)  # black padding, in the model's [-1, 1]
    x0, y0 = int(round(dx)), int(round(dy))
    tensor[y0:y0 + size[1], x0:x0 + size[0]] = np.asarray(small, np.float32) / 127.5 - 1.0
    out = _run("pose_detection.tflite", tensor[None])
    return out["Identity"], out["Identity_1"][:, 0], width, height


def person_in(image: np.ndarray, detection: Detection) -> Person:
    """The landmarks and mask of the person ``detection`` found in ``image`` [H,W,3] uint8."""
    from PIL import Image

    region = detection.region()
    picture = Image.fromarray(np.asarray(image, np.uint8))
    crop = picture.transform((CROP, CROP), Image.AFFINE, region.affine(CROP), Image.BILINEAR)
    out = _run("pose_landmark_full.tflite", (np.asarray(crop, np.float32) / 255.0)[None])
    raw = out["Identity"].reshape(-1, 5)[:len(LANDMARKS)]
    landmarks = region.to_picture(raw[:, :2] / CROP)
    c, s = np.cos(region.rotation), np.sin(region.rotation)
    world = out["Identity_4"].reshape(-1, 3)[:len(LANDMARKS)].astype(np.float64)
    world[:, :2] = world[:, :2] @ np.array([[c, s], [-s, c]])  # turned as the picture is
    return Person(detection, region, float(np.ravel(out["Identity_1"])[0]), landmarks,
                  expit(raw[:, 3].astype(np.float64)), world,
                  _mask_in_picture(expit(out["Identity_2"][..., 0]), region, image.shape[1], image.shape[0]))


def _mask_in_picture(mask: np.ndarray, region: Region, width: int, height: int) -> np.ndarray:
    """The region's mask [256,256] drawn back onto the picture [height,width] (0 outside the region)."""
    from PIL import Image

    c, s = np.cos(region.rotation), np.sin(region.rotation)
    k = CROP / region.side
    # crop pixel centre of a picture pixel centre q: (R^T (q - centre)) k + CROP / 2
    a, b, d, e = k * c, k * s, -k * s, k * c
    q0 = np.array([0.5, 0.5]) - region.centre
    f0 = a * q0[0] + b * q0[1] + CROP / 2 - 0.5
    f1 = d * q0[0] + e * q0[1] + CROP / 2 - 0.5
    back = Image.fromarray(mask.astype(np.float32), mode="F").transform(
        (width, height), Image.AFFINE, (a, b, f0, d, e, f1), Image.BILINEAR, fillcolor=0.0)
    return np.asarray(back, np.float32)


def find_person(image: np.ndarray) -> Person | None:
    """The most confident person in ``image`` [H,W,3] uint8: the detector's best detection when the
    landmark model says its region holds a person; else the next candidates (``CANDIDATES``, module
    constants) at a stricter presence; else the mirror image's best detection at the first rule, the
    person found there mirrored back (``_mirrored``); None when none holds one.

    The detector reads a picture and its mirror image differently: of the 5 posed renders (seed 101)
    where it found nobody, 4 have a person in the mirror image (presence 0.96-1.00), two of them at
    the detector's own score; the weaker candidates of a mirror image are not tried, since
    scikit-image's logo, mirrored, has one at presence 1.00 and crispness 0.92."""
    person = _find_person_once(image)
    if person is None:
        mirrored = _find_person_once(np.ascontiguousarray(image[:, ::-1]), candidates=False)
        person = None if mirrored is None else _mirrored(mirrored, image.shape[1])
    return person


def _find_person_once(image: np.ndarray, candidates: bool = True) -> Person | None:
    """``find_person`` on the picture as it is: the best detection, then (``candidates``) the weaker
    candidates."""
    outputs = _detector_outputs(image)  # the network once; its outputs decoded at both bars
    people = decode(*outputs)
    if people:
        person = person_in(image, people[0])
        if person.presence >= MIN_PRESENCE:
            return person
    for detection in decode(*outputs, CANDIDATE_SCORE)[:CANDIDATES] if candidates else []:
        person = person_in(image, detection)
        if person.presence >= CANDIDATE_PRESENCE and mask_crispness(person.mask) >= CANDIDATE_CRISPNESS:
            return person
    return None


#: Each landmark's mirror partner (left and right exchanged; the nose is its own).
MIRROR = np.array([LANDMARKS.index(n.replace("left", "#").replace("right", "left").replace("#", "right"))
                   for n in LANDMARKS])


def _mirrored(person: Person, width: int) -> Person:
    """The person found in a picture's mirror image, in the picture itself (``width`` pixels): every
    x becomes width - x (pixel edges, so a pixel's centre maps to its mirror's), regions turn the
    other way, the left and right landmarks exchange names (the mirror's left hand is the person's
    right), the world x (right) changes sign, the mask is flipped."""
    detection = person.detection
    box = detection.box.copy()
    box[[0, 2]] = width - detection.box[[2, 0]]
    keypoints = detection.keypoints.copy()
    keypoints[:, 0] = width - keypoints[:, 0]
    region = Region(np.array([width - person.region.centre[0], person.region.centre[1]]), person.region.side,
                    -person.region.rotation)
    landmarks = person.landmarks[MIRROR].copy()
    landmarks[:, 0] = width - landmarks[:, 0]
    world = person.world[MIRROR].copy()
    world[:, 0] = -world[:, 0]
    return Person(Detection(detection.score, box, keypoints), region, person.presence, landmarks,
                  person.visibility[MIRROR].copy(), world, np.ascontiguousarray(person.mask[:, ::-1]))


def mask_crispness(mask: np.ndarray) -> float:
    """The share of a soft person ``mask`` (0..1; its pixels over 0.05) that is over 0.5: near 1
    when the landmark model is sure where the person's edge runs."""
    return float((mask > 0.5).sum() / max((mask > 0.05).sum(), 1))
