"""Recorded launches (sim.engine.launch.Launcher) run a kernel exactly as wp.launch does: the arrays they
were recorded with, and scalar arguments that change between calls."""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.engine.launch import Launcher, Replay

wp = warp()


@wp.kernel
def add_scaled(source: wp.array(dtype=wp.vec3), scale: float, offset: wp.vec3, target: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    target[i] = target[i] + scale * source[i] + offset


def test_replayed_launch_takes_new_scalars_and_keeps_arrays_apart():
    launch = Launcher("cpu")
    source = wp.array(np.arange(12, dtype=np.float32).reshape(4, 3), dtype=wp.vec3)
    first, second = (wp.zeros(4, dtype=wp.vec3) for _ in range(2))
    launch(add_scaled, 4, [source, 1.0, wp.vec3(0.0, 0.0, 1.0), first])
    launch(add_scaled, 4, [source, 2.0, wp.vec3(0.0, 0.0, 1.0), first])  # replayed, scale changed
    launch(add_scaled, 4, [source, 2.0, wp.vec3(1.0, 0.0, 0.0), first])  # replayed, offset changed
    launch(add_scaled, 4, [source, 0.5, wp.vec3(0.0, 0.0, 0.0), second])  # another target: its own record
    base = np.arange(12, dtype=np.float32).reshape(4, 3)
    np.testing.assert_allclose(first.numpy(), 5.0 * base + [1.0, 0.0, 2.0])
    np.testing.assert_allclose(second.numpy(), 0.5 * base)
    launch(add_scaled, 0, [source, 1.0, wp.vec3(0.0), second])  # an empty launch does nothing
    np.testing.assert_allclose(second.numpy(), 0.5 * base)


@wp.kernel
def scale_into(source: wp.array(dtype=float), scale: float, target: wp.array(dtype=float)):
    i = wp.tid()
    target[i] = target[i] + scale * source[i]


def test_replayed_block_runs_as_its_launches_and_captures_again_for_a_new_key():
    """A block (a fill and two launches) captured on its second call and replayed on the third gives
    what running it directly does; a new key (a new scale) is run, captured and replayed anew."""
    replay = Replay("cpu")
    source = wp.array(np.arange(4, dtype=np.float32), dtype=float)
    scratch, total = wp.zeros(4, dtype=float), wp.zeros(4, dtype=float)
    launch = Launcher("cpu")

    def block(scale):
        scratch.zero_()
        launch(scale_into, 4, [source, scale, scratch])
        launch(scale_into, 4, [scratch, 1.0, total])

    for _ in range(3):
        replay.run(2.0, lambda: block(2.0))
    assert replay.captured == 1
    np.testing.assert_array_equal(total.numpy(), 3 * 2.0 * np.arange(4))
    for _ in range(3):
        replay.run(0.5, lambda: block(0.5))
    assert replay.captured == 2
    np.testing.assert_array_equal(total.numpy(), (6.0 + 1.5) * np.arange(4))


def test_captured_sweeps_step_exactly_as_direct_ones():
    """The folded sheet dropping onto itself (self-contacts, ground friction): recorded launches and
    the solver's sweeps replayed as a captured block give bit-for-bit the positions of plain
    ``wp.launch`` calls (``replay_launches`` off), also after a change of the host values they
    launch with (edge-edge contacts off, other
    friction between layers), which makes new captures."""
    from sim.engine.model import cloth_model
    from sim.engine.settings import SimSettings
    from sim.engine.simulation import Simulation
    from tests.helpers import sheet_dart
    from tests.test_self_contact import FAR_BODY, folded_sheet

    vertices, faces, _ = folded_sheet()
    model = cloth_model(sheet_dart(vertices, faces))
    body_vertices, body_faces = FAR_BODY
    replayed, direct = (Simulation(model, model.rest, body_faces, body_vertices,
                                   SimSettings(substeps=8, replay_launches=replay)) for replay in (True, False))
    for frame in range(8):
        if frame == 4:
            for run in (replayed, direct):
                run.self_contact.edge_edge = False
                run.self_contact.friction_coefficient = 0.1
        for run in (replayed, direct):
            run.step_frame(body_vertices)
    assert replayed.solver.replay.captured == 2 and direct.solver.replay.captured == 0
    assert np.abs(replayed.positions() - model.rest).max() > 0.01  # it fell
    np.testing.assert_array_equal(replayed.positions(), direct.positions())
