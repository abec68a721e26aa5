"""Self-contact of the garment: vertex-triangle repulsion with side memory, and a crossing count.

Every search (every ``self_contact_interval`` substeps) refits a BVH over the garment's
own triangles (the particle array itself, so never rebuilt) and gives each particle its closest
triangle within reach that is not its neighbour on the rest garment, with the side it is on: from
the candidate triangles a broad phase listed for it (every ``self_contact_broad_interval``
substeps), or from the BVH for a particle too fast for a list. Each
sweep then keeps the particle ``separation`` away from that triangle's plane on that side, sharing
the correction with the triangle's corners by inverse mass and barycentric weight (an XPBD contact
with zero compliance). Remembering the side means a particle that has already passed the plane is
pulled back instead of pushed through; the side carries over when the particle slides on to a
neighbouring triangle of a smooth layer. Edges get the same treatment against the edges of the
garment triangles near them (closest points of two segments, both inside their segments, kept
``separation`` apart along the edges' common normal on the side they started on), which catches
two layers whose edges slide through each other between vertices. All corrections of a sweep are
averaged per particle before they are applied. Between two garments of an outfit the side is not
remembered but known, outer over inner (every garment's triangles face away from the body), so a
particle or edge that has passed through another garment is pulled back out.

What the contacts let through anyway (a fold pushed past the search's reach is forgotten, and one
found on the wrong side is then held there) is untangled: the edges that pass through a garment
triangle, found at each broad phase, and those triangles are moved apart a little every substep, the
way that shortens the contour where the garment cuts itself (intersection contour minimisation,
Volino and Magnenat-Thalmann 2006), until the cut is gone.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.engine.launch import Launcher
from sim.engine.self_contact_kernels import (
    SPEED_BINS,
    apply_averaged,
    crossings_per_world,
    find_crossings,
    find_edge_contacts,
    find_self_contacts,
    gather_candidates,
    histogram_medians,
    resolve_edge_contacts,
    resolve_self_contacts,
    self_friction,
    speed_histogram,
    untangle_crossings,
    world_means,
    world_velocity_sums,
)
from sim.engine.state import on_cpu

wp = warp()

#: candidate triangles kept per particle by the broad phase (the nearest)
MAX_CANDIDATES = 16


def host_speeds(v, world: np.ndarray, max_speed: float) -> tuple[np.ndarray, np.ndarray]:
    """Per world w (``world`` [P]: each particle's): (the mean velocity v̄_w [W,3], the median of
    |v_i - v̄_w| capped at ``max_speed`` [W]) over its finite velocities ``v`` [P] (a blown-up
    particle, the run about to stop, aside; zeros for a world with none)."""
    velocities = v.numpy()
    count = int(world.max(initial=0)) + 1
    mean, spread = np.zeros((count, 3), np.float32), np.zeros(count, np.float32)
    finite = np.isfinite(velocities).all(axis=1)
    for w in range(count):
        mine = velocities[finite & (world == w)]
        if len(mine):
            mean[w] = mine.mean(axis=0)
            offset = mine - mean[w]
            spread[w] = min(float(np.median(np.sqrt(np.einsum("ij,ij->i", offset, offset)))), max_speed)
    return mean, spread


def edge_faces(edges: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """[E,2]: the triangles of ``faces`` [F,3] on the two sides of each edge of ``edges`` [E,2]
    (-1 where there is none: the second of a boundary edge, both of a pair that is no triangle's
    edge), by the undirected edge keys of ``darts.geometry.mesh.half_edges`` (half-edge h is face
    h // 3's)."""
    from darts.geometry.mesh import half_edges

    faces = np.asarray(faces, np.int64)
    _, _, key = half_edges(faces)
    base = int(faces.max()) + 1
    low, high = np.sort(np.asarray(edges, np.int64), axis=1).T
    wanted = low * base + high
    order = np.argsort(key, kind="stable")
    sorted_keys = key[order]
    first = np.searchsorted(sorted_keys, wanted, side="left")
    found = np.full((len(wanted), 2), -1, np.int32)
    for side in range(2):
        at = np.minimum(first + side, len(order) - 1)
        hit = (high < base) & (first + side < len(order)) & (sorted_keys[at] == wanted)
        found[:, side] = np.where(hit, order[at] // 3, -1)
    return found


def vertex_edge_lists(edges: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Edges at each vertex as CSR: vertex v's edge indices are incident[start[v]:start[v + 1]]."""
    ends = np.asarray(edges, np.int64).reshape(-1)
    incident = np.argsort(ends, kind="stable") // 2
    start = np.concatenate([[0], np.cumsum(np.bincount(ends, minlength=count))])
    return start.astype(np.int32), incident.astype(np.int32)


class SelfContact:
    """The garment's self-contact state on the device; positions are the solver's particle array."""

    def __init__(self, x, rest: np.ndarray, faces: np.ndarray, edges: np.ndarray, separation: float,
                 exclusion: float, device: str, layer: np.ndarray | None = None, record: bool = True,
                 world: np.ndarray | None = None):
        self.x, self.device, self.count = x, device, x.shape[0]
        self.launch = Launcher(device, record)
        self.separation, self.exclusion = float(separation), float(exclusion)
        self.side_carry = float(exclusion)  # m on the rest garment within which a side carries over
        self.reach = float(exclusion)
        self.edge_edge = True  # edge-edge contacts too (off only to show what they add)
        self.faces = wp.array(np.ascontiguousarray(faces, np.int32), dtype=wp.int32, device=device)
        self.edges = wp.array(np.ascontiguousarray(edges, np.int32), dtype=wp.int32, device=device)
        self.rest = wp.array(np.ascontiguousarray(rest, np.float32), dtype=wp.vec3, device=device)
        self.mesh = wp.Mesh(points=x, indices=wp.array(np.ascontiguousarray(faces, np.int32).reshape(-1), dtype=wp.int32,
                                                       device=device))
        self.candidates = wp.zeros((self.count, MAX_CANDIDATES), dtype=wp.int32, device=device)
        self.candidate_distance = wp.zeros((self.count, MAX_CANDIDATES), dtype=float, device=device)
        self.candidate_count = wp.full(self.count, -1, dtype=wp.int32, device=device)  # -1: no list yet
        self.face = wp.full(self.count, -1, dtype=wp.int32, device=device)
        self.bary = wp.zeros(self.count, dtype=wp.vec3, device=device)
        self.side = wp.zeros(self.count, dtype=float, device=device)
        start, incident = vertex_edge_lists(edges, self.count)
        sides = edge_faces(edges, faces)
        self.edge_face = wp.array(np.ascontiguousarray(sides[:, 0]), dtype=wp.int32, device=device)
        self.edge_sides = wp.array(sides, dtype=wp.int32, device=device)
        self.vertex_edge_start = wp.array(start, dtype=wp.int32, device=device)
        self.vertex_edges = wp.array(incident, dtype=wp.int32, device=device)
        self.partner = wp.full(self.edges.shape[0], -1, dtype=wp.int32, device=device)
        self.partner_st = wp.zeros(self.edges.shape[0], dtype=wp.vec2, device=device)
        self.partner_side = wp.zeros(self.edges.shape[0], dtype=float, device=device)
        self._delta = wp.zeros(self.count, dtype=wp.vec3, device=device)
        self._hits = wp.zeros(self.count, dtype=float, device=device)
        self.crossed = wp.full(self.edges.shape[0], -1, dtype=wp.int32, device=device)  # the triangle each edge passes through
        self._untangle_tally = wp.zeros(self.count, dtype=float, device=device)  # apply_averaged's tally; unread
        self.pushed = wp.zeros(self.count, dtype=float, device=device)  # m pushed apart this substep
        self.friction_coefficient = 0.0  # Coulomb friction between layers (the solver sets the material's)
        self.layer = wp.array(np.zeros(self.count, np.int32) if layer is None else np.asarray(layer, np.int32),
                              dtype=wp.int32, device=device)  # each particle's garment in an outfit
        self.layered = layer is not None and len(np.unique(layer)) > 1
        self.world_host = np.zeros(self.count, np.int64) if world is None else np.asarray(world, np.int64)
        self.world = wp.array(self.world_host.astype(np.int32), dtype=wp.int32, device=device)  # each particle's job
        worlds = int(self.world_host.max(initial=0)) + 1
        self.mean_velocity = wp.zeros(worlds, dtype=wp.vec3, device=device)  # per world (``speeds``)
        self.other_speed = wp.zeros(worlds, dtype=float, device=device)
        self.host_statistics = on_cpu(device)  # ``speeds`` on the host (CPU) or the device (CUDA)
        self._sums = wp.zeros(worlds, dtype=wp.vec3, device=device)
        self._counts = wp.zeros(worlds, dtype=wp.int32, device=device)
        self._bins = wp.zeros((worlds, SPEED_BINS), dtype=wp.int32, device=device)
        self._world_crossings = wp.zeros(worlds, dtype=wp.int32, device=device)

    def search(self, x_start, v, reach: float, lookahead: float, max_speed: float,
               broad: tuple[float, float, float] | None = None) -> None:
        """Refit the garment's BVH to the particles; with ``broad`` = (reach_b, lookahead_b, most),
        first list each particle's candidates (``gather_candidates``: the non-neighbour triangles
        within reach_b plus what it and a particle at the garment's median speed travel in
        lookahead_b seconds, the nearest MAX_CANDIDATES; none for a particle whose reach is over
        ``most``, m). Then give each particle its closest facing triangle within ``reach`` plus what
        it and a particle at the median speed (speeds relative to the mean of the velocities ``v``
        [P], m/s) travel in ``lookahead`` seconds, among its candidates (without a list, among the
        BVH's), and each edge its closest non-neighbour edge within ``reach`` (``x_start``: the
        positions the sides are taken from); no particle's reach counts more than ``max_speed`` (m/s)."""
        self.reach = float(reach)
        self.mesh.refit()
        self.speeds(v, max_speed)
        mean, other = self.mean_velocity, self.other_speed
        if broad is not None:
            broad_reach, broad_lookahead, most = broad
            self.launch(gather_candidates, self.count,
                        [self.mesh.id, self.faces, self.x, v, self.rest, broad_reach, mean, other, self.world, broad_lookahead,
                         max_speed, most, self.exclusion, self.candidates, self.candidate_distance, self.candidate_count])
        self.launch(find_self_contacts, self.count,
                    [self.mesh.id, self.faces, self.x, x_start, v, self.rest, self.candidates, self.candidate_count,
                     reach, mean, other, self.world, lookahead, max_speed, self.exclusion, self.side_carry, self.layer, self.face,
                     self.bary, self.side])
        if self.edge_edge:
            self.launch(find_edge_contacts, self.edges.shape[0],
                        [self.faces, self.edges, self.vertex_edge_start, self.vertex_edges, self.face, self.x,
                         x_start, self.rest, reach, self.exclusion, self.layer, self.edge_face, self.partner,
                         self.partner_st, self.partner_side])

    def speeds(self, v, max_speed: float) -> None:
        """Each world's mean velocity and median speed relative to it (capped at ``max_speed``) into
        ``mean_velocity`` and ``other_speed``: on the host where ``v`` lives there (the CPU backend:
        ``host_speeds``, exact), else on the device (``speed_histogram``: the median rounded up to its
        bin's edge, under 5 % high), so that a CUDA substep never waits for the host."""
        if self.host_statistics:
            mean, other = host_speeds(v, self.world_host, max_speed)
            self.mean_velocity.assign(mean)
            self.other_speed.assign(other)
            return
        self._sums.zero_()
        self._counts.zero_()
        self._bins.zero_()
        self.launch(world_velocity_sums, self.count, [v, self.world, self._sums, self._counts])
        self.launch(world_means, len(self._counts), [self._sums, self._counts, self.mean_velocity])
        self.launch(speed_histogram, self.count, [v, self.world, self.mean_velocity, max_speed, self._bins])
        self.launch(histogram_medians, len(self._counts), [self._bins, self._counts, max_speed, self.other_speed])

    def launch_key(self) -> tuple:
        """The host values ``resolve`` and ``friction`` launch with (for ``sim.engine.launch.Replay``)."""
        return self.separation, self.reach, self.edge_edge, self.friction_coefficient, self.layered

    def resolve(self, inverse_mass, body_push) -> None:
        """One sweep keeping every particle ``separation`` off its triangle and every edge off its
        partner edge, on their sides (particles the body pushed this substep, ``body_push`` > 0,
        count ten times heavier), each particle moved by the mean of its corrections."""
        self._delta.zero_()
        self._hits.zero_()
        self.launch(resolve_self_contacts, self.count,
                    [self.faces, self.face, self.bary, self.side, inverse_mass, body_push, self.separation,
                     self.reach, self.x, self._delta, self._hits])
        if self.edge_edge:
            self.launch(resolve_edge_contacts, self.edges.shape[0],
                        [self.edges, self.partner, self.partner_st, self.partner_side, inverse_mass, body_push,
                         self.separation, self.reach, self.x, self._delta, self._hits])
        self.launch(apply_averaged, self.count, [self._delta, self._hits, self.x, self.pushed])

    def friction(self, x_start, inverse_mass, body_push) -> None:
        """Coulomb friction for the substep's self-contact pushes between layers (``self_friction``;
        ``body_push`` [P]: how far the body pushed each particle this substep), then forget them."""
        if self.friction_coefficient > 0.0 and self.layered:
            self.launch(self_friction, self.count, [self.faces, self.face, self.bary, self.pushed,
                                                    self.friction_coefficient, self.layer, inverse_mass, body_push,
                                                    x_start, self.x])
        self.pushed.zero_()

    def find_crossings(self, screen: float = 0.0) -> None:
        """Refit the BVH and find, for each garment edge, a garment triangle it passes through
        (``crossed``; ``find_crossings``); with ``screen`` (m, the reach of the candidate lists just
        made) only edges near another layer are tested (about a fifth of the cost on the top's walk)."""
        self.mesh.refit()
        wp.launch(find_crossings, dim=self.edges.shape[0], inputs=[self.mesh.id, self.faces, self.edges, self.x,
                                                                    self.rest, self.exclusion, self.candidate_count,
                                                                    float(screen), self.crossed],
                  device=self.device)

    def untangle(self, x, inverse_mass, step: float) -> None:
        """Move each edge found crossing a triangle and that triangle apart by up to ``step`` m along
        the triangle's normal, the way that shrinks the contour where the garment cuts itself
        (``untangle_crossings``; ``x`` [P]: the positions moved), each particle by the mean of its
        moves."""
        self._delta.zero_()
        self._hits.zero_()
        self.launch(untangle_crossings, self.edges.shape[0],
                    [self.faces, self.edges, self.edge_sides, self.crossed, self.layer, inverse_mass, step, x,
                     self._delta, self._hits])
        self.launch(apply_averaged, self.count, [self._delta, self._hits, x, self._untangle_tally])

    def crossing_edges(self) -> np.ndarray:
        """Mask [E] of the garment edges that pass through a garment triangle right now."""
        self.find_crossings()
        return self.crossed.numpy() >= 0

    def crossings(self) -> np.ndarray:
        """[W] how many edges of each world pass through a garment triangle right now, counted on
        the device (only W numbers come back to the host)."""
        self.find_crossings()
        self._world_crossings.zero_()
        wp.launch(crossings_per_world, dim=self.edges.shape[0], inputs=[self.crossed, self.edges, self.world,
                                                                         self._world_crossings], device=self.device)
        return self._world_crossings.numpy()
