"""A cloth simulation: a static model, its state, the body as a collider, one registered solver, and
the frame loop (Newton's split: ``Model`` static, ``State`` per step, ``Solver.step(state_in,
state_out, collider, dt)``).

Everything is in the world frame (Z up, metres, seconds, kilograms). Per frame the body moves
linearly from its previous vertices to the next; the solver takes ``settings.substeps`` substeps.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.engine import kernels
from sim.engine.collider import BodyCollider
from sim.engine.layers import LayerCover
from sim.engine.model import ClothModel
from sim.engine.settings import SimSettings
from sim.engine.solvers import resolved_settings, solver_class
from sim.engine.state import ClothState

wp = warp()


@dataclass
class FrameMeasure:
    """Fractions of particles inside the body — by the sign at their closest body point, those of
    them where the posed body overlaps itself (armpits, a deep squat) so that no place outside it
    exists, and by the body's winding number (inside any part, overlaps included) with those of them
    inside two parts at once (the winding number over 1.5: the body's own overlap) — the largest
    speed (m/s), whether every value is finite, and how many garment edges pass through a garment
    triangle. The winding measures are None unless asked for (they cost about four times the rest);
    the body's and the crossings' measures are None when only the speeds were asked for.
    ``max_substep_speed``: the largest particle speed of any substep since the frame began (m/s;
    ``max_speed`` is the last substep's)."""

    penetration: float | None
    penetration_in_body_overlap: float | None
    penetration_winding: float | None
    penetration_winding_in_body_overlap: float | None
    max_speed: float
    finite: bool
    self_intersections: int | None
    max_substep_speed: float = 0.0


class Simulation:
    """Steps ``model`` (particles at ``positions`` [P,3], world frame) on a body mesh given frame by
    frame; ``body_world`` [V]: each body vertex's world where the model holds several
    (``sim.worlds``)."""

    def __init__(self, model: ClothModel, positions: np.ndarray, body_faces: np.ndarray,
                 body_vertices: np.ndarray, settings: SimSettings, body_parts: np.ndarray | None = None,
                 body_world: np.ndarray | None = None):
        settings = resolved_settings(settings)
        self.model, self.settings = model, settings
        self.device = device = settings.device
        self.count = len(model.rest)
        self.thickness = float(model.material["thickness"])
        self.state = ClothState(positions, device)  # what every substep writes
        self.previous = ClothState(positions, device)  # the state the substep started from
        self.collider = BodyCollider(body_faces, body_vertices, self.count, self.thickness,
                                     float(model.material["friction"]), model.grip(settings.waist_friction),
                                     settings, model.body_offset, body_parts, model.world, body_world)
        self.solver = solver_class(settings.solver)(model, self.state, settings)
        # an outfit's layers kept off the body by the garments under them (on the device)
        self.layer_cover = (LayerCover(model, self.state.x, device) if settings.layer_offsets and model.layer.max() > 0
                            else None)
        # The same body surface with winding-number support, refit only to measure.
        self._winding = wp.Mesh(points=self.collider.points, indices=self.collider.mesh.indices,
                                support_winding_number=True)
        self.worlds = model.worlds
        self._world = self.solver.world
        self._inside = wp.zeros((self.worlds, 4), dtype=wp.int32, device=device)
        self._max_speed = wp.zeros(self.worlds, dtype=float, device=device)
        self._finite = wp.zeros(self.worlds, dtype=wp.int32, device=device)
        self._particles = np.bincount(model.world, minlength=self.worlds)  # each world's particles

    @property
    def x(self):
        """Particle positions (Warp vec3 array, the state every substep writes)."""
        return self.state.x

    @property
    def v(self):
        """Particle velocities (Warp vec3 array)."""
        return self.state.v

    @property
    def self_contact(self):
        return self.solver.self_contact

    def step_frame(self, body_next: np.ndarray) -> None:
        """Advance one frame (1 / fps seconds) while the body moves to ``body_next`` [V,3]; a model of
        several layers first keeps each particle off the body by the garments under it now
        (``sim.engine.layers.LayerCover``, on the device; ``settings.layer_offsets``)."""
        if self.layer_cover is not None:
            self.collider.max_offset = self.layer_cover.offsets(self.collider.offset)
        self.collider.begin_frame(body_next)
        self.solver.fastest.zero_()
        substeps = self.settings.substeps
        dt = 1.0 / (self.settings.fps * substeps)
        for s in range(substeps):
            self.previous.assign(self.state)
            self.solver.step(self.previous, self.state, self.collider, dt, self.collider.time + (s + 1) * dt, s)
        self.collider.end_frame()

    def measure(self, winding: bool = False, bodies: bool = True) -> FrameMeasure:
        """What ``FrameMeasure`` holds, right now, over every particle (with the winding-number
        penetration if ``winding``; without ``bodies`` only the speeds and the finite check, which
        cost next to nothing)."""
        return self._measures(winding, bodies, each_world=False)[0]

    def measure_worlds(self, winding: bool = False, bodies: bool = True) -> list[FrameMeasure]:
        """``measure`` for each world (job) of the model, in order."""
        return self._measures(winding, bodies, each_world=True)

    def _measures(self, winding: bool, bodies: bool, each_world: bool) -> list[FrameMeasure]:
        self._inside.zero_()
        self._max_speed.zero_()
        self._finite.fill_(1)
        winding = winding and bodies
        if winding:
            self._winding.refit()
        wp.launch(kernels.frame_measures, dim=self.count,
                  inputs=[self.collider.mesh.id, self._winding.id, int(bodies), int(winding), self.state.x, self.state.v,
                          self._world, self._inside, self._max_speed, self._finite], device=self.device)
        finite, speed, fastest = self._finite.numpy(), self._max_speed.numpy(), self.solver.fastest.numpy()
        inside, particles = self._inside.numpy(), self._particles
        crossings = None
        if bodies and finite.all():
            crossings = self.solver.self_contact.crossings().astype(int)
        if not each_world:  # the model as one: counts summed, speeds the largest
            finite, speed, fastest = finite.min(keepdims=True), speed.max(keepdims=True), fastest.max(keepdims=True)
            inside, particles = inside.sum(0, keepdims=True), particles.sum(keepdims=True)
            crossings = None if crossings is None else crossings.sum(keepdims=True)
        measures = []
        for w in range(len(finite)):
            speeds = {"max_speed": float(speed[w]), "max_substep_speed": float(fastest[w])}
            if not bodies:
                measures.append(FrameMeasure(None, None, None, None, finite=bool(finite[w]), self_intersections=None,
                                             **speeds))
                continue
            share = inside[w] / particles[w]
            measures.append(FrameMeasure(float(share[0]), float(share[1]), float(share[2]) if winding else None,
                                         float(share[3]) if winding else None, finite=bool(finite[w]),
                                         self_intersections=0 if crossings is None else int(crossings[w]), **speeds))
        return measures

    def diagnose(self, world: int = 0) -> str:
        """Which particle of ``world`` and constraint a blow-up starts from: its first non-finite
        particle (else the fastest), and the most violated constraint on it (edge strain, seam
        spring, body or self contact), particles and triangles numbered within the world."""
        x, v = self.state.positions(), self.state.velocities()
        model, found = self.model, []
        in_world = model.world == world
        first = int(np.argmax(in_world))  # the world's particles and triangles are contiguous
        first_face = int(np.argmax(model.world[model.faces[:, 0]] == world))
        bad = (~np.isfinite(x).all(1) | ~np.isfinite(v).all(1)) & in_world
        speed = np.where(in_world, np.nan_to_num(np.linalg.norm(v, axis=1), nan=np.inf), -1.0)
        particle = int(np.argmax(bad)) if bad.any() else int(np.argmax(speed))
        mine = np.any(model.edges == particle, axis=1)
        if mine.any():
            e = model.edges[mine]
            strain = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1) / model.edge_rest[mine] - 1.0
            worst = int(np.nanargmax(np.abs(np.nan_to_num(strain, nan=np.inf))))
            a, b = e[worst] - first
            found.append((abs(strain[worst]), f"edge {a}-{b} strained {100 * strain[worst]:+.0f} %"))
        for s in np.flatnonzero(np.any(model.springs == particle, axis=1)):
            a, b = model.springs[s]
            gap = np.linalg.norm(x[a] - x[b]) - model.spring_rest[s]
            found.append((gap / max(self.thickness, 1e-6), f"seam '{model.seam_names[model.spring_seam[s]]}' spring "
                                                           f"{a - first}-{b - first} off its rest length by {1e3 * gap:.1f} mm"))
        depth = self.collider.contact_depth(particle, x[particle])
        if depth is not None:
            found.append((depth / self.thickness, f"body contact {1e3 * depth:.1f} mm deep"))
        touching = self.solver.self_contact.face.numpy()[particle] if self.settings.self_contact else -1
        if touching >= 0:
            found.append((0.0, f"self contact with garment triangle {touching - first_face}"))
        speed = np.linalg.norm(v[particle])
        state = "non-finite" if bad[particle] else f"at {speed:.1f} m/s"
        worst = max(found, key=lambda item: np.nan_to_num(item[0], nan=np.inf))[1] if found else "no constraint"
        return f"particle {particle - first} {state}, worst constraint on it: {worst}"

    def positions(self) -> np.ndarray:
        """Particle positions [P,3] (float64 copy)."""
        return self.state.positions()
