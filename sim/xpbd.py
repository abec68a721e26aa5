"""XPBD with small steps (Macklin et al. 2016, 2019): many substeps, few constraint sweeps each.

Per substep: v += dt (g + f/m); predict x; place the body; then ``iterations`` Gauss-Seidel sweeps
over edge stretch, then seam springs, then contacts, after one bending sweep; v = dx / dt.
Compliance is 1 / stiffness: edges use the material's stretch stiffness (N/m), seam springs their
seam's stiffness, hinges kappa from ``hinge_stiffness``.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim import kernels
from sim.solver import ClothSolver, ColoredConstraints, hinge_stiffness

wp = warp()


def _compliance(stiffness: np.ndarray) -> np.ndarray:
    return 1.0 / np.asarray(stiffness, np.float64)


class XpbdIntegrator:
    """The default integrator of ``ClothSolver``."""

    def __init__(self, solver: ClothSolver):
        model, device = solver.model, solver.device
        self.solver = solver
        sprung = model.spring_stiffness > 0
        self.stretch = ColoredConstraints(model.edges, {
            "rest": model.edge_rest,
            "compliance": _compliance(np.full(len(model.edges), model.material["stretch_stiffness"])),
            "anchors": np.full((len(model.edges), 2), -1),
        }, solver.count, device)
        self.seams = ColoredConstraints(model.springs[sprung], {
            "rest": model.spring_rest[sprung], "compliance": _compliance(model.spring_stiffness[sprung]),
            "anchors": model.spring_anchors[sprung],
        }, solver.count, device)
        kappa = hinge_stiffness(model)
        keep = kappa > 0
        self.bending = ColoredConstraints(model.hinges[keep], {
            "rest_angle": model.hinge_rest_angle[keep], "compliance": _compliance(kappa[keep]),
        }, solver.count, device)
        self.damping = float(np.exp(-solver.settings.damping / (solver.settings.fps * solver.settings.substeps)))

    def substep(self, dt: float, time: float, index: int) -> None:
        s = self.solver
        s.external_forces(time)
        wp.launch(kernels.predict, dim=s.count,
                  inputs=[s.x, s.v, s.x_start, s.force, s.inverse_mass, wp.vec3(*s.settings.gravity), dt, self.damping],
                  device=s.device)
        s.update_contacts(index, dt)
        for group in (self.stretch, self.seams, self.bending):
            group.multiplier.zero_()
        b = self.bending.fields
        self.bending.launch(kernels.solve_bending, [b["rest_angle"], b["compliance"]],
                            [s.inverse_mass, dt, self.bending.multiplier, s.x])
        for _ in range(s.settings.iterations):
            for group in (self.stretch, self.seams):  # seams last: Gauss-Seidel favours the last sweep
                d = group.fields
                group.launch(kernels.solve_distances, [d["rest"], d["compliance"], d["anchors"]],
                             [s.inverse_mass, dt, group.multiplier, s.x])
            s.resolve_contacts()
        s.apply_friction(dt)
        wp.launch(kernels.velocities_from_positions, dim=s.count, inputs=[s.x, s.x_start, dt, s.v], device=s.device)
