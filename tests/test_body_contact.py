"""Body contact: a cloth moving fast enough to pass a thin body part between two contact searches
stays on the side it came from (continuous collision), and tunnels through without it; a cloth
pressed into a narrow crease keeps a thickness off both of its faces (crease contacts), and one
squeezed between two parts keeps out of both."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from darts.dart.model import MATERIALS
from sim.engine.model import cloth_model
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
from tests.helpers import grid_sheet, sheet_dart

SPEED = 10.0  # m/s, downwards: 3.3 cm a substep at 30 fps x 10 substeps
PLATE = 0.02  # m, thickness of the body: a plate with its top at z = 0
THICKNESS = MATERIALS["cotton"]["thickness"]  # m, the test sheets' (``sheet_dart``'s material)


def _square_sheet(side: int, spacing: float, height: float) -> tuple[np.ndarray, np.ndarray]:
    """A horizontal square grid of side x side vertices, centred over the origin at ``height``."""
    corner = -(side - 1) / 2 * spacing
    return grid_sheet(side, spacing, (corner, corner), lambda x, y: np.full_like(x, height))


def _throw_at_plate(height: float, continuous: bool, frames: int = 6) -> tuple[np.ndarray, float]:
    """Throw a 10 cm sheet from ``height`` above the plate at SPEED; heights (m) of its particles
    after ``frames`` frames, and the material thickness."""
    plate = trimesh.creation.box(extents=(0.4, 0.4, PLATE), transform=trimesh.transformations.translation_matrix(
        (0.0, 0.0, -PLATE / 2)))
    model = cloth_model(sheet_dart(*_square_sheet(11, 0.01, height)))
    settings = SimSettings(substeps=10, iterations=4, ground=False, air_density=0.0, self_contact=False,
                           continuous_collision=continuous)
    solver = Simulation(model, model.rest, np.asarray(plate.faces), np.asarray(plate.vertices), settings)
    solver.v.assign(np.tile(np.float32([0.0, 0.0, -SPEED]), (solver.count, 1)))
    for _ in range(frames):
        solver.step_frame(np.asarray(plate.vertices))
    return solver.positions()[:, 2], solver.thickness


#: Start heights (m) at which, without continuous collision, the sheet is found past the plate's
#: middle at a search (pushed out below) or already through it (not inside at all).
HEIGHTS = (0.05, 0.07)


@pytest.mark.parametrize("height", HEIGHTS)
def test_a_fast_sheet_lands_on_a_thin_plate(height):
    z, thickness = _throw_at_plate(height, continuous=True)
    assert np.all(np.abs(z - thickness) < 0.1 * thickness)  # resting on top, a thickness up


@pytest.mark.parametrize("height", HEIGHTS)
def test_without_continuous_collision_it_tunnels(height):
    """The closest-point contact alone lets every particle through (the test above can fail)."""
    z, _ = _throw_at_plate(height, continuous=False)
    assert np.all(z < -PLATE)


#: The walls of the crease rise this steeply (rad): a 30-degree groove, its faces' outward normals
#: 150 degrees apart, as between the thigh and the belly in a deep squat.
WALL = np.radians(75.0)


def _groove() -> tuple[trimesh.Trimesh, np.ndarray]:
    """Two 4 cm slabs whose top faces meet along the Y axis in a V (and overlap 1 cm past it, as the
    posed body overlaps itself in a crease); the mesh and the two faces' outward unit normals (their
    planes pass through the origin)."""
    slabs = []
    for sign in (1, -1):
        slab = trimesh.creation.box(extents=(0.2, 0.2, 0.04))
        slab.apply_translation((-sign * 0.09, 0.0, -0.02))
        slab.apply_transform(trimesh.transformations.rotation_matrix(sign * WALL, (0, 1, 0)))
        slabs.append(slab)
    normals = np.array([[np.sin(WALL), 0.0, np.cos(WALL)], [-np.sin(WALL), 0.0, np.cos(WALL)]])
    return trimesh.util.concatenate(slabs), normals


def _press_into_groove(crease: bool, sweeps: int = 3, **settings) -> tuple[np.ndarray, np.ndarray]:
    """One substep of ``sweeps`` sweeps (three by default: a crease's push is held to
    ``crease_push_limit`` a sweep; ``settings``: more ``SimSettings``) of a small patch placed 4 mm up
    the groove, within a thickness of both faces: each particle's distance to each face's plane
    afterwards, in material thicknesses [P,2], and how far (m) each moved [P]."""
    body, normals = _groove()
    patch = np.array([[0.0003, -0.001, 0.004], [0.0003, 0.001, 0.004], [0.0008, 0.0, 0.0045]])
    model = cloth_model(sheet_dart(patch, np.array([[0, 1, 2]])))
    settings = SimSettings(substeps=1, iterations=sweeps, gravity=(0.0, 0.0, 0.0), ground=False, air_density=0.0,
                           self_contact=False, crease_contacts=crease, **settings)
    solver = Simulation(model, model.rest, np.asarray(body.faces), np.asarray(body.vertices), settings)
    assert np.all(model.rest @ normals.T < 0.99 * solver.thickness)  # the patch starts too close to both
    solver.step_frame(np.asarray(body.vertices))
    positions = solver.positions()
    return positions @ normals.T / solver.thickness, np.linalg.norm(positions - model.rest, axis=1)


def test_a_patch_in_a_crease_ends_a_thickness_off_both_faces():
    distances, _ = _press_into_groove(crease=True)
    assert np.all(np.abs(distances - 1.0) < 0.01)


def test_without_crease_contacts_it_stays_too_close_to_one_face():
    """One plane per particle pushes it off the nearer face into the other's thickness (the test
    above can fail)."""
    distances, _ = _press_into_groove(crease=False)
    assert np.all(distances.min(axis=1) < 0.5)


def test_a_crease_push_is_held_to_its_limit_a_sweep():
    """The groove's patch needs 3.3-3.7 mm along the crease; one sweep moves it the crease limit."""
    _, held = _press_into_groove(crease=True, sweeps=1, crease_push_limit=0.002)
    _, free = _press_into_groove(crease=True, sweeps=1, crease_push_limit=0.01)
    assert np.all(np.abs(held - 0.002) < 1e-5)
    assert np.all(free > 0.003)  # the push it needs, in one sweep


def _ride_rising_plate(skin: float, frames: int = 15) -> tuple[np.ndarray, float, list[int]]:
    """A sheet resting on a plate that rises at 0.3 m/s: its particles' heights above the plate's top
    after ``frames`` frames (material thicknesses), and how many particles each body search of the
    last frame queried."""
    plate = trimesh.creation.box(extents=(0.4, 0.4, PLATE), transform=trimesh.transformations.translation_matrix(
        (0.0, 0.0, -PLATE / 2)))
    model = cloth_model(sheet_dart(*_square_sheet(11, 0.01, 0.0021)))
    settings = SimSettings(substeps=10, iterations=2, ground=False, air_density=0.0, self_contact=False,
                           contact_skin=skin)
    solver = Simulation(model, model.rest, np.asarray(plate.faces), np.asarray(plate.vertices), settings)
    queried = []
    for frame in range(1, frames + 1):
        lift = np.array([0.0, 0.0, 0.3 * frame / 30.0])
        if frame == frames:  # count the queries of the last frame, substep by substep
            collider, original = solver.collider, solver.collider.update

            def counting_update(x, x_start, substep, dt, original=original, collider=collider):
                original(x, x_start, substep, dt)
                queried.append(int(np.sum(collider.query_time.numpy() == collider.window_time)))

            collider.update = counting_update
        solver.step_frame(np.asarray(plate.vertices) + lift)
    return (solver.positions()[:, 2] - 0.3 * frames / 30.0) / solver.thickness, solver.thickness, queried


def test_a_skin_skips_the_search_of_particles_riding_the_body_and_keeps_them_on_it():
    """With a 5 mm skin, a sheet carried by the body is searched only now and then, and still rides
    a thickness above it, as it does when every particle is searched every substep."""
    height, _, queried = _ride_rising_plate(skin=0.005)
    every, _, all_queried = _ride_rising_plate(skin=0.0)
    assert np.all(np.abs(height - 1.0) < 0.05) and np.all(np.abs(every - 1.0) < 0.05)
    assert all(q == 121 for q in all_queried)
    assert sum(queried) < 0.2 * sum(all_queried)


def _overlapping_slabs() -> trimesh.Trimesh:
    """A slab with its top at z = 0 and a second one overlapping it, as one posed body part folds
    into another: the first one's top is buried inside the second for x > 0.05 m, free for x < 0.05."""
    lower = trimesh.creation.box(extents=(0.4, 0.2, 0.04), transform=trimesh.transformations.translation_matrix(
        (0.0, 0.0, -0.02)))
    upper = trimesh.creation.box(extents=(0.2, 0.2, 0.06), transform=trimesh.transformations.translation_matrix(
        (0.15, 0.0, 0.0)))
    return trimesh.util.concatenate([lower, upper])


def _settle_on_slab(release: bool) -> tuple[np.ndarray, float, object]:
    """Two small patches 1 mm above the lower slab's top, one over its free part (x = -0.1) and one
    where it is buried in the upper slab (x = 0.15); one substep without gravity. The particles'
    heights (m), the thickness and the solver."""
    patch = np.array([[0.0, -0.001, 0.001], [0.0, 0.001, 0.001], [0.001, 0.0, 0.001]])
    vertices = np.concatenate([patch + (-0.1, 0.0, 0.0), patch + (0.15, 0.0, 0.0)])
    model = cloth_model(sheet_dart(vertices, np.array([[0, 1, 2], [3, 4, 5]])))
    body = _overlapping_slabs()
    settings = SimSettings(substeps=1, iterations=1, gravity=(0.0, 0.0, 0.0), ground=False, air_density=0.0,
                           self_contact=False, overlap_release=release)
    solver = Simulation(model, model.rest, np.asarray(body.faces), np.asarray(body.vertices), settings)
    assert 0.001 < 0.9 * solver.thickness  # both start within a thickness of the lower slab's top
    solver.step_frame(np.asarray(body.vertices))
    return solver.positions()[:, 2], solver.thickness, solver


def test_cloth_on_a_face_buried_in_another_part_is_not_pushed_off_it():
    z, thickness, _ = _settle_on_slab(release=True)
    assert np.allclose(z[:3], thickness, rtol=0.01)  # the free top: a thickness off it
    assert np.allclose(z[3:], 0.001, atol=1e-6)  # the buried top: left where it lay


def test_without_overlap_release_cloth_is_pushed_off_buried_faces_too():
    z, thickness, _ = _settle_on_slab(release=False)
    assert np.allclose(z, thickness, rtol=0.01)


def test_penetration_where_the_body_overlaps_itself_is_told_apart():
    """Particles just under the lower slab's top: under its free part they are plainly inside; under
    its buried part, inside the body's own overlap."""
    _, _, solver = _settle_on_slab(release=True)
    inside = np.array([[-0.1, 0.0, -0.002], [-0.1, 0.01, -0.002], [-0.1, -0.01, -0.002],
                       [0.15, 0.0, -0.002], [0.15, 0.01, -0.002], [0.16, 0.0, -0.002]])
    solver.state.x.assign(inside.astype(np.float32))
    measure = solver.measure()
    assert measure.penetration == pytest.approx(1.0)
    assert measure.penetration_in_body_overlap == pytest.approx(0.5)


def _covered_while_riding(refresh: int) -> np.ndarray:
    """A patch resting a thickness above a slab's top while a second slab comes down over it (as a
    thigh folds over a calf): each particle's contact face afterwards (-1: none)."""
    body = _overlapping_slabs()
    resting = np.asarray(body.vertices)
    raised = resting.copy()
    raised[8:, 2] += 0.1  # the second slab (the last 8 vertices) 10 cm up: clear of the patch
    patch = np.array([[0.15, -0.001, 0.0], [0.15, 0.001, 0.0], [0.151, 0.0, 0.0]])
    model = cloth_model(sheet_dart(patch, np.array([[0, 1, 2]])))
    settings = SimSettings(substeps=10, iterations=1, gravity=(0.0, 0.0, 0.0), ground=False, air_density=0.0,
                           self_contact=False, contact_refresh_interval=refresh)
    solver = Simulation(model, model.rest + (0.0, 0.0, 0.002), np.asarray(body.faces), raised, settings)
    for vertices in (raised, raised, resting, resting, resting):
        solver.step_frame(vertices)
    return solver.collider.contact.face.numpy()


def test_a_particle_riding_its_contact_is_searched_again_when_another_part_covers_it():
    """The contact skin searches a particle again only once it slides on its contact; the refresh
    searches every particle every few substeps, so a slab closing over the patch is noticed: the
    face under it is buried and let go (without the refresh the patch keeps riding it)."""
    assert np.all(_covered_while_riding(refresh=10) == -1)
    assert np.all(_covered_while_riding(refresh=10**6) >= 0)


def _deep_patch(limit: float, frames: int, pre_stabilise: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """A patch 3 cm deep inside a 10 cm slab (its top at z = 0), one substep of one sweep a frame,
    no gravity: the particles' heights and vertical velocities after ``frames`` frames."""
    slab = trimesh.creation.box(extents=(0.4, 0.4, 0.1), transform=trimesh.transformations.translation_matrix(
        (0.0, 0.0, -0.05)))
    patch = np.array([[0.0, -0.001, -0.03], [0.0, 0.001, -0.03], [0.001, 0.0, -0.03]])
    model = cloth_model(sheet_dart(patch, np.array([[0, 1, 2]])))
    settings = SimSettings(substeps=1, iterations=1, gravity=(0.0, 0.0, 0.0), ground=False, air_density=0.0,
                           self_contact=False, contact_push_limit=limit, pre_stabilise=pre_stabilise)
    solver = Simulation(model, model.rest, np.asarray(slab.faces), np.asarray(slab.vertices), settings)
    for _ in range(frames):
        solver.step_frame(np.asarray(slab.vertices))
    return solver.positions()[:, 2], solver.v.numpy()[:, 2]


def test_a_particle_deep_in_the_body_comes_out_at_the_push_limit_a_sweep():
    assert np.allclose(_deep_patch(0.01, 1)[0], -0.02, atol=1e-6)  # 1 cm of the 3.2 cm it needs
    assert np.allclose(_deep_patch(0.01, 3)[0], 0.0, atol=1e-6)  # 1 cm a sweep
    assert np.allclose(_deep_patch(0.01, 4)[0], THICKNESS, atol=1e-6)  # out, a thickness off
    assert np.allclose(_deep_patch(1.0, 1)[0], THICKNESS, atol=1e-6)  # without the limit: in one leap


def test_a_push_out_of_a_depth_the_particle_had_is_no_velocity():
    """Pre-stabilisation: the push out of a depth the particle already had at the substep's start
    corrects its place and gives it no speed (else 1 cm in a 1/30 s substep is 0.3 m/s, and the
    next substep carries it on: out after two sweeps instead of four, and flying)."""
    height, speed = _deep_patch(0.01, 1)
    assert np.allclose(speed, 0.0, atol=1e-4) and np.allclose(height, -0.02, atol=1e-6)
    height, speed = _deep_patch(0.01, 4)
    assert np.allclose(speed, 0.0, atol=1e-4)
    height, speed = _deep_patch(0.01, 1, pre_stabilise=False)
    assert np.allclose(speed, 0.01 * 30, rtol=1e-3)  # v = dx / h
    height, speed = _deep_patch(0.01, 2, pre_stabilise=False)
    assert np.all(height > -0.001) and np.all(speed > 0.25)  # carried out after the second sweep


def test_the_winding_number_tells_the_body_s_own_overlap_apart():
    """Inside both slabs (where they overlap) the winding number counts 2; inside one, 1."""
    _, _, solver = _settle_on_slab(release=True)
    inside = np.array([[-0.1, 0.0, -0.01], [-0.1, 0.01, -0.01], [0.15, 0.0, 0.01],  # in one slab
                       [0.15, 0.0, -0.01], [0.15, 0.01, -0.01], [0.16, 0.0, -0.02]])  # in both
    solver.state.x.assign(inside.astype(np.float32))
    measure = solver.measure(winding=True)
    assert measure.penetration_winding == pytest.approx(1.0)
    assert measure.penetration_winding_in_body_overlap == pytest.approx(0.5)


def _squeeze(gap: float, crease: bool) -> np.ndarray:
    """A patch 0.2 mm over a slab's top (z = 0) under a second slab whose underside faces it
    ``gap`` (m) above (two body parts pressed together, as an arm on the torso), one substep of
    three sweeps: each particle's distance to the lower and to the upper face [P,2] (m; negative:
    inside that slab)."""
    below = trimesh.creation.box(extents=(0.2, 0.2, 0.04), transform=trimesh.transformations.translation_matrix(
        (0.0, 0.0, -0.02)))
    above = trimesh.creation.box(extents=(0.2, 0.2, 0.04), transform=trimesh.transformations.translation_matrix(
        (0.0, 0.0, gap + 0.02)))
    body = trimesh.util.concatenate([below, above])
    patch = np.array([[0.0, -0.001, 0.0002], [0.0, 0.001, 0.0002], [0.001, 0.0, 0.0002]])
    model = cloth_model(sheet_dart(patch, np.array([[0, 1, 2]])))
    settings = SimSettings(substeps=1, iterations=3, gravity=(0.0, 0.0, 0.0), ground=False, air_density=0.0,
                           self_contact=False, crease_contacts=crease)
    solver = Simulation(model, model.rest, np.asarray(body.faces), np.asarray(body.vertices), settings)
    solver.step_frame(np.asarray(body.vertices))
    z = solver.positions()[:, 2]
    return np.stack([z, gap - z], axis=1)


def test_cloth_squeezed_between_two_parts_keeps_out_of_both():
    """Half a thickness t between two parts: the offset off both shrinks from t to t g / (2 t + t) =
    g / 3, so the patch ends outside both, a third of the gap off the nearer."""
    distances = _squeeze(0.5 * THICKNESS, crease=True)
    gap = distances.sum(axis=1)
    assert np.all(distances > 0)
    assert np.allclose(distances[:, 0], gap / 3, atol=2e-5)


def test_without_crease_contacts_squeezed_cloth_is_pushed_into_the_other_part():
    distances = _squeeze(0.5 * THICKNESS, crease=False)
    assert np.allclose(distances[:, 0], THICKNESS, atol=1e-5) and np.all(distances[:, 1] < 0)
