"""Garment parsing of a photographed person (``darts.photo.parsing``) and the garments read from it
(``darts.photo.attributes``), on renders of the default body whose garments are painted on with
known extents: the labels, the sleeve and hem ends and the categories must come back."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from darts.body.segmentation import PART_INDEX, body_segmentation
from darts.camera import Camera
from darts.photo.attributes import ARM, LEG, _project, chain, garments_seen, point_at
from darts.photo.fit import FLIP, landmark_table
from darts.photo.parsing import DRESS, LOWER, UPPER, parse_person, part_image
from darts.photo.person import LANDMARKS

SKIN, TOP, PANTS, SHOES, HAIR, BACK = (205, 150, 120), (40, 110, 60), (40, 50, 120), (20, 20, 20), (60, 40, 25), (225, 225, 230)
WIDTH, HEIGHT = 240, 320


@pytest.fixture(scope="module")
def scene():
    """The default body in its rest pose seen from the front: the part at each pixel, BlazePose-like
    landmarks (the calibrated landmark points projected) and the camera."""
    from darts import api

    body = api.load_body()
    vertices, joints = (a[0].double().numpy() for a in body.shaped())
    camera = Camera(WIDTH, HEIGHT, 300.0, 300.0, WIDTH / 2, HEIGHT / 2 + 10, FLIP.copy(), np.array([0.0, 0.0, 3.2]))
    labels = body_segmentation(body)
    parts = part_image(vertices, np.asarray(body.faces), labels, camera)
    names, offsets = landmark_table()
    points = np.array([joints[body.joint_names.index(j)] for j in names]) + offsets
    landmarks, _ = camera.project(points)
    return body, vertices, labels, parts, landmarks, camera


def _limb_s(landmarks: np.ndarray, side: str, joints) -> np.ndarray:
    """s along the limb (0 shoulder or hip, 1 wrist or ankle) of every pixel [H,W]."""
    polyline = chain(landmarks, side, joints)
    rows, cols = np.mgrid[:HEIGHT, :WIDTH]
    s, _ = _project(np.stack([cols.ravel() + 0.5, rows.ravel() + 0.5], 1), polyline)
    return s.reshape(HEIGHT, WIDTH)


def _dress_up(scene, sleeve: float, hem: float | None, dress: bool = False):
    """(picture, person mask, true upper mask, true lower mask): the body painted with a top whose
    sleeves end at s = ``sleeve`` (0: none) and trousers to s = ``hem`` (None: none); with ``dress``
    the top's cloth runs to the hem, filling the gap between the legs."""
    _, _, _, parts, landmarks, _ = scene
    names = np.array(list(PART_INDEX))
    part = np.where(parts >= 0, names[np.maximum(parts, 0)], "")
    image = np.empty((HEIGHT, WIDTH, 3), np.uint8)
    image[:] = BACK
    person = parts >= 0
    image[person] = SKIN
    image[np.isin(part, ["head"]) & (np.mgrid[:HEIGHT, :WIDTH][0] < landmarks[LANDMARKS.index("left_eye")][1] - 4)] = HAIR
    image[np.isin(part, ["left_foot", "right_foot"])] = SHOES
    upper = np.isin(part, ["upper_torso", "lower_torso"])
    for side in ("left", "right"):
        arm = np.isin(part, [f"{side}_upper_arm", f"{side}_forearm"])
        upper |= arm & (_limb_s(landmarks, side, ARM) < sleeve)
    lower = np.zeros_like(person)
    if hem is not None:
        lower = np.isin(part, ["hips"])
        for side in ("left", "right"):
            lower |= np.isin(part, [f"{side}_thigh", f"{side}_calf"]) & (_limb_s(landmarks, side, LEG) < hem)
    if dress:  # the skirt spans the legs from the hips to the hem, a little wider than they are
        from matplotlib.path import Path as Polygon
        from scipy import ndimage

        left, right = (chain(landmarks, side, LEG) for side in ("left", "right"))
        steps = np.linspace(0.0, hem, 12)
        outline = [point_at(left, t) for t in steps] + [point_at(right, t) for t in steps[::-1]]
        rows, cols = np.mgrid[:HEIGHT, :WIDTH]
        between = Polygon(np.array(outline)).contains_points(np.stack([cols.ravel() + 0.5, rows.ravel() + 0.5], 1))
        between = ndimage.binary_dilation(between.reshape(HEIGHT, WIDTH), iterations=4) & (rows < point_at(left, hem)[1])
        lower |= between
        person = person | between
        upper, lower = upper | lower, np.zeros_like(lower)
    image[upper] = TOP
    image[lower] = PANTS
    return image, person.astype(np.float32), upper, lower


def _read(scene, image, person):
    body, vertices, labels, _, landmarks, camera = scene
    parsing = parse_person(image, person, landmarks, np.ones(len(landmarks)), vertices, np.asarray(body.faces), labels,
                           camera)
    garments, notes, read = garments_seen(parsing, landmarks)
    return read, (garments, notes)


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / max((a | b).sum(), 1))


def test_parsing_labels_a_top_and_trousers_and_reads_their_categories(scene):
    image, person, upper, lower = _dress_up(scene, sleeve=0.25, hem=0.97)
    parsing, (garments, notes) = _read(scene, image, person)
    assert not parsing.one_piece
    assert _iou(parsing.mask(UPPER, WIDTH, HEIGHT), upper) > 0.85
    assert _iou(parsing.mask(LOWER, WIDTH, HEIGHT), lower) > 0.85
    assert [(g.kind, g.category) for g in garments] == [("lower", "long-pants"), ("upper", "short-sleeve-top")]
    assert all(g.probability > 0.6 for g in garments) and notes == []


@pytest.mark.parametrize("cuff, category", [(0.0, "sleeveless-top"), (0.3, "short-sleeve-top"), (0.7, "long-sleeve-top"),
                                            (0.97, "long-sleeve-top")])
def test_the_sleeve_end_is_read_where_the_cuff_is(scene, cuff, category):
    image, person, _, _ = _dress_up(scene, sleeve=cuff, hem=0.4)
    _, (garments, _) = _read(scene, image, person)
    top = garments[-1]
    assert top.kind == "upper" and top.category == category
    assert top.attributes["sleeve_end"] == pytest.approx(cuff, abs=0.1)
    assert garments[0].category == "short-pants" and garments[0].attributes["hem_end"] == pytest.approx(0.4, abs=0.1)


def test_one_cloth_filling_the_gap_between_the_legs_is_a_dress(scene):
    image, person, dress, _ = _dress_up(scene, sleeve=0.0, hem=0.45, dress=True)
    parsing, (garments, _) = _read(scene, image, person)
    assert parsing.one_piece and [(g.kind, g.category) for g in garments] == [("dress", "sleeveless-dress")]
    assert _iou(parsing.mask(DRESS, WIDTH, HEIGHT), dress) > 0.85
    assert garments[0].attributes["between_legs_fill"] > 0.8


def test_lengths_read_place_the_lines_at_the_measured_ends(scene):
    """A top read with sleeves to s = 0.7 and a hem at s = 0.35 down the body's middle line (a cropped
    top): its cuffs move out along the arms to the point 40 % of the way from elbow to wrist, its hem
    up to that level; an end that runs out of the picture only lengthens."""
    from darts.dart.io import load_dart
    from darts.photo.lengths import length_targets, place_lines, rest_landmarks
    from darts.regress.posed_lines import template_lines
    from darts.templates.categories import CATEGORIES

    body = scene[0]
    template = load_dart(Path(__file__).parents[1] / "scenes" / "garments" / "short-sleeve-top.npz")
    names = CATEGORIES["short-sleeve-top"].line_names
    lines = dict(zip(names, template_lines(template, "short-sleeve-top")))
    centre = template.vertices.mean(0)
    attributes = {"sleeve_end": 0.7, "top_hem_end": 0.35}
    targets = length_targets("short-sleeve-top", attributes, body, None)
    placed, report = place_lines(lines, targets, centre)
    points = rest_landmarks(body, None)
    wrist_side = point_at(chain(points, "left", ARM), 0.7)
    assert np.allclose(targets["left_cuff"]["point"], wrist_side)
    assert abs(placed["left_cuff"].mean(0)[0] - wrist_side[0]) < 0.02  # the arm runs along +X at rest
    assert report["left_cuff"]["moved_cm"] > 10 and report["hem"]["moved_cm"] < -5
    assert placed["hem"].mean(0)[1] == pytest.approx(targets["hem"]["point"][1], abs=0.01)
    assert np.allclose(placed["neckline"], lines["neckline"])
    beyond = length_targets("short-sleeve-top", {"sleeve_end": 0.1, "sleeve_beyond_picture": True}, body, None)
    kept, report = place_lines(lines, beyond, centre)
    assert report["left_cuff"]["moved_cm"] == 0 and np.allclose(kept["left_cuff"], lines["left_cuff"])
