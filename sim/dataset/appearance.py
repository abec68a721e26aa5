"""How a dataset sample looks: camera, cloth colour and print, skin, background, light.

Two appearance ranges: ``seen`` (train, validation, test) and ``unseen`` (the second test part),
which shares none of its cloth hues, prints, backgrounds or light directions with ``seen`` and
widens the camera's range, so that a network's robustness to appearance can be measured.

| | seen | unseen |
|---|---|---|
| cloth hue | outside the two held-out bands | in [0.08, 0.16) (orange) or [0.55, 0.63) (blue) |
| print | plain, stripes, checks | dots, waves |
| background | vertical two-colour gradient | speckled noise, another palette |
| light | 20-60 deg up, within 40 deg of the camera | 5-20 deg up, 40-75 deg to the side |
| camera yaw / pitch / distance | +-25 deg / +-3 deg / x0.9-1.15 | 25-40 / 4-10 deg up or down / x0.85-0.9 or 1.15-1.25 |

Cameras are framed per category (``darts.camera.FRAMES``) and jittered about the category's
default camera (``Camera.default``). The seen range keeps the camera level with the garment's
middle: every opening below the eye (hems, leg hems) is then seen from above and every opening
above it (waist, neckline) from below, so the part of a loop the camera cannot see lies behind
the garment or just beside it; from 4 degrees up or down a short garment's hem is seen from the
wrong side and its back half lands on the legs, several pixels off the garment's mask.
All positions are in the body's canonical frame (Y up, front +Z), metres.
"""
from __future__ import annotations

import colorsys
from dataclasses import dataclass

import numpy as np

from darts.camera import DISTANCE, FRAMES, IMAGE_SIZE, Camera, focal_for

HELD_OUT_HUES = ((0.08, 0.16), (0.55, 0.63))
SEEN_PRINTS = ("plain", "stripes", "checks")
UNSEEN_PRINTS = ("dots", "waves")
SKIN_TONES = np.array([[0.96, 0.80, 0.69], [0.90, 0.72, 0.58], [0.78, 0.57, 0.44], [0.62, 0.43, 0.31],
                       [0.45, 0.30, 0.21], [0.33, 0.22, 0.16]])


@dataclass
class Appearance:
    """Everything about a picture except the geometry."""

    camera: Camera
    cloth: tuple[float, float, float]
    cloth_second: tuple[float, float, float]
    print_kind: str
    print_period: float  # metres
    print_axis: int  # 0 x, 1 y, 2 z (stripes); phase of waves
    skin: tuple[float, float, float]
    background: tuple[tuple[float, float, float], tuple[float, float, float]]
    light: tuple[float, float, float]  # unit direction towards the light
    noise: float  # standard deviation of the pixel noise

    def as_dict(self) -> dict:
        out = {k: v for k, v in self.__dict__.items() if k != "camera"}
        return {k: (np.asarray(v).round(4).tolist() if isinstance(v, (tuple, np.ndarray)) else v) for k, v in out.items()}


def _hue(rng: np.random.Generator, unseen: bool) -> float:
    if unseen:
        low, high = HELD_OUT_HUES[rng.integers(2)]
        return float(rng.uniform(low, high))
    while True:
        hue = float(rng.uniform())
        if not any(low <= hue < high for low, high in HELD_OUT_HUES):
            return hue


def _colour(rng: np.random.Generator, hue: float, saturation=(0.25, 0.85), value=(0.3, 0.9)) -> tuple:
    return colorsys.hsv_to_rgb(hue, rng.uniform(*saturation), rng.uniform(*value))


def direction(yaw: float, up: float) -> np.ndarray:
    """The unit vector turned ``yaw`` about the vertical from +Z (the body's front) and ``up`` above
    the horizontal (radians; canonical frame, Y up)."""
    return np.array([np.sin(yaw) * np.cos(up), np.sin(up), np.cos(yaw) * np.cos(up)])


def _camera(rng: np.random.Generator, category: str, unseen: bool, size: int) -> Camera:
    """The category's default camera (``Camera.default``) moved about its target: yaw about the
    vertical, pitch up (> 0: from above, looking down), distance and focal length scaled, target
    shifted up to 3 cm."""
    centre, extent = FRAMES[category]
    if unseen:
        yaw = np.deg2rad(rng.uniform(25, 40)) * rng.choice([-1, 1])
        pitch = np.deg2rad(rng.uniform(4, 10)) * rng.choice([-1, 1])
        distance = DISTANCE * (rng.uniform(0.85, 0.9) if rng.uniform() < 0.5 else rng.uniform(1.15, 1.25))
    else:
        yaw, pitch = np.deg2rad(rng.uniform(-25, 25)), np.deg2rad(rng.uniform(-3, 3))
        distance = DISTANCE * rng.uniform(0.9, 1.15)
    target = np.asarray(centre) + rng.uniform(-0.03, 0.03, 3)
    eye = target + distance * direction(yaw, pitch)
    focal = focal_for(extent, size, distance) * rng.uniform(0.92, 1.08)
    return Camera.look_at(eye, target, size, size, focal)


def sample_appearance(rng: np.random.Generator, category: str, unseen: bool, size: int = IMAGE_SIZE) -> Appearance:
    """A random appearance from the ``seen`` or ``unseen`` range (module docstring)."""
    camera = _camera(rng, category, unseen, size)
    hue = _hue(rng, unseen)
    cloth = _colour(rng, hue)
    second = _colour(rng, (hue + rng.uniform(0.3, 0.7)) % 1.0 if not unseen else _hue(rng, True))
    kind = str(rng.choice(UNSEEN_PRINTS if unseen else SEEN_PRINTS))
    skin = tuple(np.clip(SKIN_TONES[rng.integers(len(SKIN_TONES))] * rng.uniform(0.95, 1.05, 3), 0, 1))
    if unseen:
        background = (_colour(rng, rng.uniform(), (0.4, 0.9), (0.15, 0.5)), _colour(rng, rng.uniform(), (0.4, 0.9), (0.5, 0.9)))
        up, side = np.deg2rad(rng.uniform(5, 20)), np.deg2rad(rng.uniform(40, 75)) * rng.choice([-1, 1])
    else:
        background = (_colour(rng, rng.uniform(), (0.0, 0.35), (0.55, 1.0)), _colour(rng, rng.uniform(), (0.0, 0.35), (0.3, 0.8)))
        up, side = np.deg2rad(rng.uniform(20, 60)), np.deg2rad(rng.uniform(-40, 40))
    view = camera.centre - np.asarray(FRAMES[category][0])
    yaw = np.arctan2(view[0], view[2]) + side
    light = direction(yaw, up)
    return Appearance(camera, cloth, second, kind, float(rng.uniform(0.02, 0.06)), int(rng.integers(3)), skin,
                      background, tuple(light), float(rng.uniform(0.0, 0.02)))


def cloth_albedo(points: np.ndarray, look: Appearance) -> np.ndarray:
    """Cloth colour [N,3] at canonical points: the print is a solid texture (a function of the 3D
    point on the rest-frame garment), so it needs no UV layout."""
    a, b, p = np.asarray(look.cloth), np.asarray(look.cloth_second), look.print_period
    if look.print_kind == "plain":
        second = np.zeros(len(points), bool)
    elif look.print_kind == "stripes":
        second = np.floor(points[:, look.print_axis] / p).astype(int) % 2 == 1
    elif look.print_kind == "checks":
        second = np.floor(points / p).astype(int).sum(1) % 2 == 1
    elif look.print_kind == "dots":
        cell = points / p - np.round(points / p)
        second = np.linalg.norm(cell, axis=1) < 0.3
    else:  # waves
        second = np.sin(2 * np.pi * points[:, 1] / p + 3.0 * np.sin(2 * np.pi * points[:, 0] / (2 * p))) > 0.3
    return np.where(second[:, None], b, a)


def background(look: Appearance, rng: np.random.Generator, size: int, unseen: bool) -> np.ndarray:
    """Background image [size, size, 3]: a vertical gradient (seen) or speckled noise (unseen)."""
    top, bottom = (np.asarray(c) for c in look.background)
    t = np.linspace(0, 1, size)[:, None, None]
    image = np.broadcast_to((1 - t) * top + t * bottom, (size, size, 3)).copy()
    if unseen:
        coarse = rng.uniform(0, 1, (size // 8 + 1, size // 8 + 1))
        blobs = np.kron(coarse, np.ones((8, 8)))[:size, :size, None]
        image = (1 - blobs) * top + blobs * bottom
    return image
