"""The layers of a model joined from several garments (``ClothModel.layer``, inner first): how far
each particle keeps off the body, given the garments under it where it is now.

A particle of an outer garment within ``COVER`` of an inner garment's surface keeps ``LAYER_OFFSET``
thicknesses more off the body per such garment (``covering_offsets``); ``Simulation.step_frame``
sets these at the start of every frame of a layered model, so the body contact holds each layer
over the ones under it. ``LayerCover`` does the same on the simulation's device, with no copy of
the particles to the host: the same query, the same offsets to the bit.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.engine.model import ClothModel
from sim.engine.state import float_array, int_array

wp = warp()

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


@wp.kernel
def _count_covers(mesh: wp.uint64, x: wp.array(dtype=wp.vec3), layer: wp.array(dtype=wp.int32), inner: int,
                  cover: float, count: wp.array(dtype=wp.int32)):
    """count[i] += 1 where particle i lies in a layer over ``inner`` and within 0.99 ``cover`` of the
    inner layer's triangles (``mesh``), as ``covering_offsets`` asks."""
    i = wp.tid()
    if layer[i] <= inner:
        return
    query = wp.mesh_query_point_sign_normal(mesh, x[i], cover)
    if query.result and wp.length(x[i] - wp.mesh_eval_position(mesh, query.face, query.u, query.v)) < 0.99 * cover:
        count[i] += 1


@wp.kernel
def _offsets_of_counts(count: wp.array(dtype=wp.int32), table: wp.array(dtype=float), offset: wp.array(dtype=float),
                       most: wp.array(dtype=wp.int32)):
    """offset[i] = table[count[i]], and the largest count."""
    i = wp.tid()
    offset[i] = table[count[i]]
    wp.atomic_max(most, 0, count[i])


class LayerCover:
    """``covering_offsets`` of a layered ``model`` whose particles are the device array ``x``: one
    BVH per inner layer over its triangles, refit each time; ``offsets(out)`` writes each particle's
    offset into ``out`` and returns the largest (m), one number read back."""

    def __init__(self, model: ClothModel, x, device: str):
        self.x, self.device, self.count = x, device, len(model.rest)
        face_layer = model.layer[model.faces[:, 0]]
        self.meshes = [wp.Mesh(points=x, indices=int_array(model.faces[face_layer == j].reshape(-1), device))
                       for j in range(int(model.layer.max()))]
        self.layer = int_array(model.layer, device)
        step = LAYER_OFFSET * float(model.material["thickness"])
        self.table_host = np.cumsum([0.0] + [step] * len(self.meshes))  # k covers: k steps, added as the host adds them
        self.table = float_array(self.table_host, device)
        self.covers = wp.zeros(self.count, dtype=wp.int32, device=device)
        self.most = wp.zeros(1, dtype=wp.int32, device=device)

    def offsets(self, out) -> float:
        self.covers.zero_()
        self.most.zero_()
        for inner, mesh in enumerate(self.meshes):
            mesh.refit()
            wp.launch(_count_covers, dim=self.count, inputs=[mesh.id, self.x, self.layer, inner, COVER, self.covers],
                      device=self.device)
        wp.launch(_offsets_of_counts, dim=self.count, inputs=[self.covers, self.table, out, self.most], device=self.device)
        return float(self.table_host[int(self.most.numpy()[0])])
