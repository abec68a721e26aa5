"""The posed body's parts pressed against each other instead of through each other (issue 46).

Linear blend skinning lets a posed body overlap itself: in a squat the calves sink into the thighs
and the thighs into the belly, crossed arms into the chest. Cloth caught there lies inside one part
whatever the solver does, since no place outside the body exists between the two surfaces. Soft
tissue does not pass through itself; it flattens where two parts press together. This module does
that to each frame of a body track (world frame, Z up, metres), before the cloth sees it:

For a body vertex v with unit normal n: where the ray from v along -n leaves a volume (meets a face
from behind) within ``DEPTH_REACH``, after t, and the ray along n also meets a face from behind, v
lies inside another part (``sim.engine.kernels.buried``'s test) about t deep, and moves by

    d(v) = -n min((min(t, DEPTH_CAP) + g) / 2, STEP)

so that the two surfaces, each moving half the depth plus half the gap g, meet g apart. A vertex
whose ray along n meets a face from the front at s < g (another part closer than the gap) moves by
-n (g - s) / 2. Between an upper arm and the torso g is ``ARM_GAP_FACTOR`` times the gap: a top
puts two layers there (the sleeve's inner wall and its side), each held a thickness off its own
part. The moves are averaged twice with each vertex's one-ring (d <- (d + mean of the ring's d) / 2:
the flesh around a pressed spot gives too; none of it into a part that keeps its shape); a move
that would turn a face over against the skinned body's is halved, up to ``UNFOLD_HALVINGS`` times,
then held; the vertices move, and the normals and rays are taken again for the moved vertices and
their rings, up to ``ITERATIONS`` rounds or until no move reaches ``TOLERANCE``. Only the parts a
garment covers move (torso, hips, arms, thighs, calves): the head, neck, hands and feet keep their
shape (the bundled body's own mesh overlaps itself a little at the toes and fingers, which is no
cloth's business), while a part pressed against them still gives way.

The moves depend on the pose alone (no state is carried from frame to frame), so they follow it;
frames without any overlap or near contact are left exactly as skinned.
"""
from __future__ import annotations

import numpy as np

from darts.body.segmentation import PART_INDEX
from darts.geometry.mesh import face_normals, unique_edges
from darts.geometry.warp_runtime import warp

wp = warp()

#: the parts whose surface may move: those a garment can cover
MOVABLE_PARTS = ("upper_torso", "lower_torso", "hips", "left_upper_arm", "right_upper_arm", "left_forearm",
                 "right_forearm", "left_thigh", "right_thigh", "left_calf", "right_calf")
ITERATIONS = 8  # rounds of rays and moves per frame, at most
SMOOTHING = 2  # one-ring averages of the moves per round
DEPTH_CAP = 0.04  # m: an overlap deeper than this along the normal is taken as this deep (a ray grazing a fold)
DEPTH_REACH = 0.08  # m a ray along -n looks for where v leaves another part (deeper: only the ring's moves reach it)
STEP = 0.01  # m a vertex moves at most per round
UNFOLD_HALVINGS = 6  # times a move that would turn a face over is halved
TOLERANCE = 1.0e-4  # m: a round whose largest move is under this is the last
#: body gaps between an upper arm and the torso (the long-sleeve top's squat: 176-180 crossing edges
#: against 219-254 with one gap there, three runs each; docs/simulation.md)
ARM_GAP_FACTOR = 2.0
#: the part groups whose pairs take ARM_GAP_FACTOR: an upper arm (1) against the torso (2)
ARM_GROUPS = {"left_upper_arm": 1, "right_upper_arm": 1, "upper_torso": 2, "lower_torso": 2}
REACH = 0.25  # m a ray looks for another part (more than the deepest overlap of two posed parts)


@wp.kernel
def _face_normals_to_vertices(points: wp.array(dtype=wp.vec3), faces: wp.array(dtype=wp.int32),
                              normal: wp.array(dtype=wp.vec3)):
    """normal[v] += each face's area-weighted normal, for the face's three corners."""
    f = wp.tid()
    a, b, c = faces[3 * f], faces[3 * f + 1], faces[3 * f + 2]
    n = wp.cross(points[b] - points[a], points[c] - points[a])
    wp.atomic_add(normal, a, n)
    wp.atomic_add(normal, b, n)
    wp.atomic_add(normal, c, n)


@wp.kernel
def _separating_moves(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), normal: wp.array(dtype=wp.vec3),
                      active: wp.array(dtype=wp.int32), group: wp.array(dtype=wp.int32),
                      face_group: wp.array(dtype=wp.int32), gap: float, arm_gap: float,
                      move: wp.array(dtype=wp.vec3)):
    """move[v] for each ``active`` vertex v: -n min((t + g) / 2, STEP) inside another part (t: how far
    along -n it leaves that part, at most DEPTH_CAP), -n (g - s) / 2 where its ray along n meets
    another surface from the front at s < g, else 0 (``move`` zero beforehand); g is ``arm_gap``
    where v and the face its ray meets are an upper arm and the torso (``group`` 1 and 2), else ``gap``."""
    i = active[wp.tid()]
    p = points[i]
    n = wp.normalize(normal[i])
    amount = float(0.0)
    # Leaving a volume along -n within DEPTH_REACH: v may lie inside another part, which the (long)
    # ray along n then meets from behind; otherwise only a surface within the gap along n matters.
    inward = wp.mesh_query_ray(mesh, p - 1.0e-4 * n, -n, DEPTH_REACH)
    reach = wp.max(gap, arm_gap)
    if inward.result and inward.sign < 0.0:
        reach = REACH
    out = wp.mesh_query_ray(mesh, p + 1.0e-4 * n, n, reach)
    g = gap
    if out.result:
        if group[i] + face_group[out.face] == 3:  # an upper arm and the torso
            g = arm_gap
    if out.result and out.sign < 0.0:
        amount = wp.min(0.5 * (wp.min(inward.t, DEPTH_CAP) + g), STEP)
    elif out.result and out.t < g:
        amount = 0.5 * (g - out.t)
    move[i] = -amount * n


def padded_lists(keys: np.ndarray, values: np.ndarray, count: int, pad: int) -> np.ndarray:
    """[count, D] the ``values`` paired with each key 0..count-1 (pairs ``keys``, ``values``), in
    increasing order, each row padded with ``pad`` (D: the longest list)."""
    order = np.lexsort((values, keys))
    keys, values = keys[order], values[order]
    length = np.bincount(keys, minlength=count)
    table = np.full((count, max(int(length.max(initial=0)), 1)), pad, np.int64)
    table[keys, np.arange(len(keys)) - np.repeat(np.cumsum(length) - length, length)] = values
    return table


def one_rings(faces: np.ndarray, count: int) -> np.ndarray:
    """[count, D] each vertex's one-ring neighbours (the vertices sharing an edge with it), in
    increasing order, padded with ``count``."""
    edges = unique_edges(np.asarray(faces, np.int64).reshape(-1, 3))
    return padded_lists(np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]], count, count)


class BodySeparation:
    """Separates the overlapping parts of one body mesh (``faces`` [F,3]; ``parts`` [V]: each
    vertex's part index in ``darts.body.segmentation.PART_NAMES``) frame by frame, ``gap`` (m) apart
    (an upper arm and the torso ``ARM_GAP_FACTOR`` times that)."""

    def __init__(self, faces: np.ndarray, parts: np.ndarray, gap: float):
        self.faces = np.asarray(faces, np.int32).reshape(-1, 3)
        self.count = len(parts)
        self.gap = float(gap)
        group = np.zeros(self.count, np.int32)
        for name, value in ARM_GROUPS.items():
            group[np.asarray(parts) == PART_INDEX[name]] = value
        self.group = wp.array(group, dtype=wp.int32, device="cpu")
        self.face_group = wp.array(group[self.faces[:, 0]], dtype=wp.int32, device="cpu")  # a face: its first corner's
        self.rings = one_rings(self.faces, self.count)
        self.ring_weight = 1.0 / np.maximum((self.rings < self.count).sum(1), 1)[:, None]  # the ring average's
        self.movable = np.isin(np.asarray(parts), [PART_INDEX[name] for name in MOVABLE_PARTS])
        self.every_movable = wp.array(np.flatnonzero(self.movable).astype(np.int32), dtype=wp.int32, device="cpu")
        self.vertex_faces = padded_lists(self.faces.reshape(-1), np.repeat(np.arange(len(self.faces)), 3), self.count,
                                         len(self.faces))
        self.points = wp.zeros(self.count, dtype=wp.vec3, device="cpu")
        self.indices = wp.array(self.faces.reshape(-1), dtype=wp.int32, device="cpu")
        self.mesh = None  # built on the first frame's points (a tree built on zeros would be refit into a poor one)
        self.normal = wp.zeros_like(self.points)
        self.move = wp.zeros_like(self.points)

    def __call__(self, vertices: np.ndarray) -> np.ndarray:
        """``vertices`` [V,3] of one frame with its parts moved apart (a new array; the same values
        where nothing overlaps or comes within the gap)."""
        points = np.array(vertices, np.float64)
        posed_normals = None  # the skinned body's face normals, taken once a move needs them
        active = self.every_movable
        for _ in range(ITERATIONS):
            self.points.assign(points.astype(np.float32))
            if self.mesh is None:
                self.mesh = wp.Mesh(points=self.points, indices=self.indices)
            self.mesh.refit()
            self.normal.zero_()
            self.move.zero_()
            wp.launch(_face_normals_to_vertices, len(self.faces), [self.points, self.indices, self.normal], device="cpu")
            wp.launch(_separating_moves, len(active), [self.mesh.id, self.points, self.normal, active, self.group,
                                                       self.face_group, self.gap, ARM_GAP_FACTOR * self.gap, self.move],
                      device="cpu")
            move = self.move.numpy().astype(np.float64)
            if np.abs(move).max(initial=0.0) < TOLERANCE:
                break
            # the moves reach two rings by the averages: only rows near a move are averaged (the others stay 0)
            region = _moving(move)
            for _ in range(SMOOTHING):
                region = self._with_ring(region)
                move[region] = 0.5 * (move[region] + self._ring_average(move, region))
            move[~self.movable] = 0.0  # the average reaches a ring into the parts that keep their shape
            if posed_normals is None:
                posed_normals = face_normals(np.asarray(vertices, np.float64), self.faces)
            points += self._unfolding(posed_normals, points, move)
            near_moves = self._with_ring(_moving(move))
            active = wp.array(near_moves[self.movable[near_moves]].astype(np.int32), dtype=wp.int32, device="cpu")
        return points

    def _with_ring(self, vertices: np.ndarray) -> np.ndarray:
        """The sorted ``vertices`` and their one-ring neighbours."""
        return _unpadded(np.union1d(vertices, self.rings[vertices]), self.count)

    def _ring_average(self, move: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """[len(rows),3] the mean of ``move`` [V,3] over each of ``rows``' one-ring (summed in ring order)."""
        padded = np.concatenate([move, np.zeros((1, 3))])
        weight = self.ring_weight[rows]
        total = np.zeros((len(rows), 3))
        for column in self.rings[rows].T:
            total += weight * padded[column]
        return total

    def _unfolding(self, posed_normals: np.ndarray, points: np.ndarray, move: np.ndarray) -> np.ndarray:
        """``move`` [V,3] of ``points`` with the moves of a face's corners halved, up to
        ``UNFOLD_HALVINGS`` times, while the face would end turned over against the skinned body's
        (its normal at more than 90 degrees to ``posed_normals`` [F,3]), then stopped."""
        touched = _unpadded(np.unique(self.vertex_faces[_moving(move)]), len(self.faces))
        faces, before = self.faces[touched], posed_normals[touched]

        def turned_over():
            return (face_normals(points + move, faces) * before).sum(1) <= 0.0

        for _ in range(UNFOLD_HALVINGS):
            turned = turned_over()
            if not turned.any():
                return move
            move[np.unique(faces[turned])] *= 0.5
        while (turned := turned_over()).any():
            move[np.unique(faces[turned])] = 0.0  # kept still: a face whose corners all stay cannot turn
        return move


def _unpadded(values: np.ndarray, pad: int) -> np.ndarray:
    """Sorted unique ``values`` of a ``padded_lists`` table, less its padding ``pad`` (the largest)."""
    return values[:-1] if len(values) and values[-1] == pad else values


def _moving(move: np.ndarray) -> np.ndarray:
    """The vertices whose ``move`` [V,3] is not zero, in order."""
    return np.flatnonzero((move != 0.0).any(1))


def separate_parts(vertices: np.ndarray, faces: np.ndarray, parts: np.ndarray, gap: float) -> np.ndarray:
    """A body track's vertices [T,V,3] with every frame's overlapping parts pressed ``gap`` (m) apart
    (``BodySeparation``); ``gap`` 0 returns them as they are."""
    if gap <= 0:
        return vertices
    separation = BodySeparation(faces, parts, gap)
    return np.stack([separation(frame) for frame in vertices]).astype(np.asarray(vertices).dtype)
