"""Self-contact: a folded sheet drops onto itself, no vertex may cross a triangle of its own garment;
a strip dropped across another, touching it only between vertices, rests on it (edge-edge contact)."""
from __future__ import annotations

import numpy as np
from scipy.interpolate import LinearNDInterpolator
from scipy.spatial import cKDTree

from darts.geometry.mesh import unique_edges
from darts.geometry.warp_runtime import warp
from sim.engine.model import cloth_model
from sim.engine.self_contact import SelfContact
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
from tests.helpers import grid_sheet, sheet_dart

wp = warp()

SPACING = 0.01  # m between grid vertices
LAYER = 0.3  # m, length of each layer
RISE = 0.05  # m, the fold's height: the upper layer starts this far above the lower one
WIDTH = 0.2  # m


def folded_sheet() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A Z-up sheet folded once: the lower layer lies on the ground, the upper one RISE above it,
    joined by a vertical strip. Returns vertices [V,3], faces [F,3] and which vertices are upper."""
    s = np.arange(0.0, 2 * LAYER + RISE + 1e-9, SPACING)
    y = np.arange(0.0, WIDTH + 1e-9, SPACING)
    path = np.stack([np.where(s < LAYER, LAYER - s, np.where(s < LAYER + RISE, 0.0, s - LAYER - RISE)),
                     np.clip(s - LAYER, 0.0, RISE)], axis=1)
    vertices = np.array([[px, py, pz + 0.003] for px, pz in path for py in y])
    n = len(y)
    faces = []
    for i in range(len(s) - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, i * n + j + 1, (i + 1) * n + j, (i + 1) * n + j + 1
            faces += [[a, c, b], [b, c, d]] if (i + j) % 2 else [[a, c, d], [a, d, b]]
    upper = np.repeat(s > LAYER + RISE + 1e-9, n)
    return vertices, np.array(faces), upper


#: A tetrahedron far above everything: only the ground holds the lower layer.
FAR_BODY = (np.array([[0.0, 0.0, 50.0], [1.0, 0.0, 50.0], [0.0, 1.0, 50.0], [0.0, 0.0, 51.0]]),
            np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))


def _drop(self_contact: bool, frames: int = 20):
    vertices, faces, upper = folded_sheet()
    model = cloth_model(sheet_dart(vertices, faces))
    body_vertices, body_faces = FAR_BODY
    settings = SimSettings(self_contact=self_contact)
    solver = Simulation(model, model.rest, body_faces, body_vertices, settings)
    checker = SelfContact(solver.x, model.rest, model.faces, model.edges, 0.0, solver.self_contact.exclusion, "cpu")
    crossings = []
    for _ in range(frames):
        solver.step_frame(body_vertices)
        crossings.append(int(checker.crossing_edges().sum()))
    x = solver.positions()
    particle_upper = np.zeros(len(x), bool)
    particle_upper[model.particle_of_vertex[upper]] = True
    return x, particle_upper, crossings, solver.thickness


def _overlap(x: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Upper- and lower-layer particles away from the fold and the sheet's sides (5 cm and 3 cm)."""
    inside = (x[:, 0] > 0.05) & (x[:, 0] < LAYER - 0.05) & (x[:, 1] > 0.03) & (x[:, 1] < WIDTH - 0.03)
    return upper & inside, ~upper & inside


def test_fold_lands_on_itself_without_crossing():
    x, upper, crossings, thickness = _drop(True)
    assert max(crossings) == 0
    # The upper layer has landed (it fell 5 cm) and rests on the lower one, every particle of it at
    # least half a material thickness above the lower layer's particle right below it.
    over, under = _overlap(x, upper)
    assert x[over, 2].max() < 0.02
    below = cKDTree(x[under][:, :2]).query(x[over][:, :2])[1]
    assert np.all(x[over, 2] > x[under][below, 2] + 0.5 * thickness)


def test_without_self_contact_the_fold_passes_through():
    """The same drop with self-contact off: the upper layer reaches the lower one (the test above can fail)."""
    x, upper, _, thickness = _drop(False)
    over, under = _overlap(x, upper)
    below = cKDTree(x[under][:, :2]).query(x[over][:, :2])[1]
    assert np.any(x[over, 2] <= x[under][below, 2] + 0.5 * thickness)


STRIP_SPACING = 0.01  # m between a strip's rungs
STRIP_WIDTH = 0.004  # m: narrower than the rungs are apart, so no vertex lies over the other strip


def _strip(along_y: bool, height: float, rungs: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """A strip one quad wide through the origin along x (or y), its rungs at odd multiples of half
    STRIP_SPACING, so that where it crosses another such strip no vertex of either lies over the other."""
    t = (np.arange(rungs) - rungs / 2 + 0.5) * STRIP_SPACING
    vertices = np.array([[c, s, height] if along_y else [s, c, height] for s in t for c in (-STRIP_WIDTH / 2, STRIP_WIDTH / 2)])
    faces = []
    for i in range(rungs - 1):
        a, b, c, d = 2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3
        faces += [[a, c, b], [b, c, d]] if i % 2 else [[a, c, d], [a, d, b]]
    return vertices, np.array(faces)


def _cross_strips(edge_edge: bool, frames: int = 20) -> tuple[float, float, float]:
    """Drop a strip along y from 3 cm onto one along x lying on the ground; the heights (m) of the
    upper and lower strips' particles over the crossing (mean), and the material thickness."""
    lower, lower_faces = _strip(False, 0.003)
    upper, upper_faces = _strip(True, 0.033)
    model = cloth_model(sheet_dart(np.vstack([lower, upper]), np.vstack([lower_faces, upper_faces + len(lower)])))
    body_vertices, body_faces = FAR_BODY
    solver = Simulation(model, model.rest, body_faces, body_vertices, SimSettings())
    solver.self_contact.edge_edge = edge_edge
    for _ in range(frames):
        solver.step_frame(body_vertices)
    x = solver.positions()
    is_upper = np.zeros(len(x), bool)
    is_upper[model.particle_of_vertex[len(lower):]] = True
    crossing = (np.abs(x[:, 0]) < STRIP_SPACING) & (np.abs(x[:, 1]) < STRIP_SPACING)
    return x[is_upper & crossing, 2].mean(), x[~is_upper & crossing, 2].mean(), solver.thickness


def test_strip_rests_across_another_on_edge_contacts():
    upper, lower, thickness = _cross_strips(edge_edge=True)
    assert upper > lower + 0.5 * thickness  # on top, a material thickness up
    assert upper < lower + 2.0 * thickness  # and landed (it fell 3 cm)


def test_without_edge_contacts_the_strip_passes_through():
    """Vertex-triangle contact alone: the strips touch only between vertices, and the upper one falls
    through the lower one to the ground (the test above can fail)."""
    upper, lower, thickness = _cross_strips(edge_edge=False)
    assert upper < lower + 0.25 * thickness


def _two_sheets(gap: float):
    """Two 10 cm square sheets of 1 cm quads, the upper one ``gap`` above the lower (Z up); on the
    rest garment they lie 1 m apart, so neither is the other's neighbour. Positions, rest, faces, edges."""
    vertices, faces = grid_sheet(11, 0.01, (0.0, 0.0), lambda x, y: np.zeros_like(x))
    positions, rest, faces = _apart_on_rest((vertices, faces), (vertices + [0.0, 0.0, gap], faces))
    return positions, rest, faces, unique_edges(faces)


def _upper_contacts(speed: float, lookahead: float) -> int:
    """Upper-sheet particles that find a lower-sheet triangle, the sheets 8 mm apart and the upper one
    falling at ``speed`` (m/s), searched with a 3 mm reach and ``lookahead`` seconds."""
    positions, rest, faces, edges = _two_sheets(0.008)
    x = wp.array(positions.astype(np.float32), dtype=wp.vec3)
    velocities = np.zeros_like(positions)
    velocities[len(positions) // 2:, 2] = -speed
    contact = SelfContact(x, rest, faces, edges, 0.001, 0.015, "cpu")
    v = wp.array(velocities.astype(np.float32), dtype=wp.vec3)
    contact.search(x, v, 0.003, lookahead, 50.0)
    face = contact.face.numpy()[len(positions) // 2:]
    return int(np.sum((face >= 0) & (face < len(faces) // 2)))


def test_search_reaches_as_far_as_the_layers_close_before_the_next_search():
    """reach_i = 3 mm + T (|v_i - mean| + median): the upper sheet falling at 1 m/s has 0.5 m/s
    relative to the mean and the median is 0.5 m/s, so with T = 1/150 s it searches 9.7 mm and finds
    the lower sheet 8 mm below, every one of its 121 particles; without the lookahead (3 mm) or at
    rest none does."""
    assert _upper_contacts(1.0, 1.0 / 150.0) == 121
    assert _upper_contacts(1.0, 0.0) == 0
    assert _upper_contacts(0.0, 1.0 / 150.0) == 0


def _stacked_sheet(rng) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A sheet folded twice into a Z of three layers 4 mm apart (the folds 4 mm tall), then jittered
    by up to 1.5 mm: positions, rest (the unfolded sheet, so layers are far apart on it), faces, edges."""
    spacing, width, layer = 0.01, 0.1, 0.15
    s = np.arange(0.0, 3 * layer + 1e-9, spacing)
    y = np.arange(0.0, width + 1e-9, spacing)
    level = np.floor(s / layer).clip(0, 2)
    along = np.where(level == 1, 2 * layer - s, s - level * layer)
    positions = np.array([[px, py, 0.004 * pz] for px, pz in zip(along, level) for py in y])
    positions += rng.uniform(-0.0015, 0.0015, positions.shape)
    rest = np.array([[ps, py, 0.0] for ps in s for py in y])
    n = len(y)
    faces = np.array([f for i in range(len(s) - 1) for j in range(n - 1)
                      for f in (((i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1),
                                 (i * n + j, (i + 1) * n + j + 1, i * n + j + 1)))])
    edges = unique_edges(faces)
    return positions, rest, faces, edges


def _brute_force_contacts(positions, rest, faces, reach, exclusion) -> np.ndarray:
    """The closest facing triangle within ``reach`` of every particle whose corners are all farther
    than ``exclusion`` on the rest sheet (-1: none), every triangle tested; and the distance to it."""
    import trimesh

    p_index, f_index = np.meshgrid(np.arange(len(positions)), np.arange(len(faces)), indexing="ij")
    p_index, f_index = p_index.ravel(), f_index.ravel()
    far = (np.linalg.norm(rest[faces[f_index]] - rest[p_index][:, None], axis=2) > exclusion).all(1)
    p_index, f_index = p_index[far], f_index[far]
    triangles = positions[faces[f_index]]
    closest = trimesh.triangles.closest_point(triangles, positions[p_index])
    d = positions[p_index] - closest
    distance = np.linalg.norm(d, axis=1)
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    keep = (distance < reach) & (np.abs(np.einsum("ij,ij->i", d, normal)) >= 0.5 * distance)
    best, best_distance = np.full(len(positions), -1), np.full(len(positions), np.inf)
    for p, f, dist in zip(p_index[keep], f_index[keep], distance[keep]):
        if dist < best_distance[p]:
            best[p], best_distance[p] = f, dist
    return best, best_distance


def _matches_brute_force(contact, positions, rest, faces, reach, exclusion, which) -> int:
    """Assert that the particles ``which`` found the brute force's contact (or one as close: a tie
    may go either way); return how many of them have one."""
    import trimesh

    expected, distance = _brute_force_contacts(positions, rest, faces, reach, exclusion)
    found = contact.face.numpy()
    different = np.where((found != expected) & which)[0]
    if len(different):
        assert (found[different] >= 0).all()
        closest = trimesh.triangles.closest_point(positions[faces[found[different]]], positions[different])
        assert np.allclose(np.linalg.norm(positions[different] - closest, axis=1), distance[different], atol=1e-6)
    return int(((expected >= 0) & which).sum())


def test_candidate_lists_find_every_contact_the_brute_force_finds():
    """Three layers of a sheet folded into a Z, 4 mm apart and jittered: the broad phase's lists (within
    12 mm) and the search over them give every particle the same closest facing triangle within the
    7 mm reach as testing every triangle does, when the lists are made and after every particle has
    moved up to 1 mm with them kept; and so does a particle without a list (its reach over the most
    a list may cover), which searches the BVH."""
    rng = np.random.default_rng(3)
    positions, rest, faces, edges = _stacked_sheet(rng)
    x = wp.array(positions.astype(np.float32), dtype=wp.vec3)
    v = wp.zeros(len(positions), dtype=wp.vec3)  # at rest: every reach is the plain one
    exclusion, reach = 0.015, 0.007
    contact = SelfContact(x, rest, faces, edges, 0.001, exclusion, "cpu")
    everyone = np.ones(len(positions), bool)
    contact.search(x, v, reach, 0.0, 50.0, broad=(0.012, 0.0, 1.0))
    assert (contact.candidate_count.numpy() > 8).any()  # several layers' triangles in some lists
    assert _matches_brute_force(contact, positions, rest, faces, reach, exclusion, everyone) > 0.5 * len(positions)

    step = rng.normal(size=positions.shape)
    positions = positions + rng.uniform(0.0, 0.001, (len(positions), 1)) * step / np.linalg.norm(step, axis=1, keepdims=True)
    x.assign(positions.astype(np.float32))
    contact.search(x, v, reach, 0.0, 50.0)  # the lists kept
    _matches_brute_force(contact, positions, rest, faces, reach, exclusion, everyone)

    contact.search(x, v, reach, 0.0, 50.0, broad=(0.012, 0.0, 0.005))  # 12 mm is over the most: no lists
    assert (contact.candidate_count.numpy() == -1).all()
    _matches_brute_force(contact, positions, rest, faces, reach, exclusion, everyone)


def _side_after_sliding(folded: bool, carry: float | None = None) -> tuple[float, float]:
    """A particle 2 mm above triangle T1 = (a, b, d) (normal +z), then moved across the shared edge
    ad to 1 mm *below* its neighbour T2 = (a, d, c): with T2 in T1's plane (the layer flat), or,
    with ``folded``, T2 folded back over T1 (normals 143 degrees apart) and the particle 1 mm on its
    back, outside the fold. The particle's rest is far from both (no neighbour). Returns the side
    kept for T1 at the first search and for T2 at the second."""
    a, b, d = [0.0, 0.0, 0.0], [0.01, 0.005, 0.0], [0.0, 0.01, 0.0]
    flat_c = [-0.01, 0.005, 0.0]
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    edges = np.array([[0, 1], [1, 2], [0, 2], [2, 3], [0, 3]])
    rest = np.array([a, b, d, flat_c, [10.0, 10.0, 10.0]])
    positions = np.array([a, b, d, flat_c, [0.004, 0.005, 0.002]])
    x = wp.array(positions.astype(np.float32), dtype=wp.vec3)
    v = wp.zeros(len(positions), dtype=wp.vec3)
    contact = SelfContact(x, rest, faces, edges, 0.001, 0.015, "cpu")
    if carry is not None:
        contact.side_carry = carry
    contact.search(x, v, 0.003, 0.0, 50.0)
    first = (int(contact.face.numpy()[4]), float(contact.side.numpy()[4]))
    if folded:  # c over T1, 6 mm up: T2's normal (0.6, 0, -0.8); the particle 1 mm above T2's back
        positions[3] = [0.008, 0.005, 0.006]
        positions[4] = np.array([0.004, 0.005, 0.003]) + 0.001 * np.array([-0.6, 0.0, 0.8])
    else:
        positions[4] = [-0.004, 0.005, -0.001]
    x.assign(positions.astype(np.float32))
    contact.search(x, v, 0.003, 0.0, 50.0)
    second = (int(contact.face.numpy()[4]), float(contact.side.numpy()[4]))
    assert first[0] == 0 and second[0] == 1  # T1, then its neighbour T2
    return first[1], second[1]


def test_side_carries_to_a_neighbouring_triangle_of_a_smooth_layer():
    """A particle that slides from a triangle to its neighbour keeps the side it had (the layer's
    triangles are consistently oriented): one found 1 mm through the flat layer's next triangle is
    still held on the side it came from (+1, so the projection pulls it back), where a side taken
    afresh from where it is would lock the crossing in (-1, as with the carry off). Where the layer
    is folded between the two triangles (normals more than 60 degrees apart) the side is taken
    afresh: a particle on the fold's back is on T2's back (-1), though it was above T1 (+1)."""
    assert _side_after_sliding(folded=False) == (1.0, 1.0)
    assert _side_after_sliding(folded=False, carry=0.0) == (1.0, -1.0)
    assert _side_after_sliding(folded=True) == (1.0, -1.0)


def test_edge_faces_gives_each_edge_the_triangles_on_its_two_sides():
    """The triangles on the two sides of each edge, in either order of its ends: the known side of an
    outfit's edge is read from the first, the untangling's contour from both; -1 where there is none
    (a boundary edge's second, a pair that is no triangle's edge)."""
    from sim.engine.self_contact import edge_faces

    faces = np.array([[0, 1, 2], [2, 1, 3]])
    edges = np.array([[1, 0], [1, 2], [3, 2], [0, 3]])
    found = edge_faces(edges, faces)
    assert found.shape == (4, 2)
    assert found[0].tolist() == [0, -1] and sorted(found[1].tolist()) == [0, 1] and found[2].tolist() == [1, -1]
    assert found[3].tolist() == [-1, -1]
    for edge, sides in zip(edges[:3], found[:3]):
        for face in sides[sides >= 0]:
            assert set(edge) <= set(faces[face])


def _apart_on_rest(lower: tuple[np.ndarray, np.ndarray], upper: tuple[np.ndarray, np.ndarray]):
    """Two sheets (vertices, faces) as one garment whose rest shape holds them 1 m apart, so neither is
    the other's neighbour: positions [V,3] (the lower sheet's first), rest, faces."""
    (low, low_faces), (high, high_faces) = lower, upper
    positions = np.concatenate([low, high])
    rest = np.concatenate([low, high + [0.0, 0.0, 1.0]])
    return positions, rest, np.concatenate([low_faces, high_faces + len(low)])


def _bump_through_sheet() -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """A flat 20 cm sheet at z = 0 and, under it, a sheet 4 mm down with a 16 mm bump at the middle
    whose top pokes 12 mm through the first (a closed cut). Returns vertices [V,3] (the flat sheet's
    first), faces, rest positions (the sheets 1 m apart: never neighbours) and the flat sheet's count."""
    top = grid_sheet(21, 0.01, (0.0, 0.0), lambda x, y: np.zeros_like(x))
    bump = grid_sheet(21, 0.01, (0.0037, 0.0041),
                      lambda x, y: -0.004 + 0.016 * np.exp(-((x - 0.1) ** 2 + (y - 0.1) ** 2) / (2 * 0.02 ** 2)))
    vertices, rest, faces = _apart_on_rest(top, bump)
    return vertices, faces, rest, len(top[0])


def test_untangling_pulls_a_bump_back_through_the_sheet_it_pokes_through():
    """A sheet with a 12 mm bump lies 4 mm under another sheet, the bump through it (a closed cut, as
    where a fold has been pushed through the layer over it and the contacts hold it there). Edges
    found crossing every 10 steps and moved 0.5 mm a step the way that shortens the cut: the cut is
    gone, the whole bump ends under the sheet it went through, and the sheets away from the cut
    (over 6 cm from the bump's axis) have not moved."""
    centre = np.array([0.1, 0.1])
    vertices, faces, rest, flat = _bump_through_sheet()
    x = wp.array(vertices.astype(np.float32), dtype=wp.vec3, device="cpu")
    contact = SelfContact(x, rest, faces, unique_edges(faces), 0.0, 0.015, "cpu")
    inverse_mass = wp.array(np.ones(len(vertices), np.float32), dtype=float, device="cpu")
    assert contact.crossing_edges().sum() > 20
    for step in range(600):
        if step % 10 == 0:
            contact.find_crossings()
        contact.untangle(x, inverse_mass, 0.0005)
    assert contact.crossing_edges().sum() == 0
    after = x.numpy()
    top_surface = LinearNDInterpolator(after[:flat, :2], after[:flat, 2])
    height_over_top = after[flat:, 2] - top_surface(after[flat:, :2])
    assert np.nanmax(height_over_top) < 0.0
    far = np.linalg.norm(vertices[:, :2] - centre, axis=1) > 0.06
    assert np.abs(after[far] - vertices[far]).max() < 1e-6


def test_the_screened_crossing_search_finds_what_the_full_one_finds():
    """The untangling's search skips an edge shorter than twice the candidate lists' reach whose
    two ends have empty lists (nothing within that reach to pass through): on the bump poked through
    a sheet it finds exactly the full search's crossing edges, with lists made at a 6 mm reach."""
    vertices, faces, rest, flat = _bump_through_sheet()
    x = wp.array(vertices.astype(np.float32), dtype=wp.vec3, device="cpu")
    contact = SelfContact(x, rest, faces, unique_edges(faces), 0.001, 0.015, "cpu")
    still = wp.zeros(len(vertices), dtype=wp.vec3, device="cpu")
    contact.search(x, still, 0.003, 0.0, 50.0, broad=(0.006, 0.0, 1.0))
    lists = contact.candidate_count.numpy()
    assert 0 < (lists == 0).sum() < len(lists)
    contact.find_crossings(screen=0.006)
    screened = contact.crossed.numpy().copy()
    contact.find_crossings()
    assert (screened >= 0).sum() > 20 and np.array_equal(screened, contact.crossed.numpy())


def test_the_device_side_speed_statistics_match_the_hosts():
    """The search's per-world mean velocity and median relative speed, as a CUDA substep computes
    them (atomics and a log-spaced histogram, run here on the CPU backend) against the host's exact
    ones: the mean equal, the median rounded up by under one bin (5 %), a non-finite particle and the
    speed cap respected in both."""
    vertices, faces, _ = folded_sheet()
    world = (np.arange(len(vertices)) >= len(vertices) // 3).astype(np.int64)
    rng = np.random.default_rng(3)
    velocities = rng.normal(0.0, 0.4, (len(vertices), 3)) + np.where(world[:, None] == 1, [1.2, 0.0, 0.0], 0.0)
    velocities[5] = np.nan
    velocities[np.flatnonzero(world == 1)[:3]] *= 200.0  # a few far over the cap
    x = wp.array(vertices.astype(np.float32), dtype=wp.vec3)
    v = wp.array(velocities.astype(np.float32), dtype=wp.vec3)
    contact = SelfContact(x, vertices, faces, unique_edges(faces), 0.002, 0.02, "cpu", world=world)
    for cap in (50.0, 0.3):
        contact.host_statistics = True
        contact.speeds(v, cap)
        host = contact.mean_velocity.numpy().copy(), contact.other_speed.numpy().copy()
        contact.host_statistics = False
        contact.speeds(v, cap)
        device = contact.mean_velocity.numpy(), contact.other_speed.numpy()
        assert np.allclose(device[0], host[0], atol=1e-5)
        assert np.allclose(host[0], [velocities[(world == w) & np.isfinite(velocities).all(1)].mean(0) for w in (0, 1)],
                           atol=1e-4)
        assert np.all(device[1] >= host[1] * (1 - 1e-6)) and np.all(device[1] <= np.minimum(host[1] * 1.06, cap))
        assert np.all(host[1] <= cap)
