"""A triangle mesh cut into panels along the borders of a distance field, exactly, not along its
own edges (the file's mesh of ``darts import --own-mesh``, cut into the registered template's panels).

Each vertex v carries its distance D[v, p] to every panel p (of the registered template). Its
panel is the nearest, a(v) = argmin_p D[v, p]; the border between panels a and b is the zero set
of phi_ab = D[:, a] - D[:, b], which on the template's own surface is the seam where a and b meet.
A vertex's *allowed* panels A(v) are those within ``TIE`` of its nearest (a vertex on a seam has
two or three). Then:

1. **Snapped**: an edge (u, w) whose ends share no allowed panel crosses a border at
   t = phi(u) / (phi(u) - phi(w)) along it (phi linear along the edge). Where t < ``SNAP`` of the
   way from u, and every neighbour of u lies in the same two panels, u moves there (along the edge:
   it stays on the mesh's surface; a vertex on an opening only along the opening) and becomes a
   border vertex of both, so no sliver is cut off.
2. **Split**: every edge whose ends still share no allowed panel gets a new vertex at its crossing
   (at least ``MARGIN`` of the edge from either end);
   a triangle with one or two split edges is cut along the segment joining its border points into
   a triangle and a quadrilateral (two triangles), each a panel its vertices allow; one with three
   (three panels meet inside it) into three corner quadrilaterals around the point where the three
   borders meet (``_triple_point``). A triangle whose every vertex is on a border takes the panel
   nearest its corners.
3. A patch of one panel of under ``MIN_PATCH`` vertices (joined by edges) joins the panel around
   it before any of this.

The new vertices lie on the mesh's triangles (on its edges, or inside one triangle): the surface is
the mesh's, only triangulated along the borders. Openings given as vertex loops get the new
vertices of their split edges. (``darts.geometry.levelset`` inserts the zero set of one field, for
a template's seams one at a time; here every border of P panels at once.)
"""
from __future__ import annotations

import numpy as np

from darts.geometry.mesh import unique_edges

#: A vertex whose distance to another panel is within this of its nearest (metres) lies on their border.
TIE = 1e-6
#: A crossing closer than this share of an edge to one end moves that end onto it instead of cutting.
SNAP = 0.2
#: A crossing that cannot be snapped (the vertex near it borders a third panel) is cut at least this
#: share of the edge from either end: half a millimetre off on a centimetre's edge, and no sliver.
MARGIN = 0.05
#: A connected patch of one panel with fewer vertices joins the panel around it.
MIN_PATCH = 10


def _merge_small_patches(labels: np.ndarray, distances: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """``distances`` [N,P] with each vertex of a small patch (module docstring, 3) made nearest to
    the panel most of the patch's neighbours are in (a tenth of a millimetre nearer than its own)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    same = labels[edges[:, 0]] == labels[edges[:, 1]]
    graph = coo_matrix((np.ones(same.sum()), (edges[same, 0], edges[same, 1])), shape=(len(labels),) * 2)
    _, patch = connected_components(graph, directed=False)
    distances = distances.copy()
    for small in np.flatnonzero(np.bincount(patch) < MIN_PATCH):
        inside = patch == small
        rim = edges[inside[edges[:, 0]] != inside[edges[:, 1]]]
        around = labels[np.where(inside[rim[:, 0]], rim[:, 1], rim[:, 0])]
        if len(around):
            panel = np.bincount(around).argmax()
            distances[inside, panel] = distances[inside].min(1) - 1e-4
    return distances


def _snap(vertices: np.ndarray, faces: np.ndarray, distances: np.ndarray, allowed: list[set], edges: np.ndarray,
          neighbours: list[list[int]]) -> np.ndarray:
    """``vertices`` with the ends close to a crossing moved onto it (``allowed`` updated in place);
    a vertex on an opening moves only along the opening, which keeps its outline."""
    from darts.geometry.mesh import boundary_edges

    rim_edges = {tuple(sorted(edge)) for edge in boundary_edges(faces).tolist()}
    on_rim = np.zeros(len(vertices), bool)
    on_rim[np.asarray(list(rim_edges), np.int64).reshape(-1)] = True
    labels = distances.argmin(1)
    crossing = np.array([not (allowed[u] & allowed[w]) for u, w in edges.tolist()], bool)
    candidates = []
    for u, w in edges[crossing].tolist():
        a, b = labels[u], labels[w]
        phi_u, phi_w = distances[u, a] - distances[u, b], distances[w, a] - distances[w, b]
        t = phi_u / (phi_u - phi_w) if phi_u != phi_w else 0.5
        candidates += [(t, u, w, a, b), (1.0 - t, w, u, b, a)]
    vertices = vertices.copy()
    for t, u, w, a, b in sorted(candidates):
        if t >= SNAP:
            break
        if len(allowed[u]) > 1 or len(allowed[w]) > 1 or not all(allowed[n] <= {a, b} for n in neighbours[u]):
            continue
        if on_rim[u] and (min(u, w), max(u, w)) not in rim_edges:
            continue
        vertices[u] = vertices[u] + t * (vertices[w] - vertices[u])
        allowed[u] = {a, b}
    return vertices


def _triple_point(corners: np.ndarray, distances: np.ndarray) -> np.ndarray:
    """The point of the triangle ``corners`` [3,3] where the borders of its corners' three panels
    meet. ``distances`` [3,3]: corner k's distance to corner j's panel. With every field linear over
    the triangle, the barycentric weights w solve sum(w) = 1 and sum_k w_k (D[k,0] - D[k,1]) =
    sum_k w_k (D[k,0] - D[k,2]) = 0; each weight is kept at least ``MARGIN`` (then renormalised), so
    the point stays inside and cuts no sliver; a degenerate system gives the centroid."""
    system = np.stack([np.ones(3), distances[:, 0] - distances[:, 1], distances[:, 0] - distances[:, 2]])
    try:
        weights = np.linalg.solve(system, [1.0, 0.0, 0.0])
    except np.linalg.LinAlgError:
        weights = np.full(3, 1.0 / 3.0)
    weights = np.clip(weights, MARGIN, None)
    return (weights / weights.sum()) @ corners


def cut_along_panels(vertices: np.ndarray, faces: np.ndarray, distances: np.ndarray,
                     loops: dict[str, np.ndarray] | None = None,
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """(vertices [N',3], faces [F',3], each face's panel [F'], ``loops`` through the new vertices) of
    the mesh ``vertices`` [N,3], ``faces`` [F,3] triangulated along the borders of ``distances``
    [N,P] (module docstring). The first N vertices are the mesh's (a few moved along an edge)."""
    faces = np.asarray(faces, np.int64)
    distances = np.asarray(distances, np.float64)
    edges = unique_edges(faces)
    distances = _merge_small_patches(distances.argmin(1), distances, edges)
    nearest = distances.min(1, keepdims=True)
    allowed = [set(np.flatnonzero(row).tolist()) for row in distances <= nearest + TIE]
    neighbours = [[] for _ in range(len(vertices))]
    for u, w in edges.tolist():
        neighbours[u].append(w)
        neighbours[w].append(u)
    vertices = _snap(np.asarray(vertices, np.float64), faces, distances, allowed, edges, neighbours)
    labels = distances.argmin(1)
    for v, panels in enumerate(allowed):  # a vertex's own panel is its nearest allowed one
        if len(panels) > 1:
            labels[v] = min(panels, key=lambda p: distances[v, p])

    points = list(vertices)
    split = {}  # sorted edge -> its new vertex

    def crossing(u: int, w: int) -> int | None:
        if allowed[u] & allowed[w]:
            return None
        key = (min(u, w), max(u, w))
        if key not in split:
            a, b = labels[key[0]], labels[key[1]]
            phi = distances[list(key), a] - distances[list(key), b]
            t = float(np.clip(phi[0] / (phi[0] - phi[1]), MARGIN, 1.0 - MARGIN)) if phi[0] != phi[1] else 0.5
            split[key] = len(points)
            points.append(vertices[key[0]] + t * (vertices[key[1]] - vertices[key[0]]))
        return split[key]

    def panel_of(ends: list[int]) -> int:
        """The panel the ``ends`` (original vertices of a region) all allow, nearest on average."""
        shared = set.intersection(*(allowed[v] for v in ends))
        if not shared:
            shared = set.union(*(allowed[v] for v in ends))
        return min(shared, key=lambda p: distances[ends, p].sum())

    new_faces, face_panels = [], []

    def add(polygon: list[int], ends: list[int]) -> None:
        panel = panel_of(ends)
        for k in range(1, len(polygon) - 1):
            new_faces.append((polygon[0], polygon[k], polygon[k + 1]))
            face_panels.append(panel)

    for face in faces.tolist():
        cuts = [crossing(face[k], face[(k + 1) % 3]) for k in range(3)]  # on edge k: corner k to k + 1
        count = sum(c is not None for c in cuts)
        if count == 0:
            add(face, face)
        elif count == 3:
            middle = len(points)
            corner_panels = labels[face]
            three = len(set(corner_panels.tolist())) == 3
            points.append(_triple_point(vertices[face], distances[np.ix_(face, corner_panels)]) if three
                          else np.mean([points[c] for c in cuts], axis=0))
            for k in range(3):
                add([face[k], cuts[k], middle, cuts[k - 1]], [face[k]])
        elif count == 1:  # the cut edge a-b, c opposite
            k = next(k for k in range(3) if cuts[k] is not None)
            a, b, c, x = face[k], face[(k + 1) % 3], face[(k + 2) % 3], cuts[k]
            add([c, a, x], [c, a])
            add([c, x, b], [c, b])
        else:  # the corner c between the two cut edges, cut off from a and b
            k = next(k for k in range(3) if cuts[k] is not None and cuts[k - 1] is not None)
            c, a, b = face[k], face[(k + 1) % 3], face[(k + 2) % 3]
            to_a, from_b = cuts[k], cuts[k - 1]  # on c-a and on b-c
            add([c, to_a, from_b], [c])
            add([to_a, a, b, from_b], [a, b])
    result_loops = {}
    for name, loop in (loops or {}).items():
        walk = []
        loop = [int(v) for v in loop]
        for k, v in enumerate(loop):
            walk.append(v)
            key = (min(v, loop[(k + 1) % len(loop)]), max(v, loop[(k + 1) % len(loop)]))
            if key in split:
                walk.append(split[key])
        result_loops[name] = np.asarray(walk, np.int64)
    return np.asarray(points), np.asarray(new_faces, np.int64), np.asarray(face_panels, np.int64), result_loops
