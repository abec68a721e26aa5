"""XPBD with small steps (Macklin et al. 2016, 2019): many substeps, few constraint sweeps each.

Per substep: v += dt (g + f/m); predict x; place the body; then ``iterations`` Gauss-Seidel sweeps
over the long-range tethers (``sim.engine.tethers``, unless ``settings.tethers`` is off), edge stretch,
contacts, then seam springs, after one bending sweep; friction, and the seam springs once more
(``after_friction``); v = dx / dt. The sweeps and the velocity
update, the same launches every substep, run as one captured block (``sim.engine.launch.Replay``).
Compliance is 1 / stiffness: edges use the material's stretch stiffness (N/m), seam springs their
seam's stiffness, hinges kappa from ``hinge_stiffness``.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.engine.coloring import color_order
from sim.engine.launch import Launcher, Replay
from sim.engine.solvers import xpbd_kernels
from sim.engine.solvers.base import Solver, hinge_rest_cos_sin, hinge_stiffness
from sim.engine.state import float_array, int_array, on_cpu
from sim.engine.tethers import tethers

wp = warp()


class ColoredConstraints:
    """A constraint list on the device, sorted by colour; ``launch`` projects it colour by colour."""

    def __init__(self, members: np.ndarray, fields: dict[str, np.ndarray], particle_count: int, device: str,
                 record: bool = True):
        order, self.offsets = color_order(members, particle_count)
        self.device = device
        self.sequential = on_cpu(device)  # the CPU backend runs a launch's threads in order
        self._launch = Launcher(device, record)
        self.count = len(members)
        members = np.asarray(members, np.int64)
        self.members = int_array(members.reshape(len(members), members.shape[1] if members.ndim == 2 else 1)[order], device)
        self.fields = {}
        for name, values in fields.items():
            values = np.asarray(values)[order]
            self.fields[name] = int_array(values, device) if values.dtype.kind == "i" else float_array(values, device)
        self.multiplier = wp.zeros(self.count, dtype=float, device=device)

    def launch(self, kernel, fields: list, state: list) -> None:
        """``kernel(offset, members, *fields, *state)`` over every constraint. The CPU backend runs a
        launch's threads in order, so one launch over the sorted list equals a launch per colour."""
        if self.count == 0:
            return
        spans = [(0, self.count)] if self.sequential else zip(self.offsets[:-1], self.offsets[1:])
        for start, end in spans:
            self._launch(kernel, int(end - start), [int(start), self.members, *fields, *state])


def _compliance(stiffness: np.ndarray) -> np.ndarray:
    return 1.0 / np.asarray(stiffness, np.float64)


class XpbdSolver(Solver):
    """``--solver xpbd``: the default."""

    name = "xpbd"
    default_substeps = 20
    iterations_help = "constraint sweeps per substep"

    def __init__(self, model, state, settings):
        super().__init__(model, state, settings)
        sprung = model.spring_stiffness > 0
        record = settings.replay_launches
        self.stretch = ColoredConstraints(model.edges, {
            "rest": model.edge_rest,
            "compliance": _compliance(model.edge_stiffness),
            "anchors": np.full((len(model.edges), 2), -1),
        }, self.count, self.device, record)
        self.seams = ColoredConstraints(model.springs[sprung], {
            "rest": model.spring_rest[sprung], "compliance": _compliance(model.spring_stiffness[sprung]),
            "anchors": model.spring_anchors[sprung],
        }, self.count, self.device, record)
        no_tethers = (np.zeros((0, 2), np.int64), np.zeros(0))
        pairs, limits = tethers(model, scale=settings.tether_scale) if settings.tethers else no_tethers
        self.tethers = ColoredConstraints(pairs, {"limit": limits}, self.count, self.device, record)
        self.replay = Replay(self.device, record)
        kappa = hinge_stiffness(model)
        keep = kappa > 0
        rest_cos, rest_sin = hinge_rest_cos_sin(model)
        self.bending = ColoredConstraints(model.hinges[keep], {
            "rest_cos": rest_cos[keep], "rest_sin": rest_sin[keep], "compliance": _compliance(kappa[keep]),
        }, self.count, self.device, record)

    def step(self, state_in, state_out, collider, dt, time, substep):
        self.external_forces(state_in, time)
        self.launch(xpbd_kernels.predict, self.count, [state_in.x, state_in.v, self.force, self.inverse_mass,
                                                  wp.vec3(*self.settings.gravity), dt, self.damping, state_out.x,
                                                  state_out.v])
        self.find_contacts(state_in, state_out, collider, dt, substep)
        bend = substep % self.settings.bending_interval == 0
        key = (bend, dt, id(state_in.x), id(state_out.x), id(collider), self.self_contact.launch_key(),
               collider.launch_key())
        self.replay.run(key, lambda: self.sweeps(state_in, state_out, collider, dt, bend))

    def sweeps(self, state_in, state_out, collider, dt, bend: bool) -> None:
        """The substep's constraint sweeps (with ``bend``, one bending sweep first) and ``finish``:
        launches only, the same every substep (``step`` replays them as one captured block)."""
        x = state_out.x
        for group in (self.stretch, self.seams, self.bending):
            group.multiplier.zero_()
        if bend:  # its compliance spread over the interval
            b = self.bending.fields
            self.bending.launch(xpbd_kernels.solve_bending, [b["rest_cos"], b["rest_sin"], b["compliance"]],
                                [self.inverse_mass, dt * self.settings.bending_interval, self.bending.multiplier, x])
        t, d, seam = self.tethers.fields, self.stretch.fields, self.seams.fields
        for _ in range(self.settings.iterations):
            self.tethers.launch(xpbd_kernels.solve_max_distances, [t["limit"]], [self.inverse_mass, x])
            self.stretch.launch(xpbd_kernels.solve_distances, [d["rest"], d["compliance"], d["anchors"]],
                                [self.inverse_mass, dt, self.stretch.multiplier, x])
            self.resolve_contacts(state_out, collider)
            # Seams last: Gauss-Seidel favours the last sweep, and a seam squeezed between two layers
            # or two body parts (an armpit) is otherwise pulled open by their contacts.
            self.seams.launch(xpbd_kernels.solve_distances, [seam["rest"], seam["compliance"], seam["anchors"]],
                              [self.inverse_mass, dt, self.seams.multiplier, x])
        self.finish(state_in, state_out, collider, dt)

    def after_friction(self, state, dt: float) -> None:
        """The seams once more: friction holds each contact where it was, and the two ends of a seam
        pair, touching the body with different pushes, were held differently — which opened stiff
        seams by up to 3.5 mm at the shoulders and armholes of the top's walk (under 1 mm without
        friction)."""
        seam = self.seams.fields
        self.seams.launch(xpbd_kernels.solve_distances, [seam["rest"], seam["compliance"], seam["anchors"]],
                          [self.inverse_mass, dt, self.seams.multiplier, state.x])
