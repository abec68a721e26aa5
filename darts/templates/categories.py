"""The ten garment categories of DeepFashion3D, with short stable ids for the CLI.

A category says which body cuts make its surface (its feature lines), where its seams run, and how
long it is. Lengths are set from body landmarks, so templates fit any body shape.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from darts.templates.defaults import DEFAULT_EASE, SEAT_EASE, WEARING_EASE
from darts.templates.landmarks import Landmarks

SIDES = ("left", "right")


@dataclass(frozen=True)
class Category:
    """family: top | dress | pants | skirt. sleeve: the cuff's position along the arm (0 at the
    shoulder joint = sleeveless armhole, 1 elbow, 2 wrist), None without sleeves. hem: height of
    the hem (tops, dresses, skirts) or of the leg hems (pants) from the landmarks. seat_ease: the
    cloth's distance off the body below the waistband (m; a sitting allowance), None for the
    template's ease (``ease``) everywhere."""

    id: str
    family: str
    description: str
    hem: Callable[[Landmarks], float]
    sleeve: float | None = None
    seat_ease: float | None = None

    @property
    def ease(self) -> float:
        """The cloth's distance off the body (m): tops and dresses a wearing ease, skirts and
        trousers (at the waistband) ``DEFAULT_EASE``."""
        return WEARING_EASE if self.family in ("top", "dress") else DEFAULT_EASE

    @property
    def line_names(self) -> list[str]:
        if self.family in ("top", "dress"):
            return ["neckline", "left_cuff", "right_cuff", "hem"]
        if self.family == "pants":
            return ["waist", "left_hem", "right_hem"]
        return ["waist", "hem"]

    @property
    def sleeved(self) -> bool:
        return self.sleeve is not None and self.sleeve > 0


def _top_hem(lm: Landmarks) -> float:
    return lm.crotch_y + 0.07


def _dress_hem(lm: Landmarks) -> float:
    return lm.knee_y + 0.06


CATEGORIES: dict[str, Category] = {c.id: c for c in [
    Category("long-sleeve-top", "top", "long-sleeve top, hem at the hips", _top_hem, sleeve=1.92),
    Category("short-sleeve-top", "top", "short-sleeve top (T-shirt), hem at the hips", _top_hem, sleeve=0.45),
    Category("sleeveless-top", "top", "no-sleeve top, armholes at the shoulder joints", _top_hem, sleeve=0.0),
    Category("long-sleeve-dress", "dress", "long-sleeve dress, knee length", _dress_hem, sleeve=1.92),
    Category("short-sleeve-dress", "dress", "short-sleeve dress, knee length", _dress_hem, sleeve=0.45),
    Category("sleeveless-dress", "dress", "no-sleeve dress, knee length", _dress_hem, sleeve=0.0),
    Category("long-pants", "pants", "long pants (trousers), hems above the ankles", lambda lm: lm.ankle_y + 0.04,
             seat_ease=SEAT_EASE),
    Category("short-pants", "pants", "short pants (shorts), hems at mid-thigh", lambda lm: lm.crotch_y - 0.12,
             seat_ease=SEAT_EASE),
    Category("long-skirt", "skirt", "long skirt, hem at mid-calf", lambda lm: lm.knee_y - 0.18),
    Category("short-skirt", "skirt", "short skirt, hem at mid-thigh", lambda lm: lm.crotch_y - 0.14),
]}


# --- seams: a field whose zero set carries the seam, and a namer for each edge on it ----------------

@dataclass(frozen=True)
class SeamField:
    """Edges on the zero set of ``field`` become seams named by ``name(midpoints) -> names``
    (an empty name means: no seam there)."""

    field: Callable[[np.ndarray], np.ndarray]
    name: Callable[[np.ndarray], np.ndarray]


def _by_side(points: np.ndarray, left: str, right: str) -> np.ndarray:
    return np.where(points[:, 0] >= 0, left, right)


def seam_fields(category: Category, lm: Landmarks) -> list[SeamField]:
    """The predefined seams of a category on a body with landmarks ``lm``."""
    fields: list[SeamField] = []
    front = lambda p: p[:, 2] - lm.front_z  # noqa: E731  (the frontal plane)
    waistband_y = lm.waist_y - 0.045
    if category.family in ("top", "dress"):
        armholes = {s: lm.arm_point(s, 0.0) for s in SIDES}

        def in_sleeve(p, side):
            centre, axis = armholes[side]
            return ((p - centre) @ axis > 0) & (np.sign(p[:, 0]) == np.sign(centre[0])) & category.sleeved

        def front_back(p):
            side = np.where(p[:, 0] >= 0, "left", "right")
            sleeve = np.where(side == "left", in_sleeve(p, "left"), in_sleeve(p, "right"))
            arm_y = np.where(side == "left", lm.j("left_shoulder")[1], lm.j("right_shoulder")[1])
            names = np.where(p[:, 1] < lm.armpit_y, np.char.add(side, "_side"), np.char.add(side, "_shoulder"))
            underarm = np.where(p[:, 1] < arm_y, np.char.add(side, "_underarm"), "")
            return np.where(sleeve, underarm, names)

        fields.append(SeamField(front, front_back))
        if category.sleeved:
            for side in SIDES:
                centre, axis = lm.arm_point(side, 0.0)
                band = lm.j(f"{side}_shoulder")[1] - 0.2
                fields.append(SeamField(
                    lambda p, c=centre, a=axis: (p - c) @ a,
                    lambda p, s=side, b=band, c=centre:
                        np.where((p[:, 1] > b) & (np.sign(p[:, 0]) == np.sign(c[0])), f"{s}_armhole", "")))
    if category.family == "dress":
        fields.append(SeamField(lambda p: p[:, 1] - lm.waist_y, lambda p: np.full(len(p), "waist")))
        fields.append(SeamField(lambda p: p[:, 0] - lm.j("pelvis")[0],
                                lambda p: np.where(p[:, 2] < lm.front_z, "centre_back", "")))
    if category.family == "skirt":
        fields.append(SeamField(front, lambda p: np.where(p[:, 1] < waistband_y, _by_side(p, "left_side", "right_side"), "")))
    if category.family == "pants":
        def legs(p):
            side = np.where(p[:, 0] >= 0, "left", "right")
            knee_x = np.where(side == "left", lm.j("left_knee")[0], lm.j("right_knee")[0])
            inner = (np.abs(p[:, 0]) < np.abs(knee_x)) & (p[:, 1] < lm.crotch_y + 0.05)
            names = np.where(inner, np.char.add(side, "_inseam"), np.char.add(side, "_outseam"))
            return np.where(p[:, 1] < waistband_y, names, "")

        fields.append(SeamField(front, legs))
        fields.append(SeamField(lambda p: p[:, 0] - lm.j("pelvis")[0],
                                lambda p: np.where(p[:, 1] >= waistband_y, "",
                                                   np.where(p[:, 2] >= lm.front_z, "centre_front", "centre_back"))))
    if category.family in ("pants", "skirt"):
        fields.append(SeamField(lambda p: p[:, 1] - waistband_y, lambda p: np.full(len(p), "waistband")))
    return fields
