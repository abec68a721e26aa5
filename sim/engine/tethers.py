"""Long-range tethers: unilateral distance limits that carry a garment's stretch resistance across
many edges at once (in the spirit of long-range attachments, Kim et al. 2012, and hierarchical PBD,
Müller 2008), so that few Gauss-Seidel sweeps hold a hanging skirt or a waistband at its length.

A tether (i, j) only acts when |x_i - x_j| > limit (C = |x_i - x_j| - limit <= 0, projected with
zero compliance), so it never resists folding or compression. Two kinds, all in the rest shape
(canonical frame, metres):

- **surface tethers**: for each particle, ``per_particle`` partners drawn (seeded) among the
  particles whose rest distance along the surface is between r and 1.25 r, for r = each of
  ``LEVELS`` times the median edge length; the limit is the shortest path to them through the
  graph of edges and two-edge hops (rest Euclidean lengths), an estimate of the geodesic distance
  (median 2 % above the straight chord on the shipped top), so an isometric motion (unfolding,
  flattening) is never resisted; times ``scale`` (``SimSettings.tether_scale``, 1 by default), never
  under the rest chord: a scale a little under 1 trims the path's overestimate of the surface
  distance, so the tethers bind sooner. Stiff seams join the graph with length 0 (tethers cross them).
- **loop tethers**: along every closed feature line (waist, hem, cuffs, neckline), every particle
  to the ones 2, 4, 8, ... positions further round the loop, limited to the arc length between
  them along the loop (a chord never exceeds its arc); the waist, which holds a skirt or trousers up,
  is limited to its rest chords instead, since a round loop's arcs never bind (``HELD_LOOPS``): a
  waistband keeps its rest shape, which is the body's.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from darts.geometry.mesh import vertex_normals
from sim.engine.model import ClothModel

#: Surface-tether radii in median edge lengths: a near ring and a far one.
LEVELS = (4, 12)
#: Loops that hold a garment up (a waistband) keep their rest shape: their tethers are limited to
#: the rest chord, so the loop can neither lengthen nor widen into an ellipse of the same length (a
#: round loop's arcs never bind: a chord is always shorter than its arc).
HELD_LOOPS = ("waist",)
#: Seam springs at least this stiff (N/m) count as joined for the surface graph (stiff, partial).
JOINED_SEAM_STIFFNESS = 1000.0


#: Two-edge hops join the surface graph only where the rest normals at their ends are this close (rad).
FLAT_ANGLE = np.radians(10.0)


def _surface_graph(model: ClothModel) -> sp.csr_matrix:
    """Edges and (where the rest shape is flat) two-edge hops of the rest mesh weighted by their
    rest Euclidean length, plus the stiff seam pairs (at a nominal 1e-9 m)."""
    n = len(model.rest)
    e = model.edges
    adjacency = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    adjacency = adjacency.maximum(adjacency.T)
    joined = model.springs[model.spring_stiffness >= JOINED_SEAM_STIFFNESS]
    if len(joined):
        seams = sp.coo_matrix((np.ones(len(joined)), (joined[:, 0], joined[:, 1])), shape=(n, n)).tocsr()
        adjacency = adjacency.maximum(seams.maximum(seams.T))
    reach = (adjacency @ adjacency + adjacency).tocoo()
    upper = reach.row < reach.col
    rows, cols = reach.row[upper], reach.col[upper]
    # A two-edge hop's straight chord is the surface distance only where the surface is flat between
    # its ends: across a crease of the rest shape it is shorter, and a tether limited by it would
    # resist unfolding the crease. Hops whose ends' normals differ by more than FLAT_ANGLE are left out.
    normal = vertex_normals(model.rest, model.faces)
    flat = np.einsum("ij,ij->i", normal[rows], normal[cols]) >= np.cos(FLAT_ANGLE)
    direct = np.asarray(adjacency[rows, cols]).ravel() > 0
    rows, cols = rows[flat | direct], cols[flat | direct]
    length = np.maximum(np.linalg.norm(model.rest[rows] - model.rest[cols], axis=1), 1e-9)
    graph = sp.coo_matrix((length, (rows, cols)), shape=(n, n)).tocsr()
    return graph.maximum(graph.T)


def surface_tethers(model: ClothModel, per_particle: int = 3, seed: int = 0, chunk: int = 256, scale: float = 1.0):
    """Surface tethers of ``model``: pairs [T,2] and limits [T] (m), max(rest chord, ``scale`` x graph path).
    Each world of a many-world model (its particles contiguous, no edge between worlds) gets the
    tethers it would get alone, drawn from its own generator seeded ``seed``."""
    graph = _surface_graph(model)
    pairs, limits = [], []
    ends = np.flatnonzero(np.diff(model.world)) + 1
    for first, last in zip(np.r_[0, ends], np.r_[ends, len(model.rest)]):
        rng = np.random.default_rng(seed)
        spacing = float(np.median(model.edge_rest[(model.edges[:, 0] >= first) & (model.edges[:, 0] < last)]))
        radii = [level * spacing for level in LEVELS]
        world = graph[first:last, first:last]
        for start in range(0, last - first, chunk):
            sources = np.arange(start, min(last - first, start + chunk))
            # the graph is symmetric: searched as directed, the same distances without symmetrising it
            distance = dijkstra(world, directed=True, indices=sources, limit=1.25 * max(radii))
            near_rows, near_cols = np.nonzero(distance < np.inf)  # row-major, as the per-ring selections below
            later = near_cols > sources[near_rows]
            near_rows, near_cols = near_rows[later], near_cols[later]
            near = distance[near_rows, near_cols]
            for r in radii:
                ring = (near >= r) & (near < 1.25 * r)
                rows, cols = near_rows[ring], near_cols[ring]
                # ``per_particle`` of each source's candidates, drawn by sorting on a random key
                order = np.lexsort((rng.random(len(rows)), rows))
                rows, cols = rows[order], cols[order]
                first_of_row = np.searchsorted(rows, rows)  # index of each row's first candidate
                keep = np.arange(len(rows)) - first_of_row < per_particle
                pairs.append(np.stack([sources[rows[keep]], cols[keep]], 1) + first)
                limits.append(distance[rows[keep], cols[keep]])
    if not pairs:
        return np.zeros((0, 2), np.int64), np.zeros(0)
    pairs = np.concatenate(pairs)
    chord = np.linalg.norm(model.rest[pairs[:, 0]] - model.rest[pairs[:, 1]], axis=1)
    return pairs, np.maximum(chord, scale * np.concatenate(limits))


def loop_tethers(model: ClothModel, loops: list[np.ndarray], held: list[bool] | None = None):
    """Loop tethers along each closed particle loop in ``loops``: pairs [T,2] and limits [T] (m);
    a ``held`` loop is limited to its rest chords instead of its arcs."""
    pairs, limits = [], []
    for index, loop in enumerate(loops):
        loop = np.asarray(loop, np.int64)
        loop = loop[np.r_[True, loop[1:] != loop[:-1]]]
        if len(loop) > 2 and loop[0] == loop[-1]:
            loop = loop[:-1]
        count = len(loop)
        segment = np.linalg.norm(model.rest[np.roll(loop, -1)] - model.rest[loop], axis=1)
        along = np.concatenate([[0.0], np.cumsum(segment)])
        total = along[-1]
        i = np.arange(count)
        skip = 2
        while skip <= count // 2:
            j = (i + skip) % count
            arc = np.where(j > i, along[j] - along[i], total - along[i] + along[j])
            pairs.append(np.stack([loop[i], loop[j]], 1))
            if held is not None and held[index]:
                limits.append(np.linalg.norm(model.rest[loop[i]] - model.rest[loop[j]], axis=1))
            else:
                limits.append(np.minimum(arc, total - arc))
            skip *= 2
    if not pairs:
        return np.zeros((0, 2), np.int64), np.zeros(0)
    return np.concatenate(pairs), np.concatenate(limits)


def tethers(model: ClothModel, seed: int = 0, scale: float = 1.0):
    """Every tether of ``model`` (surface, with ``scale``, then loop): pairs [T,2] and limits [T] (m)."""
    surface = surface_tethers(model, seed=seed, scale=scale)
    loops = loop_tethers(model, list(model.loops.values()), [name.split("/")[-1] in HELD_LOOPS for name in model.loops])
    return np.concatenate([surface[0], loops[0]]).astype(np.int64), np.concatenate([surface[1], loops[1]])
