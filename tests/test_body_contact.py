"""Body contact: a cloth moving fast enough to pass a thin body part between two contact searches
stays on the side it came from (continuous collision), and tunnels through without it."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from sim.model import cloth_model
from sim.settings import SimSettings
from sim.solver import ClothSolver
from tests.helpers import sheet_dart

SPEED = 10.0  # m/s, downwards: 3.3 cm a substep at 30 fps x 10 substeps
PLATE = 0.02  # m, thickness of the body: a plate with its top at z = 0


def _square_sheet(side: int, spacing: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """A horizontal square grid of side x side vertices, centred over the origin at ``height``."""
    t = (np.arange(side) - (side - 1) / 2) * spacing
    vertices = np.array([[a, b, height] for a in t for b in t])
    faces = []
    for i in range(side - 1):
        for j in range(side - 1):
            a, b, c, d = i * side + j, i * side + j + 1, (i + 1) * side + j, (i + 1) * side + j + 1
            faces += [[a, c, d], [a, d, b]]
    return vertices, np.array(faces)


def _throw_at_plate(height: float, continuous: bool, frames: int = 6) -> tuple[np.ndarray, float]:
    """Throw a 10 cm sheet from ``height`` above the plate at SPEED; heights (m) of its particles
    after ``frames`` frames, and the material thickness."""
    plate = trimesh.creation.box(extents=(0.4, 0.4, PLATE), transform=trimesh.transformations.translation_matrix(
        (0.0, 0.0, -PLATE / 2)))
    model = cloth_model(sheet_dart(*_square_sheet(11, 0.01, height)))
    settings = SimSettings(substeps=10, iterations=4, ground=False, air_density=0.0, self_contact=False,
                           continuous_collision=continuous)
    solver = ClothSolver(model, model.rest, np.asarray(plate.faces), np.asarray(plate.vertices), settings)
    solver.v.assign(np.tile(np.float32([0.0, 0.0, -SPEED]), (solver.count, 1)))
    for _ in range(frames):
        solver.step_frame(np.asarray(plate.vertices))
    return solver.positions()[:, 2], solver.thickness


#: Start heights (m) at which, without continuous collision, the sheet is found past the plate's
#: middle at a search (pushed out below) or already through it (not inside at all).
HEIGHTS = (0.05, 0.07)


@pytest.mark.parametrize("height", HEIGHTS)
def test_a_fast_sheet_lands_on_a_thin_plate(height):
    z, thickness = _throw_at_plate(height, continuous=True)
    assert np.all(np.abs(z - thickness) < 0.1 * thickness)  # resting on top, a thickness up


@pytest.mark.parametrize("height", HEIGHTS)
def test_without_continuous_collision_it_tunnels(height):
    """The closest-point contact alone lets every particle through (the test above can fail)."""
    z, _ = _throw_at_plate(height, continuous=False)
    assert np.all(z < -PLATE)
