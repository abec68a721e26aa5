"""The imported mesh itself as the DART (``darts import --own-mesh``): the registered template lends
it its panels, seams, seam regimes, material and feature-line names; the surface, its triangles
and whatever the template lacks (a collar, a pocket, a ruffle) are the file's.

1. **Panels**: each mesh vertex is nearest one panel of the registered template; the borders
   between panels are where a point is as near one as the other, which on the template's surface
   are its seams. The mesh is cut exactly along them (``darts.meshimport.panel_cut``: triangles
   split where a border crosses them, a vertex next to a border moved onto it), not along its own
   edges, so a seam runs where the template's does and not half a triangle either side. A detail
   the template lacks lies nearest the panel it is attached to, and becomes part of it; one folded
   over the garment (a collar turned down over the shoulders, facing against the template's
   surface) would lie nearest the panels under it and be cut at their seams, so it is kept whole,
   in the panel its fold lies nearest, with the border along the fold, where it is sewn on
   (``_folded_details``: the round trip's collared tops' seams 7.1 / 6.9 mm off, now 4.3 / 2.7).
2. **Cut**: a vertex on a border between k panels becomes k vertices, one per panel; every two of
   them are a seam pair, on the seam of the nearest template pair between the same two panels
   (two panels may share several seams: the shoulders and the sides), at that pair's position
   along it; a border the template has no seam for is a new stiff seam named after both panels.
   A seam inside one panel (a sleeve's underarm) is not cut: the panel stays one piece there.
3. **Lines**: the mesh's openings, named when it was placed, run through both copies where they
   cross a cut, as in every DART.
4. **Rest pose**: a mesh placed with the arms lowered is taken back to rest vertex by vertex by the
   blended transform of its nearest template vertex (``darts.meshimport.pose``).
5. **Out of the body**: a garment smaller than this body somewhere (made for another avatar:
   Newton's shirt at its own size has 13 % of its vertices up to 21 mm inside the default body's
   chest) is then moved out (``out_of_body``).
Canonical frame, Y up, metres.
"""
from __future__ import annotations

from dataclasses import replace
from itertools import combinations

import numpy as np

from darts.dart.model import Dart, Seam


def _panel_distances(template: Dart, points: np.ndarray) -> np.ndarray:
    """[N,P] each point's unsigned distance to each panel of ``template`` (its own faces)."""
    from darts.geometry.distance import SurfaceDistance

    template_vertices = np.asarray(template.vertices, np.float64)
    panels = np.asarray(template.panel)
    faces = np.asarray(template.faces)
    return np.stack([np.abs(SurfaceDistance(template_vertices, faces[panels == p]).query(points, winding=False)[0])
                     for p in range(len(template.panel_names))], 1)


#: A detail is a connected region of at least this many triangles folded against the template.
FOLD_MIN = 20


def _folded_details(template: Dart, vertices: np.ndarray, faces: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each detail the template lacks that is folded over the garment (a collar turned down over the
    shoulders at the neckline it is sewn to) as (its vertices [N] mask, its fold [N] mask) of the
    mesh ``vertices``, ``faces``: a connected region (triangles sharing edges) of at least
    ``FOLD_MIN`` triangles whose normal faces against the template's face normal at their centroid's
    closest point (n_mesh . n_template < 0; the mesh's winding oriented to the template's by the
    area-weighted median). Its vertices are those whose every triangle is in it; its fold, those
    with triangles in it and out of it: the line where it turns over, where it is sewn on."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from darts.geometry.distance import SurfaceDistance

    corners = vertices[faces]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = np.linalg.norm(normal, axis=1)
    surface = SurfaceDistance(np.asarray(template.vertices, np.float64), np.asarray(template.faces, np.int64))
    facing = (normal * surface.query(corners.mean(1), winding=False)[2]).sum(1) / np.maximum(area, 1e-18)
    order = np.argsort(facing)
    median = facing[order][np.searchsorted(np.cumsum(area[order]), 0.5 * area.sum())]
    folded = facing * (1.0 if median >= 0 else -1.0) < 0

    face_ids = np.flatnonzero(folded)
    corner_face = np.repeat(np.arange(len(faces)), 3)
    incidence = coo_matrix((np.ones(3 * len(faces)), (faces.reshape(-1), corner_face)), shape=(len(vertices), len(faces))).tocsr()
    sub = incidence[:, face_ids]
    adjacency = (sub.T @ sub) >= 2  # two folded triangles sharing an edge
    _, region = connected_components(adjacency, directed=False)
    triangles = np.asarray(incidence.sum(1)).ravel()  # of each vertex
    details = []
    for r in np.flatnonzero(np.bincount(region) >= FOLD_MIN):
        in_region = np.asarray(sub[:, region == r].sum(1)).ravel()  # each vertex's triangles in region r
        touching = in_region > 0
        inside = touching & (in_region == triangles)
        details.append((inside, touching & ~inside))
    return details


def _join_folded_details(distances: np.ndarray, details: list[tuple[np.ndarray, np.ndarray]]) -> None:
    """``distances`` [N,P] (each mesh vertex to each panel) changed in place so each folded detail
    (``_folded_details``) is part of the panel most of its fold lies nearest (a tenth of a
    millimetre nearer than its nearest), and its fold a border of that panel (as near it as its
    nearest): the panels meet along the fold, where the detail is sewn on. A detail with no fold (a
    loose piece) joins the panel most of it lies nearest."""
    for inside, fold in details:
        panel = np.bincount(distances[fold if fold.any() else inside].argmin(1)).argmax()
        distances[inside, panel] = distances[inside].min(1) - 1e-4
        distances[fold, panel] = distances[fold].min(1)


def _vertex_panels(dart: Dart) -> np.ndarray:
    """[V] the panel of each DART vertex (panels are split at the seams: one each)."""
    panel = np.full(len(dart.vertices), -1)
    panel[np.asarray(dart.faces).reshape(-1)] = np.repeat(np.asarray(dart.panel), 3)
    return panel


def out_of_body(vertices: np.ndarray, faces: np.ndarray, surface) -> np.ndarray:
    """``vertices`` [N,3] (a welded mesh) with the parts in or within ``CLEARANCE`` of the body
    (``surface``, a ``FitSurface`` in the mesh's pose) moved out by one CRDL solve: every vertex a
    handle at its place, those pushed out (``FitSurface.push_out``) at a tenth of the weight, so
    the ARAP term spreads the move over the cloth around them and the fit term keeps them out."""
    from darts.crdl.layer import Crdl
    from darts.meshimport.register import CLEARANCE, ROUND_ITERATIONS

    targets = surface.push_out(vertices, CLEARANCE)
    moved = np.linalg.norm(targets - vertices, axis=1) > 0
    if not moved.any():
        return vertices
    layer = Crdl(vertices, faces, np.arange(len(vertices)), surface, handle_weights=np.where(moved, 0.1, 1.0))
    return layer.solve_local_global(targets, iterations=ROUND_ITERATIONS).vertices


def dart_from_mesh(template: Dart, vertices: np.ndarray, faces: np.ndarray, lines: dict[str, np.ndarray],
                   surface, rest=None) -> tuple[Dart, np.ndarray]:
    """The DART made of the mesh ``vertices`` [N,3], ``faces`` [F,3] (placed on the body, in the
    pose of the registered ``template``), its openings ``lines`` (name -> loop of mesh vertex
    indices), with ``rest`` (``darts.meshimport.pose.LoweredArms``, or None at rest) taking it back
    to the rest pose, and there moved out of the body (``out_of_body``; ``surface``: the body at
    rest, a ``FitSurface``) (module docstring)."""
    from darts.meshimport.panel_cut import cut_along_panels

    template_vertices = np.asarray(template.vertices, np.float64)
    vertices = np.asarray(vertices, np.float64)
    distances = _panel_distances(template, vertices)
    _join_folded_details(distances, _folded_details(template, vertices, faces))
    vertices, faces, labels, lines = cut_along_panels(vertices, faces, distances, lines)

    # the cut: one copy of each vertex per panel it touches
    keys = np.stack([faces.reshape(-1), np.repeat(labels, 3)], 1)
    copies, copy_of_corner = np.unique(keys, axis=0, return_inverse=True)
    new_faces = copy_of_corner.reshape(-1, 3)
    source = copies[:, 0]

    pairs, pair_panels = _copy_pairs(copies)
    seams, pair_seam, pair_position = _seams_of(template, vertices[source], pairs, pair_panels)
    new_lines = {name: _through_copies(loop, faces, labels, copies) for name, loop in lines.items()}

    positions = vertices if rest is None else rest.rest(vertices, _nearest_vertices(template_vertices, vertices)[1])
    outside = out_of_body(positions, faces, surface)
    moved = np.linalg.norm(outside - positions, axis=1)
    return replace(template, vertices=outside[source].astype(np.float32), faces=new_faces.astype(np.int32),
                   panel=labels.astype(np.int32), lines=new_lines, seams=seams, pairs=pairs.astype(np.int32),
                   pair_seam=pair_seam.astype(np.int32), pair_position=pair_position.astype(np.float32)), moved


def _copy_pairs(copies: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(seam pairs [P,2]: every two copies of one mesh vertex, indices into ``copies`` [C,2] (mesh
    vertex, panel; sorted by vertex); their panels [P,2], sorted)."""
    source = copies[:, 0]
    pairs, panels = [], []
    starts = np.flatnonzero(np.r_[True, source[1:] != source[:-1]])
    for start, end in zip(starts, np.r_[starts[1:], len(source)]):
        for a, b in combinations(range(start, end), 2):
            pairs.append((a, b))
            panels.append(sorted((int(copies[a, 1]), int(copies[b, 1]))))
    return np.asarray(pairs, np.int64).reshape(-1, 2), np.asarray(panels, np.int64).reshape(-1, 2)


def _through_copies(loop: np.ndarray, faces: np.ndarray, labels: np.ndarray, copies: np.ndarray) -> np.ndarray:
    """The opening ``loop`` (mesh vertices in order) as copies (``copies`` [C,2]: mesh vertex,
    panel): each vertex's copy in the panel of the opening's edge before it, and where the edge
    after it lies in another panel (a cut crosses the opening there), that panel's copy too."""
    edge_panel = {}
    for face, label in zip(faces.tolist(), labels.tolist()):
        for k in range(3):
            edge_panel[(face[k], face[(k + 1) % 3])] = edge_panel[(face[(k + 1) % 3], face[k])] = label
    copy_index = {(int(v), int(p)): i for i, (v, p) in enumerate(copies)}
    loop = [int(v) for v in loop]
    walk = []
    for k, vertex in enumerate(loop):
        before, after = edge_panel[(loop[k - 1], vertex)], edge_panel[(vertex, loop[(k + 1) % len(loop)])]
        walk.append(copy_index[(vertex, before)])
        if after != before:
            walk.append(copy_index[(vertex, after)])
    return np.asarray(walk, np.int32)


def _nearest_vertices(reference: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distance [N], index [N]) of each point's nearest ``reference`` vertex."""
    from scipy.spatial import cKDTree

    return cKDTree(reference).query(points)


def _seams_of(template: Dart, vertices: np.ndarray, pairs: np.ndarray,
              pair_panels: np.ndarray) -> tuple[list[Seam], np.ndarray, np.ndarray]:
    """(the seams: the template's and one new stiff seam per pair of panels it has none between;
    each pair's seam [P]; its position along it [P]: the nearest template pair's between the same
    two panels, 0 on a new seam). ``vertices`` are the copies', ``pair_panels`` [P,2] sorted."""
    seams = list(template.seams)
    pair_seam, positions = np.zeros(len(pairs), np.int64), np.zeros(len(pairs))
    template_pairs = np.asarray(template.pairs)
    template_panels = np.sort(_vertex_panels(template)[template_pairs], axis=1)
    template_middle = np.asarray(template.vertices, np.float64)[template_pairs].mean(1)
    middle = vertices[pairs].mean(1) if len(pairs) else np.zeros((0, 3))
    for panels in np.unique(pair_panels, axis=0):
        mine = np.all(pair_panels == panels, axis=1)
        theirs = np.all(template_panels == panels, axis=1)
        if theirs.any():
            _, nearest = _nearest_vertices(template_middle[theirs], middle[mine])
            pair_seam[mine] = np.asarray(template.pair_seam)[theirs][nearest]
            positions[mine] = np.asarray(template.pair_position)[theirs][nearest]
        else:
            names = [template.panel_names[p] for p in panels]
            seams.append(Seam(f"{names[0]}_{names[1]}"))
            pair_seam[mine] = len(seams) - 1
    return seams, pair_seam, positions
