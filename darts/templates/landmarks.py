"""Body landmarks in the canonical rest (T-) pose, and the candidate feature-line cuts F_smpl.

Every cut is a scalar field on the body surface whose zero set is the feature line; a garment
keeps the side where the field is <= 0. Fields restricted to a region combine a plane with the
region by ``min`` so the zero set stays a closed loop.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Landmarks:
    """Joint positions and heights (metres, canonical frame: Y up, front +Z, left +X)."""

    joints: dict[str, np.ndarray]
    crotch_y: float
    front_z: float  # the frontal plane z = front_z splits garments into front and back

    def j(self, name: str) -> np.ndarray:
        return self.joints[name]

    @property
    def waist_y(self) -> float:
        return float(self.j("spine1")[1])

    @property
    def knee_y(self) -> float:
        return float(0.5 * (self.j("left_knee")[1] + self.j("right_knee")[1]))

    @property
    def ankle_y(self) -> float:
        return float(0.5 * (self.j("left_ankle")[1] + self.j("right_ankle")[1]))

    @property
    def armpit_y(self) -> float:
        return float(0.5 * (self.j("left_shoulder")[1] + self.j("right_shoulder")[1]) - 0.1)

    def arm_point(self, side: str, position: float) -> tuple[np.ndarray, np.ndarray]:
        """A point and the bone direction along the arm: position 0 = shoulder, 1 = elbow, 2 = wrist."""
        chain = [self.j(f"{side}_shoulder"), self.j(f"{side}_elbow"), self.j(f"{side}_wrist")]
        k = min(int(position), 1)
        axis = chain[k + 1] - chain[k]
        return chain[k] + (position - k) * axis, axis / np.linalg.norm(axis)


def landmarks(vertices: np.ndarray, joints: np.ndarray, joint_names: list[str]) -> Landmarks:
    """Landmarks of a body in its canonical rest pose (vertices [V,3], joints [J,3])."""
    named = {name: joints[i] for i, name in enumerate(joint_names)}
    pelvis = named["pelvis"]
    centre = (np.abs(vertices[:, 0] - pelvis[0]) < 0.012) & (vertices[:, 1] < pelvis[1])
    crotch_y = float(vertices[centre, 1].min()) if centre.any() else float(pelvis[1] - 0.1)
    front_z = float(0.5 * (named["left_shoulder"][2] + named["left_hip"][2]))
    return Landmarks(named, crotch_y, front_z)


# --- cut fields: positive where the garment is removed -------------------------------------------

def neckline_field(lm: Landmarks, points: np.ndarray, drop: float = 0.0) -> np.ndarray:
    """Above a plane through the neck joint tilted 19 deg forwards (front lower), near the neck."""
    neck = lm.j("neck") - [0.0, drop, 0.0]
    tilt = np.array([0.0, 1.0, 0.35]) / np.linalg.norm([0.0, 1.0, 0.35])
    inside = 1.0 - ((points[:, 0] - neck[0]) / 0.09) ** 2 - ((points[:, 2] - neck[2]) / 0.2) ** 2
    return np.minimum((points - neck) @ tilt, 0.1 * inside)


def arm_field(lm: Landmarks, points: np.ndarray, side: str, position: float) -> np.ndarray:
    """Beyond the plane across the ``side`` arm at ``position`` (0 shoulder, 1 elbow, 2 wrist)."""
    centre, axis = lm.arm_point(side, position)
    band = points[:, 1] - (lm.j(f"{side}_shoulder")[1] - 0.2)
    return np.minimum((points - centre) @ axis, band)


def below_field(height: float, points: np.ndarray) -> np.ndarray:
    """Below y = height."""
    return height - points[:, 1]


def above_field(height: float, points: np.ndarray) -> np.ndarray:
    """Above y = height."""
    return points[:, 1] - height
