"""Removing slivers from a garment surface whose seams and boundary are marked curves.

Inserting seams as level sets (``darts.geometry.levelset``) leaves millimetre-long edges where a seam
passes close to a vertex that may not move (the boundary, an earlier seam) and where seams meet.
In the simulator such an edge is a stiff, tiny constraint next to normal ones: its strain reads in
hundreds of percent and it caps the stable step. Two repairs, both keeping every curve a curve:

* **Edge collapse** (Hoppe et al. 1993): an edge ab shorter than ``min_length`` is collapsed, the
  removed vertex r going to the kept vertex k. A vertex may only slide along its curves: every
  curve through r must contain the edge kr, unless both ends are junctions on a curve that
  contains kr (then the other curves of r are rerouted through k, moving them by |kr|). The
  topology must stay a manifold with the same boundary: the link condition
  N(k) ∩ N(r) = {third corners of the faces on kr}, and two vertices on one curve only collapse
  along that curve's edge. No face around r may turn by more than 60° or lose its area; two free
  vertices (on no curve) meet at the edge's midpoint. A free vertex within ``min_length`` of an
  outline edge of its face that cannot collapse joins the outline (that face is peeled off).
* **Corners with one triangle**: a vertex sector between two consecutive curve edges (a panel
  corner in the DART) that holds a single triangle (v, b, c) gives its particle only two
  neighbours, held by nothing but those two edges. A spike of one curve (vb and vc both on it)
  slides into the nearer of b and c; otherwise the opposite edge bc is split by a new vertex m
  (m joins bc's curve if bc is on one), which gives v the triangles (v, b, m), (v, m, c); where
  that split would make an edge shorter than ``min_length``, bc is flipped to vd instead when
  that keeps every sector at two triangles or more, else the nearer of b and c slides into v.

What is left after a round gets Delaunay flips of the edges off the curves and tangential
relaxation of the free vertices around it, then the next round (``ROUNDS`` at most).

Positions are in whatever frame the caller uses (the templates: canonical, Y up, metres).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from darts.geometry.mesh import boundary_edges

BOUNDARY = "__boundary__"
MAX_TURN_COS = 0.5  # a face may turn by at most 60 degrees in a collapse, a flip or a relaxation step
ROUNDS = 4  # collapse, corners, relaxation


def _key(a: int, b: int) -> tuple[int, int]:
    return (a, b) if a < b else (b, a)


@dataclass
class SliverReport:
    """What ``remove_slivers`` did: edges collapsed, flat boundary faces peeled, corner edges split or flipped, and what it could
    not repair (edges still shorter than the limit, sectors still holding one triangle)."""

    collapsed: int = 0
    peeled: int = 0
    split: int = 0
    flipped: int = 0
    short_left: int = 0
    lone_corners_left: int = 0


class _EditableMesh:
    """A triangle mesh with curves (named sets of undirected edges), edited in place."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, curves: dict[str, np.ndarray]):
        self.x = [np.asarray(p, np.float64) for p in vertices]
        self.faces = [tuple(int(i) for i in f) for f in faces]
        self.alive = [True] * len(self.faces)
        self.vertex_faces: list[set[int]] = [set() for _ in self.x]
        for index, face in enumerate(self.faces):
            for v in face:
                self.vertex_faces[v].add(index)
        named = dict(curves)
        named[BOUNDARY] = boundary_edges(np.asarray(faces))
        self.curve_edges = {name: {_key(int(a), int(b)) for a, b in edges} for name, edges in named.items()}
        self.vertex_curves: list[set[str]] = [set() for _ in self.x]
        for name, edges in self.curve_edges.items():
            for a, b in edges:
                self.vertex_curves[a].add(name)
                self.vertex_curves[b].add(name)

    # --- queries ---
    def neighbours(self, v: int) -> set[int]:
        return {u for f in self.vertex_faces[v] for u in self.faces[f] if u != v}

    def edge_faces(self, a: int, b: int) -> list[int]:
        return sorted(self.vertex_faces[a] & self.vertex_faces[b])

    def curves_on(self, a: int, b: int) -> set[str]:
        key = _key(a, b)
        return {name for name in self.vertex_curves[a] & self.vertex_curves[b] if key in self.curve_edges[name]}

    def normal(self, face: tuple[int, int, int], moved: dict[int, np.ndarray] | None = None) -> np.ndarray:
        p = [moved[v] if moved and v in moved else self.x[v] for v in face]
        return np.cross(p[1] - p[0], p[2] - p[0])

    def turns_less_than_limit(self, face: tuple[int, int, int], moved: dict[int, np.ndarray],
                              new_face: tuple[int, int, int] | None = None) -> bool:
        """Whether ``face`` (or ``new_face`` replacing it) with the ``moved`` positions keeps its area
        and turns by at most 60 degrees."""
        before, after = self.normal(face), self.normal(new_face or face, moved)
        scale = np.linalg.norm(before) * np.linalg.norm(after)
        return bool(scale > 1e-30 and before @ after >= MAX_TURN_COS * scale)

    def edges(self) -> list[tuple[int, int]]:
        return sorted({_key(f[k], f[(k + 1) % 3]) for i, f in enumerate(self.faces) if self.alive[i] for k in range(3)})

    def length(self, a: int, b: int) -> float:
        d = self.x[a] - self.x[b]
        return math.sqrt(d @ d)

    def short_edges(self, min_length: float) -> list[tuple[float, int, int]]:
        """(length, a, b) of every edge shorter than ``min_length``, shortest first."""
        edges = np.array(self.edges(), np.int64).reshape(-1, 2)
        points = np.asarray(self.x)
        d = points[edges[:, 0]] - points[edges[:, 1]]
        lengths = np.sqrt(np.einsum("ij,ij->i", d, d))
        return sorted((float(lengths[k]), int(edges[k, 0]), int(edges[k, 1])) for k in np.flatnonzero(lengths < min_length))

    def is_curve_edge(self, a: int, b: int) -> bool:
        return bool(self.curves_on(a, b))

    def sectors(self, v: int) -> list[list[int]]:
        """The faces around ``v`` grouped into sectors: runs of faces joined across edges at v that
        are on no curve (a sector is one panel corner in the DART)."""
        faces = sorted(self.vertex_faces[v])
        parent = {f: f for f in faces}

        def find(f):
            while parent[f] != f:
                parent[f] = f = parent[parent[f]]
            return f

        for u in self.neighbours(v):
            shared = self.edge_faces(v, u)
            if len(shared) == 2 and not self.is_curve_edge(v, u):
                parent[find(shared[0])] = find(shared[1])
        groups: dict[int, list[int]] = {}
        for f in faces:
            groups.setdefault(find(f), []).append(f)
        return list(groups.values())

    # --- edits ---
    def set_face(self, index: int, face: tuple[int, int, int]) -> None:
        for v in self.faces[index]:
            self.vertex_faces[v].discard(index)
        self.faces[index] = face
        for v in face:
            self.vertex_faces[v].add(index)

    def _add_face(self, face: tuple[int, int, int]) -> None:
        self.faces.append(face)
        self.alive.append(True)
        for v in face:
            self.vertex_faces[v].add(len(self.faces) - 1)

    def _kill_face(self, index: int) -> None:
        for v in self.faces[index]:
            self.vertex_faces[v].discard(index)
        self.alive[index] = False

    def may_collapse(self, removed: int, kept: int) -> bool:
        """Whether ``removed`` may go to ``kept``: it slides along its curves (or both are junctions
        on a curve along the edge), no curve is cut short, and the surface stays manifold."""
        along = self.curves_on(removed, kept)
        if any(name not in along for name in self.vertex_curves[removed] & self.vertex_curves[kept]):
            return False  # both on a curve that does not run along the edge: the curve would be cut short
        slides = self.vertex_curves[removed] <= along
        junctions = bool(along) and len(self.vertex_curves[removed]) > 1 and len(self.vertex_curves[kept]) > 1
        if not (slides or junctions):
            return False
        opposite = {v for f in self.edge_faces(removed, kept) for v in self.faces[f] if v not in (removed, kept)}
        return self.neighbours(removed) & self.neighbours(kept) == opposite  # the link condition

    def collapse_targets(self, a: int, b: int) -> list[tuple[int, int]]:
        """The allowed ways (kept, removed) to collapse ab, best first: the vertex on more curves
        stays, or the one that the other slides to along its curves."""
        first, second = sorted((a, b), key=lambda v: -len(self.vertex_curves[v]))
        return [(kept, removed) for kept, removed in ((first, second), (second, first)) if self.may_collapse(removed, kept)
                and (self.vertex_curves[removed] <= self.curves_on(a, b)
                     or len(self.vertex_curves[kept]) >= len(self.vertex_curves[removed]))]

    def collapse(self, kept: int, removed: int) -> bool:
        """Collapse ``removed`` into ``kept`` if no face flips or vanishes. ``kept`` stays where it is,
        unless both are on no curve: then they meet at the edge's midpoint."""
        free = not self.vertex_curves[kept] and not self.vertex_curves[removed]
        point = 0.5 * (self.x[kept] + self.x[removed]) if free else self.x[kept]
        moved = {removed: point, kept: point}
        shared = set(self.edge_faces(kept, removed))
        around = (self.vertex_faces[removed] | self.vertex_faces[kept]) - shared
        if not all(self.turns_less_than_limit(self.faces[f], moved) for f in around):
            return False
        self.x[kept] = point
        for f in shared:
            self._kill_face(f)
        for f in list(self.vertex_faces[removed]):
            self.set_face(f, tuple(kept if v == removed else v for v in self.faces[f]))
        for name in self.vertex_curves[removed]:
            edges = self.curve_edges[name]
            for u in [u for u in self.neighbours(kept) | {kept} if _key(u, removed) in edges]:
                edges.discard(_key(u, removed))
                if u != kept:
                    edges.add(_key(u, kept))
            self.vertex_curves[kept].add(name)
        self.vertex_curves[removed] = set()
        return True

    def peel(self, free: int, a: int, b: int) -> bool:
        """Remove the face (free, a, b) whose edge ab is on the boundary, so that ``free`` (on no
        curve and not on the boundary) joins the boundary between a and b."""
        if self.vertex_curves[free] or BOUNDARY not in self.curves_on(a, b):
            return False
        face = next((f for f in self.edge_faces(a, b) if free in self.faces[f]), None)
        if face is None:
            return False
        self._kill_face(face)
        edges = self.curve_edges[BOUNDARY]
        edges.discard(_key(a, b))
        edges |= {_key(a, free), _key(free, b)}
        self.vertex_curves[free].add(BOUNDARY)
        return True

    def split(self, b: int, c: int, point: np.ndarray) -> int:
        """Split edge bc with a new vertex m at ``point`` (on bc's curves if any); returns m."""
        m = len(self.x)
        self.x.append(np.asarray(point, np.float64))
        self.vertex_faces.append(set())
        self.vertex_curves.append(set())
        for name in self.curves_on(b, c):
            self.curve_edges[name] -= {_key(b, c)}
            self.curve_edges[name] |= {_key(b, m), _key(m, c)}
            self.vertex_curves[m].add(name)
        for f in self.edge_faces(b, c):
            first, second = (tuple(m if v == -1 else v for v in face) for face in _split_faces(self.faces[f], b, c))
            self.set_face(f, first)
            self._add_face(second)
        return m

    def flip(self, b: int, c: int) -> bool:
        """Flip the interior edge bc of faces (v, b, c) and (d, c, b) to vd when the two new faces
        turn by at most 60 degrees from the old ones and vd is not an edge yet."""
        faces = self.edge_faces(b, c)
        if len(faces) != 2 or self.is_curve_edge(b, c):
            return False
        first, second = (self.faces[f] for f in faces)
        k = first.index(b)
        if first[(k + 1) % 3] != c:
            faces, first, second = faces[::-1], second, first
            k = first.index(b)
        v = first[(k + 2) % 3]  # first = (b, c, v) in its winding
        d = next(u for u in second if u not in (b, c))
        if d in self.neighbours(v):
            return False
        new = [(v, b, d), (v, d, c)]
        if not all(self.turns_less_than_limit(old, {}, face) for old in (first, second) for face in new):
            return False
        self.set_face(faces[0], new[0])
        self.set_face(faces[1], new[1])
        return True

    def compact(self) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        faces = np.array([f for f, alive in zip(self.faces, self.alive) if alive], np.int64)
        used = np.unique(faces)
        remap = np.full(len(self.x), -1, np.int64)
        remap[used] = np.arange(len(used))
        curves = {name: remap[np.array(sorted(edges), np.int64).reshape(-1, 2)]
                  for name, edges in self.curve_edges.items() if name != BOUNDARY}
        return np.asarray(self.x)[used], remap[faces], curves


def _collapse_short_edges(mesh: _EditableMesh, min_length: float, report: SliverReport) -> None:
    while True:
        short = mesh.short_edges(min_length)
        touched: set[int] = set()
        done = 0
        for _, a, b in short:
            if a in touched or b in touched:
                continue  # its neighbourhood changed in this pass: look again in the next one
            around = mesh.neighbours(a) | mesh.neighbours(b) | {a, b}
            if any(mesh.collapse(kept, removed) for kept, removed in mesh.collapse_targets(a, b)):
                touched |= around
                done += 1
            elif _peel_onto_boundary(mesh, a, b, min_length):
                touched |= around
                report.peeled += 1
                done += 1
        report.collapsed += done
        if not done:
            return


def _peel_onto_boundary(mesh: _EditableMesh, a: int, b: int, min_length: float) -> bool:
    """Where a free vertex of the short edge ab lies within ``min_length`` of a boundary edge of one
    of its faces (a flat triangle on the boundary), let it join the boundary (the boundary moves by
    less than ``min_length``); the next pass collapses it along the boundary."""
    for free, other in ((a, b), (b, a)):
        if mesh.vertex_curves[free] or BOUNDARY not in mesh.vertex_curves[other]:
            continue
        for f in mesh.vertex_faces[free]:
            p, q = (u for u in mesh.faces[f] if u != free)
            if BOUNDARY in mesh.curves_on(p, q):
                direction = mesh.x[q] - mesh.x[p]
                t = np.clip((mesh.x[free] - mesh.x[p]) @ direction / max(direction @ direction, 1e-30), 0.0, 1.0)
                if np.linalg.norm(mesh.x[p] + t * direction - mesh.x[free]) < min_length and mesh.peel(free, p, q):
                    return True
    return False


def _lone_sectors(mesh: _EditableMesh, vertices) -> set[tuple[int, int]]:
    """Sectors around ``vertices`` holding a single face, as (corner, face)."""
    return {(v, group[0]) for v in vertices if mesh.vertex_faces[v] for group in mesh.sectors(v) if len(group) == 1}


def _split_point(mesh: _EditableMesh, b: int, c: int, min_length: float) -> np.ndarray | None:
    """Where to split bc so that no new edge is shorter than ``min_length`` and no face turns by
    more than 60 degrees: the midpoint on a curve; off the curves, the mean of b, c and the
    opposite corners moved into the plane through the midpoint (a relaxed position), else the
    midpoint. None when neither works."""
    faces = mesh.edge_faces(b, c)
    others = [u for f in faces for u in mesh.faces[f] if u not in (b, c)]
    midpoint = 0.5 * (mesh.x[b] + mesh.x[c])
    candidates = [midpoint]
    if not mesh.is_curve_edge(b, c):
        normal = sum(mesh.normal(mesh.faces[f]) for f in faces)
        normal = normal / max(np.linalg.norm(normal), 1e-30)
        shift = np.mean([mesh.x[u] for u in [b, c] + others], axis=0) - midpoint
        candidates.insert(0, midpoint + shift - normal * (normal @ shift))
    for point in candidates:
        if min(np.linalg.norm(mesh.x[u] - point) for u in [b, c] + others) < min_length:
            continue
        halves = [face for f in faces for face in _split_faces(mesh.faces[f], b, c)]
        if all(mesh.turns_less_than_limit(mesh.faces[f], {-1: point}, face) for f in faces for face in halves
               if set(face) - {-1} <= set(mesh.faces[f])):
            return point
    return None


def _split_faces(face: tuple[int, int, int], b: int, c: int) -> list[tuple[int, int, int]]:
    """The two faces that replace ``face`` when its edge bc is split by a vertex numbered -1."""
    k = face.index(b)
    if face[(k + 1) % 3] == c:
        o = face[(k + 2) % 3]
        return [(b, -1, o), (-1, c, o)]
    o = face[(k + 1) % 3]
    return [(c, -1, o), (-1, b, o)]


def _fix_lone_corners(mesh: _EditableMesh, min_length: float, report: SliverReport) -> None:
    lone = _lone_sectors(mesh, range(len(mesh.x)))
    while lone:
        v, face = lone.pop()
        if not mesh.alive[face] or v not in mesh.faces[face] or (v, face) not in _lone_sectors(mesh, [v]):
            continue
        b, c = (u for u in mesh.faces[face] if u != v)
        around = {v, b, c} | {u for f in mesh.edge_faces(b, c) for u in mesh.faces[f]}
        if len(mesh.vertex_curves[v]) == 1 and mesh.curves_on(v, b) and mesh.curves_on(v, c):
            # a spike of one curve: v slides along it into the nearer of b and c
            kept = min((b, c), key=lambda u: mesh.length(u, v))
            if mesh.may_collapse(v, kept) and mesh.collapse(kept, v):
                report.collapsed += 1
                lone |= _lone_sectors(mesh, around - {v})
                continue
        point = _split_point(mesh, b, c, min_length)
        if point is not None:
            m = mesh.split(b, c, point)
            report.split += 1
            lone |= _lone_sectors(mesh, around | {m})
            continue
        before = _lone_sectors(mesh, around)
        saved = [(f, mesh.faces[f]) for f in mesh.edge_faces(b, c)]
        if mesh.flip(b, c):
            after = _lone_sectors(mesh, around)
            if len(after) < len(before) and not {corner for corner, _ in after} - {corner for corner, _ in before}:
                report.flipped += 1
                lone |= after
                continue
            for f, old in saved:  # undo
                mesh.set_face(f, old)
        # last resort: a near corner of the face goes into v (the face's sector joins the next one)
        for u in sorted((b, c), key=lambda u: mesh.length(u, v)):
            if mesh.length(u, v) < 3 * min_length and mesh.may_collapse(u, v) and mesh.collapse(v, u):
                report.collapsed += 1
                lone |= _lone_sectors(mesh, around - {u})
                break


def _relax(mesh: _EditableMesh, vertices: set[int], iterations: int = 5) -> None:
    """Tangential relaxation: each free vertex (on no curve) among ``vertices`` and their neighbours
    moves to the mean of its neighbours minus the part along its normal (Botsch & Kobbelt 2004),
    unless a face around it would turn by more than 60 degrees."""
    ring = set(vertices) | {u for v in vertices for u in mesh.neighbours(v)}
    free = sorted(u for u in ring if not mesh.vertex_curves[u] and mesh.vertex_faces[u])
    for _ in range(iterations):
        for u in free:
            normal = sum(mesh.normal(mesh.faces[f]) for f in mesh.vertex_faces[u])
            normal = normal / max(np.linalg.norm(normal), 1e-30)
            shift = np.mean([mesh.x[w] for w in mesh.neighbours(u)], axis=0) - mesh.x[u]
            target = {u: mesh.x[u] + shift - normal * (normal @ shift)}
            if all(mesh.turns_less_than_limit(mesh.faces[f], target) for f in mesh.vertex_faces[u]):
                mesh.x[u] = target[u]


def _opposite_angles(mesh: _EditableMesh, b: int, c: int) -> float:
    """The sum of the two angles facing the edge bc (radians)."""
    total = 0.0
    for f in mesh.edge_faces(b, c):
        o = next(u for u in mesh.faces[f] if u not in (b, c))
        p, q = mesh.x[b] - mesh.x[o], mesh.x[c] - mesh.x[o]
        total += float(np.arctan2(np.linalg.norm(np.cross(p, q)), p @ q))
    return total


def _flip_to_delaunay(mesh: _EditableMesh, vertices: set[int]) -> int:
    """Flip the interior edges off the curves around ``vertices`` whose opposite angles sum to more
    than pi (Delaunay flips: they widen the thinnest angles), unless a flip would leave a corner
    sector with one face. Returns the number of flips."""
    flips = 0
    ring = vertices | {u for v in vertices for u in mesh.neighbours(v)}
    for b, c in sorted({_key(v, u) for v in ring for u in mesh.neighbours(v)}):
        if len(mesh.edge_faces(b, c)) != 2 or mesh.is_curve_edge(b, c) or _opposite_angles(mesh, b, c) <= np.pi + 1e-6:
            continue
        around = {u for f in mesh.edge_faces(b, c) for u in mesh.faces[f]}
        before = {corner for corner, _ in _lone_sectors(mesh, around)}
        saved = [(f, mesh.faces[f]) for f in mesh.edge_faces(b, c)]
        if mesh.flip(b, c):
            if {corner for corner, _ in _lone_sectors(mesh, around)} <= before:
                flips += 1
                continue
            for f, old in saved:  # undo
                mesh.set_face(f, old)
    return flips


def _problems(mesh: _EditableMesh, min_length: float) -> tuple[list[tuple[int, int]], set[tuple[int, int]]]:
    """Edges shorter than ``min_length`` and single-face sectors."""
    short = [(a, b) for _, a, b in mesh.short_edges(min_length)]
    return short, _lone_sectors(mesh, range(len(mesh.x)))


def remove_slivers(vertices: np.ndarray, faces: np.ndarray, curves: dict[str, np.ndarray], min_length: float
                   ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], SliverReport]:
    """Collapse edges shorter than ``min_length`` and give every single-face corner sector a second
    face, keeping the boundary and the ``curves`` (name -> undirected edges [E,2]) as curves.

    Returns (vertices [V',3], faces [F',3], curves with new indices, report). Face winding is kept."""
    mesh = _EditableMesh(vertices, faces, curves)
    report = SliverReport()
    for _ in range(ROUNDS):
        _collapse_short_edges(mesh, min_length, report)
        _fix_lone_corners(mesh, min_length, report)
        short, lone = _problems(mesh, min_length)
        if not short and not lone:
            break
        where = {v for edge in short for v in edge} | {v for corner, face in lone for v in mesh.faces[face]}
        report.flipped += _flip_to_delaunay(mesh, where)
        _relax(mesh, where)
    short, lone = _problems(mesh, min_length)
    report.short_left, report.lone_corners_left = len(short), len(lone)
    return (*mesh.compact(), report)
