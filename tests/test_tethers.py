"""Long-range tethers (sim.engine.tethers) and what they buy the default XPBD solver: a cloth hanging
over a bar stays at its length where plain XPBD stretches, and a waistband on a cone-shaped hip
holds its place; tethers never resist folding or an isometric motion of the rest shape."""
from __future__ import annotations

import numpy as np
import trimesh

from sim.engine.model import cloth_model
from sim.engine.settings import SimSettings
from sim.engine.simulation import Simulation
from sim.engine.tethers import loop_tethers, surface_tethers, tethers
from tests.helpers import sheet_dart

BAR_RADIUS = 0.03  # m
DROP = 0.3  # m of strip hanging on each side of the bar


def _strip_over_bar(width: int = 9, spacing: float = 0.01) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A strip ``width`` particles wide lying over a horizontal bar (axis Y, top at z = 1) and
    hanging DROP down both sides; vertices, faces, and for each vertex its arc length along the strip."""
    arc_top = np.pi * (BAR_RADIUS + 0.0025)
    steps = int(round((2 * DROP + arc_top) / spacing)) + 1
    s = np.linspace(-DROP - arc_top / 2, DROP + arc_top / 2, steps)
    r = BAR_RADIUS + 0.0025
    points = []
    for along in s:
        if abs(along) <= arc_top / 2:  # over the bar
            angle = along / r
            x, z = r * np.sin(angle), 1.0 - BAR_RADIUS + r * np.cos(angle)
        else:
            x = np.sign(along) * r
            z = 1.0 - BAR_RADIUS - (abs(along) - arc_top / 2)
        points += [[x, (w - (width - 1) / 2) * spacing, z] for w in range(width)]
    faces = []
    for i in range(steps - 1):
        for j in range(width - 1):
            a, b, c, d = i * width + j, i * width + j + 1, (i + 1) * width + j, (i + 1) * width + j + 1
            faces += [[a, c, d], [a, d, b]]
    return np.array(points), np.array(faces), np.repeat(s, width)


def _hang(use_tethers: bool, frames: int = 30) -> tuple[float, float]:
    """Let the strip hang for ``frames`` frames at 30 fps (defaults otherwise); the mean stretch of
    its along-strip edges in the top 5 cm of each hanging side (where the tension is largest), and
    the analytic strain there, rho g DROP / k (a hanging sheet's tension at height h is the weight
    below it, ~ k times its strain per unit width)."""
    vertices, faces, along = _strip_over_bar()
    bar = trimesh.creation.cylinder(radius=BAR_RADIUS, height=0.4, sections=48,
                                    transform=trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    bar.apply_translation((0, 0, 1.0 - BAR_RADIUS))
    model = cloth_model(sheet_dart(vertices, faces))
    settings = SimSettings(ground=False, air_density=0.0, self_contact=False, tethers=use_tethers)
    sim = Simulation(model, model.rest, np.asarray(bar.faces), np.asarray(bar.vertices), settings)
    for _ in range(frames):
        sim.step_frame(np.asarray(bar.vertices))
    x = sim.positions()
    e = model.edges
    a = along[model.particle_of_vertex.argsort()]  # particle order is vertex order here
    arc_top = np.pi * (BAR_RADIUS + 0.0025) / 2
    vertical = np.abs(np.abs(a[e[:, 0]]) - np.abs(a[e[:, 1]])) > 0.005
    top = (np.minimum(np.abs(a[e[:, 0]]), np.abs(a[e[:, 1]])) > arc_top) & (
        np.maximum(np.abs(a[e[:, 0]]), np.abs(a[e[:, 1]])) < arc_top + 0.05)
    mine = vertical & top
    strain = np.linalg.norm(x[e[mine, 0]] - x[e[mine, 1]], axis=1) / model.edge_rest[mine] - 1.0
    material = model.material
    return float(strain.mean()), material["density"] * 9.81 * DROP / material["stretch_stiffness"]


def test_a_cloth_hanging_over_a_bar_keeps_its_length_near_the_analytic_strain():
    strain, analytic = _hang(use_tethers=True)
    assert analytic < 1e-3  # cotton under its own weight: an inextensible sheet, strain ~1e-4
    assert abs(strain - analytic) < 0.005


def test_without_tethers_the_hanging_cloth_stretches():
    """Plain XPBD at the same substeps does not converge under the load (the test above can fail)."""
    strain, analytic = _hang(use_tethers=False)
    assert strain - analytic > 0.01


def _hip_and_band(use_tethers: bool, seconds: float = 1.0) -> tuple[float, float]:
    """A 20 cm skirt top fitted (a thickness off) to a cone that widens downwards like a hip
    (radius 0.14 m at the waist, 0.17 m 20 cm lower); how far (m) its waist loop slid down after
    ``seconds``, and the loop's length change (fraction). Sliding down means stretching."""
    ring, rows = 72, 21
    slope = 0.03 / 0.2  # the hip's radius grows 3 cm over 20 cm downwards

    def radius(z: float) -> float:
        return 0.14 + slope * (1.0 - z)

    theta = np.arange(ring) * 2 * np.pi / ring
    heights = 1.0 - 0.2 * np.arange(rows) / (rows - 1)
    vertices = np.array([[(radius(z) + 0.0025) * np.cos(t), (radius(z) + 0.0025) * np.sin(t), z]
                         for z in heights for t in theta])
    faces = []
    for j in range(rows - 1):
        for i in range(ring):
            a, b, c, d = j * ring + i, j * ring + (i + 1) % ring, (j + 1) * ring + i, (j + 1) * ring + (i + 1) % ring
            faces += [[a, c, d], [a, d, b]]
    hip = trimesh.creation.revolve(np.array([[0.0, 0.4], [radius(0.4), 0.4], [radius(1.1), 1.1], [0.0, 1.1]]),
                                   sections=96)
    dart = sheet_dart(vertices, np.array(faces))
    dart.lines = {"waist": np.arange(ring)}
    model = cloth_model(dart)
    settings = SimSettings(ground=False, air_density=0.0, self_contact=False, tethers=use_tethers)
    sim = Simulation(model, model.rest, np.asarray(hip.faces), np.asarray(hip.vertices), settings)
    for _ in range(int(seconds * 30)):
        sim.step_frame(np.asarray(hip.vertices))
    x = sim.positions()[model.particle_of_vertex[:ring]]
    length = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1).sum()
    rest = np.linalg.norm(np.roll(vertices[:ring], -1, axis=0) - vertices[:ring], axis=1).sum()
    return 1.0 - float(x[:, 2].mean()), length / rest - 1.0


def test_a_waistband_holds_on_a_widening_hip():
    """Hoop tension holds it: 1 cm down the hip is a 2 % longer waist; without tethers it slides
    more than twice as far (the test can fail)."""
    slid, stretch = _hip_and_band(use_tethers=True)
    assert slid < 0.015 and stretch < 0.012
    slid_without, stretch_without = _hip_and_band(use_tethers=False)
    assert slid_without > 2 * slid and stretch_without > 0.03


def test_tether_limits_never_resist_an_isometric_motion():
    """Every limit is at least the rest chord (the shape itself, and any fold, satisfies them all),
    and a loop tether's limit is the arc between its ends along the loop."""
    vertices, faces, _ = _strip_over_bar()
    model = cloth_model(sheet_dart(vertices, faces))
    pairs, limits = tethers(model)
    chord = np.linalg.norm(model.rest[pairs[:, 0]] - model.rest[pairs[:, 1]], axis=1)
    assert len(pairs) > len(model.rest) and np.all(limits >= chord - 1e-9)
    square = np.arange(8)
    model.rest[:8] = np.array([[np.cos(a), np.sin(a), 0.0] for a in square * np.pi / 4])
    loop_pairs, loop_limits = loop_tethers(model, [square])
    steps = (loop_pairs[:, 1] - loop_pairs[:, 0]) % 8
    side = 2 * np.sin(np.pi / 8)
    assert np.allclose(loop_limits, np.minimum(steps, 8 - steps) * side)
    assert surface_tethers(model)[0].shape[1] == 2


def test_tether_scale_trims_the_surface_limits_down_to_the_rest_chord():
    """``scale`` multiplies every surface tether's limit (the graph path) but never takes it under
    the rest chord; 1 keeps the path, and the solver builds its tethers with the setting."""
    vertices, faces, _ = _strip_over_bar()
    model = cloth_model(sheet_dart(vertices, faces))
    pairs, path = surface_tethers(model)
    trimmed_pairs, trimmed = surface_tethers(model, scale=0.95)
    chord = np.linalg.norm(model.rest[pairs[:, 0]] - model.rest[pairs[:, 1]], axis=1)
    assert np.array_equal(pairs, trimmed_pairs)
    assert np.allclose(trimmed, np.maximum(chord, 0.95 * path))
    # over the bar the path bends round it, so some limits stay at 0.95 x path; on the flat sides
    # the path is the chord (within the two-edge hops' 2 %), so others stop at the chord
    assert 0.05 * len(path) < np.sum(np.isclose(trimmed, 0.95 * path)) < len(path)
    assert np.sum(trimmed < path - 1e-9) > 0.5 * len(path) and np.all(trimmed >= chord - 1e-12)
    bar = trimesh.creation.box((0.1, 0.1, 0.1))
    for scale, expected in ((1.0, path), (0.95, trimmed)):
        solver = Simulation(model, model.rest, np.asarray(bar.faces), np.asarray(bar.vertices),
                            SimSettings(tether_scale=scale)).solver
        assert np.isclose(np.sort(solver.tethers.fields["limit"].numpy())[:len(path)].sum(),
                          np.sort(np.concatenate([expected, tethers(model)[1][len(path):]]))[:len(path)].sum(), rtol=1e-5)
