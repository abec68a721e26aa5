"""The layers of a model joined from several garments (``ClothModel.layer``, inner first): how far
each particle keeps off the body, given the garments under it where it is now.

A particle of an outer garment within ``COVER`` of an inner garment's surface keeps ``LAYER_OFFSET``
thicknesses more off the body per such garment (``covering_offsets``); ``Simulation.step_frame``
sets these at the start of every frame of a layered model, so the body contact holds each layer
over the ones under it.
"""
from __future__ import annotations

import numpy as np

from sim.engine.model import ClothModel

#: metres from an inner garment within which an outer particle counts as covering it
COVER = 0.03
#: thicknesses a particle keeps off the body beyond its own, per inner garment within ``COVER`` of it
LAYER_OFFSET = 1.0


def covering_offsets(model: ClothModel, particles: np.ndarray) -> np.ndarray:
    """``body_offset`` [P] (m) for ``model``'s particles at ``particles`` [P,3] (world frame): one
    ``LAYER_OFFSET`` thickness per inner garment whose surface is within ``COVER`` of the particle."""
    from darts.geometry.distance import SurfaceDistance

    thickness = float(model.material["thickness"])
    offset = np.zeros(len(particles))
    for j in range(int(model.layer.max())):
        surface = SurfaceDistance(particles, model.faces[model.layer[model.faces[:, 0]] == j])
        outer = np.flatnonzero(model.layer > j)
        gap, _, _ = surface.query(particles[outer], max_dist=COVER, winding=False)
        offset[outer[np.abs(gap) < 0.99 * COVER]] += LAYER_OFFSET * thickness
    return offset
