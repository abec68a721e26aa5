"""The cloth model the solver steps, built from a DART (canonical frame, metres, kilograms).

- particles: DART vertices, with the two ends of every *welded* seam pair merged into one;
- mass: lumped areal density, m_i = density * sum of (area / 3) of the faces around particle i
  (at least the lightest such mass);
- stretch: one distance constraint per mesh edge, at its rest length;
- bending: one hinge (i, j shared edge; k, l opposite vertices) per interior edge, with its rest
  dihedral angle;
- seam springs: one per *active* pair of a stiff, loose, repulsive or partial seam, with that
  seam's stiffness (N/m) and rest length (0, or > 0 when repulsive); each end has an anchor, a
  neighbour off every seam, which says which way the end retreats when coincident ends must part;
- loops: each feature line as a loop of particles (for ``sim.engine.tethers``);
- per constraint, the material's values (stretch stiffness per edge, bending stiffness per hinge)
  and per particle its layer (the garment it belongs to: 0 for one garment; ``sim.outfit`` joins
  several garments into one model, inner first) and its world (the job it belongs to: 0 for one
  job; ``sim.worlds`` joins several jobs' models, each on its own body, into one model).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from darts.dart.model import Dart, merged_index
from darts.geometry.mesh import half_edges, interior_edge_halves, unique_edges

#: The feature line a skirt or trousers is held up by (its waistband), and how far (m, at rest)
#: the band's grip reaches into the cloth below it.
WAIST_LINE = "waist"
WAISTBAND = 0.03


@dataclass
class ClothModel:
    """Arrays for the solver; every index is a particle index."""

    rest: np.ndarray  # [P,3]
    particle_of_vertex: np.ndarray  # [V]
    faces: np.ndarray  # [F,3]
    mass: np.ndarray  # [P]
    edges: np.ndarray  # [E,2]
    edge_rest: np.ndarray  # [E]
    hinges: np.ndarray  # [H,4]
    hinge_rest_angle: np.ndarray  # [H] radians, 0 = flat
    springs: np.ndarray  # [S,2]
    spring_rest: np.ndarray  # [S]
    spring_stiffness: np.ndarray  # [S] N/m
    spring_seam: np.ndarray  # [S] index into seam_names
    spring_anchors: np.ndarray  # [S,2] an off-seam neighbour of each end (-1: none), for repulsion
    edge_stiffness: np.ndarray  # [E] N/m, the stretch stiffness of each edge's material
    hinge_bend: np.ndarray  # [H] N m, the bending stiffness k_b of each hinge's material
    layer: np.ndarray  # [P] the garment (layer, inner first) of each particle
    body_offset: np.ndarray  # [P] m kept off the body beyond the thickness (outer layers over inner ones)
    seam_names: list[str]
    material: dict
    loops: dict = field(default_factory=dict)  # feature line name -> its closed loop of particle indices
    world: np.ndarray | None = None  # [P] the job (world) of each particle; None: all in world 0

    def __post_init__(self):
        if self.world is None:
            self.world = np.zeros(len(self.rest), np.int64)

    @property
    def worlds(self) -> int:
        """How many jobs (worlds) the model holds side by side."""
        return int(self.world.max(initial=0)) + 1

    def grip(self, waist: float) -> np.ndarray:
        """[P] each particle's Coulomb friction against the body where it grips (``BodyCollider``'s
        ``grip``): the material's μ_m, and on the waistband of a skirt or trousers, where ``waist``
        > 0, μ = μ_m + (``waist`` - μ_m)(1 - d / w) for a particle a rest distance d < w =
        ``WAISTBAND`` from the waist line (``WAIST_LINE``; an outfit's ``garment/waist``): an
        elastic band that grips the skin where woven cloth slides, tapering into the cloth below it
        (a grip on the line alone shears the row under it)."""
        from scipy.spatial import cKDTree

        material = float(self.material["friction"])
        friction = np.full(len(self.rest), material)
        if waist > 0:
            for name, loop in self.loops.items():
                if name.split("/")[-1] == WAIST_LINE:
                    distance, _ = cKDTree(self.rest[loop]).query(self.rest)
                    band = distance < WAISTBAND
                    friction[band] = material + (waist - material) * (1.0 - distance[band] / WAISTBAND)
        return friction

    def springs_and_edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every elastic pair: the edges (the material's stretch stiffness) then the sprung seam
        pairs (their seam's stiffness) as pairs [N,2] int32, rest lengths [N] and stiffnesses [N] (N/m)."""
        sprung = self.spring_stiffness > 0
        pairs = np.concatenate([self.edges, self.springs[sprung]]).astype(np.int32)
        rest = np.concatenate([self.edge_rest, self.spring_rest[sprung]])
        stiffness = np.concatenate([self.edge_stiffness, self.spring_stiffness[sprung]])
        return pairs, rest, stiffness


def join_models(models: list[ClothModel], names: list[str], worlds: bool = False) -> ClothModel:
    """One model holding ``models`` side by side (indices shifted; loops and seams prefixed by
    ``names``). As an outfit's garments (``worlds`` False) model k is layer k, and the thickness and
    friction are the largest of the models'; as worlds (``worlds`` True) model k is world k, each
    keeps its own layers, and their thickness and friction must agree (one solver steps them all)."""
    offsets = np.cumsum([0] + [len(m.rest) for m in models])
    seam_offsets = np.cumsum([0] + [len(m.seam_names) for m in models])

    def cat(key, shift=True):
        return np.concatenate([getattr(m, key) + (offsets[k] if shift else 0) for k, m in enumerate(models)])

    def each(values):
        return np.concatenate([np.full(len(m.rest), v) if np.ndim(v) == 0 else v for m, v in zip(models, values)])

    anchors = np.concatenate([np.where(m.spring_anchors >= 0, m.spring_anchors + offsets[k], -1) for k, m in enumerate(models)])
    material = dict(models[0].material)
    for key in ("thickness", "friction"):
        values = {float(m.material[key]) for m in models}
        if worlds and len(values) > 1:
            raise ValueError(f"worlds of one model need one {key}, got {sorted(values)}")
        material[key] = max(values)
    index = range(len(models))
    return ClothModel(
        rest=cat("rest", False), particle_of_vertex=cat("particle_of_vertex"), faces=cat("faces"), mass=cat("mass", False),
        edges=cat("edges"), edge_rest=cat("edge_rest", False), hinges=cat("hinges"),
        hinge_rest_angle=cat("hinge_rest_angle", False), springs=cat("springs"), spring_rest=cat("spring_rest", False),
        spring_stiffness=cat("spring_stiffness", False),
        spring_seam=np.concatenate([m.spring_seam + seam_offsets[k] for k, m in enumerate(models)]),
        spring_anchors=anchors.reshape(-1, 2), edge_stiffness=cat("edge_stiffness", False),
        hinge_bend=cat("hinge_bend", False), body_offset=cat("body_offset", False),
        layer=each([m.layer for m in models] if worlds else list(index)),
        world=each(list(index) if worlds else [m.world for m in models]),
        seam_names=[f"{names[k]}/{s}" for k, m in enumerate(models) for s in m.seam_names], material=material,
        loops={f"{names[k]}/{line}": loop + offsets[k] for k, m in enumerate(models) for line, loop in m.loops.items()},
    )


def dihedral_angles(points: np.ndarray, hinges: np.ndarray) -> np.ndarray:
    """Signed angle between the normals of triangles (i, j, k) and (j, i, l), 0 when flat."""
    i, j, k, l = (points[hinges[:, c]] for c in range(4))
    edge = j - i
    n1 = np.cross(edge, k - i)
    n2 = np.cross(l - i, edge)
    n1 /= np.maximum(np.linalg.norm(n1, axis=1, keepdims=True), 1e-20)
    n2 /= np.maximum(np.linalg.norm(n2, axis=1, keepdims=True), 1e-20)
    unit = edge / np.maximum(np.linalg.norm(edge, axis=1, keepdims=True), 1e-20)
    return np.arctan2(np.einsum("ij,ij->i", np.cross(n1, n2), unit), np.einsum("ij,ij->i", n1, n2))


def _hinges(faces: np.ndarray) -> np.ndarray:
    """(i, j, k, l) for each edge shared by two faces: (i, j) the edge, k and l the opposite corners."""
    a, b, key = half_edges(faces)
    opposite = np.roll(faces, -2, axis=1).reshape(-1)
    first, second = interior_edge_halves(key)
    return np.stack([a[first], b[first], opposite[first], opposite[second]], 1)


def _anchors(ends: np.ndarray, edges: np.ndarray, on_seam: np.ndarray) -> np.ndarray:
    """For each particle in ``ends``, one edge neighbour that is on no seam (-1 where none is)."""
    both = np.concatenate([edges, edges[:, ::-1]])
    both = both[~on_seam[both[:, 1]]]
    first = np.full(len(on_seam), -1, np.int64)
    first[both[::-1, 0]] = both[::-1, 1]  # the last write wins: the first listed neighbour
    return first[ends]


def collapse_short_edges(points: np.ndarray, faces: np.ndarray, pinned: np.ndarray, min_length: float) -> np.ndarray:
    """Group index of each point after collapsing, shortest first, every edge shorter than
    ``min_length`` whose collapse keeps the surface a manifold (link condition, and no corner left
    with fewer than three neighbours) and puts at most one of the ``pinned`` points (indices) in a
    group: a group holding one sits on it, so seam ends stay matched with their partners."""
    neighbours = [set() for _ in range(len(points))]
    for a, b in np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]).tolist():
        neighbours[a].add(b)
        neighbours[b].add(a)
    opposite: dict[tuple[int, int], set] = {}
    for tri in faces.tolist():
        for c in range(3):
            a, b, o = tri[c], tri[(c + 1) % 3], tri[(c + 2) % 3]
            opposite.setdefault((min(a, b), max(a, b)), set()).add(o)
    on_seam = np.zeros(len(points), bool)
    on_seam[np.asarray(pinned, np.int64)] = True
    members = [{i} for i in range(len(points))]
    group = np.arange(len(points))
    lengths = np.linalg.norm(points[faces[:, [1, 2, 0]]] - points[faces], axis=2).reshape(-1)
    short = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]], 0)[
        np.argsort(np.concatenate([lengths[0::3], lengths[1::3], lengths[2::3]]))]
    for a, b in short[np.sort(np.concatenate([lengths[0::3], lengths[1::3], lengths[2::3]])) < min_length].tolist():
        a, b = group[a], group[b]
        key = (min(a, b), max(a, b))
        if (a == b or key not in opposite or neighbours[a] & neighbours[b] != opposite[key]
                or any(len(neighbours[o]) < 4 for o in opposite[key]) or (on_seam[a] and on_seam[b])):
            continue
        for n in neighbours[b] - {a}:  # b's edges and faces become a's
            neighbours[n].discard(b)
            neighbours[n].add(a)
            for o in opposite.pop((min(b, n), max(b, n)), set()):
                if o != a:
                    opposite.setdefault((min(a, n), max(a, n)), set()).add(o)
        for edge, others in opposite.items():
            if b in others:
                others.discard(b)
                if a not in edge:
                    others.add(a)
        opposite.pop(key, None)
        neighbours[a] |= neighbours[b] - {a, b}
        neighbours[a].discard(b)
        members[a] |= members[b]
        on_seam[a] |= on_seam[b]
        group[list(members[b])] = a
    return np.unique(group, return_inverse=True)[1]


#: Edges shorter than this fraction of the median edge are collapsed in the solver's model.
SHORT_EDGE_FRACTION = 0.3


def cloth_model(dart: Dart) -> ClothModel:
    """The solver's model of ``dart`` (rest state in the canonical frame)."""
    welded_seams = [i for i, s in enumerate(dart.seams) if s.regime == "welded"]
    particle = merged_index(dart, dart.pairs[np.isin(dart.pair_seam, welded_seams)])
    rest = np.zeros((particle.max() + 1, 3))
    rest[particle] = dart.vertices
    faces = particle[dart.faces]
    sprung = dart.pair_active & ~np.isin(dart.pair_seam, welded_seams)
    edge_lengths = np.linalg.norm(rest[faces[:, [1, 2, 0]]] - rest[faces], axis=2)
    seam_ends = np.unique(particle[dart.pairs[~np.isin(dart.pair_seam, welded_seams)]])
    group = collapse_short_edges(rest, faces, seam_ends, SHORT_EDGE_FRACTION * np.median(edge_lengths))
    count = group.max() + 1
    merged = np.zeros((count, 3))
    np.add.at(merged, group, rest)
    merged /= np.bincount(group, minlength=count)[:, None]
    merged[group[seam_ends]] = rest[seam_ends]  # a group with a seam end sits on it
    particle, rest = group[particle], merged
    faces = particle[dart.faces].astype(np.int64)
    faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])]
    tri = rest[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    mass = np.zeros(count)
    np.add.at(mass, faces.reshape(-1), np.repeat(area / 3.0 * dart.material["density"], 3))
    # A particle whose only faces have no area (two seam ends meeting at a seam's end, say) still
    # needs a mass; it takes the lightest one found elsewhere.
    mass[mass <= 0] = mass[mass > 0].min()
    edges = unique_edges(faces)
    hinges = _hinges(faces)
    seam_of = dart.pair_seam[sprung]
    springs = particle[dart.pairs[sprung]].astype(np.int64)
    on_seam = np.zeros(count, bool)
    on_seam[particle[dart.pairs.reshape(-1)]] = True
    return ClothModel(
        rest=rest, particle_of_vertex=particle, faces=faces, mass=mass, edges=edges,
        edge_rest=np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1),
        hinges=hinges, hinge_rest_angle=dihedral_angles(rest, hinges),
        springs=springs, spring_anchors=_anchors(springs, edges, on_seam),
        spring_rest=np.array([dart.seams[s].rest_length for s in seam_of]),
        spring_stiffness=np.array([dart.seams[s].stiffness for s in seam_of]),
        spring_seam=seam_of.astype(np.int64), seam_names=dart.seam_names, material=dict(dart.material),
        edge_stiffness=np.full(len(edges), float(dart.material["stretch_stiffness"])),
        hinge_bend=np.full(len(hinges), float(dart.material["bend_stiffness"])), layer=np.zeros(count, np.int64),
        body_offset=np.zeros(count),
        loops={name: particle[np.asarray(loop, np.int64)] for name, loop in dart.lines.items()},
    )
