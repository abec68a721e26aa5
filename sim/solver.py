"""The cloth solver: garment state, the moving body it collides with, and one frame of substeps.

Everything here is in the world frame (Z up, metres, seconds, kilograms). Per frame the body moves
linearly from its previous frame to the next. Every substep places it; every few substeps its BVH
is refit and each particle's closest body point searched (in between, each contact plane follows
its body face); the integrator (XPBD or implicit mass-spring) advances the cloth.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.geometry.warp_runtime import warp
from sim import kernels
from sim.coloring import color_order
from sim.model import ClothModel
from sim.self_contact import SelfContact
from sim.settings import SimSettings
from sim.wind import Wind

wp = warp()


def _vec3(values: np.ndarray, device: str):
    return wp.array(np.ascontiguousarray(values, np.float32), dtype=wp.vec3, device=device)


def _ints(values: np.ndarray, device: str):
    return wp.array(np.ascontiguousarray(values, np.int32), dtype=wp.int32, device=device)


def _floats(values: np.ndarray, device: str):
    return wp.array(np.ascontiguousarray(values, np.float32), dtype=float, device=device)


class ColoredConstraints:
    """A constraint list on the device, sorted by colour; ``launch`` projects it colour by colour."""

    def __init__(self, members: np.ndarray, fields: dict[str, np.ndarray], particle_count: int, device: str):
        order, self.offsets = color_order(members, particle_count)
        self.device = device
        self.count = len(members)
        members = np.asarray(members, np.int64)
        self.members = _ints(members.reshape(len(members), members.shape[1] if members.ndim == 2 else 1)[order], device)
        self.fields = {}
        for name, values in fields.items():
            values = np.asarray(values)[order]
            self.fields[name] = _ints(values, device) if values.dtype.kind == "i" else _floats(values, device)
        self.multiplier = wp.zeros(self.count, dtype=float, device=device)

    def launch(self, kernel, fields: list, state: list) -> None:
        """``kernel(offset, members, *fields, *state)`` over every constraint. The CPU backend runs a
        launch's threads in order, so one launch over the sorted list equals a launch per colour."""
        if self.count == 0:
            return
        spans = [(0, self.count)] if self.device == "cpu" else zip(self.offsets[:-1], self.offsets[1:])
        for start, end in spans:
            wp.launch(kernel, dim=int(end - start), inputs=[int(start), self.members, *fields, *state],
                      device=self.device)


class BodyContacts:
    """One body contact per particle (face -1: none): where it was found (face, barycentrics, the
    outward direction in the face's frame) and its plane now (point, normal, surface velocity)."""

    def __init__(self, count: int, device: str):
        self.face = wp.full(count, -1, dtype=wp.int32, device=device)
        self.uv = wp.zeros(count, dtype=wp.vec2, device=device)
        self.local = wp.zeros(count, dtype=wp.vec3, device=device)
        self.point = wp.zeros(count, dtype=wp.vec3, device=device)
        self.normal = wp.zeros(count, dtype=wp.vec3, device=device)
        self.velocity = wp.zeros(count, dtype=wp.vec3, device=device)


#: A particle's path relative to the body longer than this (m) since the last search is traced for
#: a crossing: half the thickness of the thinnest body part (a finger, about 2 cm), so a shorter path
#: cannot have reached past a part's middle and the closest body point is the right way out.
CCD_MIN_PATH = 0.01
#: Self-contact keeps two layers this many material thicknesses apart (centre to centre).
SELF_SEPARATION = 1.0
#: Triangles with a corner closer than this many median rest edge lengths to a particle on the rest
#: garment (and at least the self-contact search reach: the rest shape is never in contact with
#: itself) are its neighbours, never its contacts.
SELF_EXCLUSION = 1.5


@dataclass
class FrameMeasure:
    """Fractions of particles inside the body — all, and those where the posed body overlaps
    itself (armpits, a deep squat) so that no place outside it exists — the largest speed (m/s),
    whether every value is finite, and how many garment edges pass through a garment triangle."""

    penetration: float
    penetration_in_body_overlap: float
    max_speed: float
    finite: bool
    self_intersections: int


def hinge_stiffness(model: ClothModel) -> np.ndarray:
    """Per-hinge bending stiffness kappa = k_b 3 |e|^2 / (A_1 + A_2) (N m), from the rest shape."""
    rest = model.rest
    i, j, k, l = (rest[model.hinges[:, c]] for c in range(4))
    area1 = 0.5 * np.linalg.norm(np.cross(j - i, k - i), axis=1)
    area2 = 0.5 * np.linalg.norm(np.cross(l - i, j - i), axis=1)
    edge2 = np.sum((j - i) ** 2, axis=1)
    return model.material["bend_stiffness"] * 3.0 * edge2 / np.maximum(area1 + area2, 1e-12)


class ClothSolver:
    """Steps ``model`` (particles at ``positions``, world frame) on a body mesh given frame by frame."""

    def __init__(self, model: ClothModel, positions: np.ndarray, body_faces: np.ndarray,
                 body_vertices: np.ndarray, settings: SimSettings):
        settings.check()
        self.model, self.settings = model, settings
        self.device = device = settings.device
        self.count = len(model.rest)
        self.thickness = float(model.material["thickness"])
        self.friction = float(model.material["friction"])
        self.wind = Wind(settings.wind, settings.gust, settings.seed)
        self.x = _vec3(positions, device)
        self.v = wp.zeros(self.count, dtype=wp.vec3, device=device)
        self.x_start = wp.zeros_like(self.x)
        self.force = wp.zeros_like(self.x)
        self.mass = _floats(model.mass, device)
        self.inverse_mass = _floats(1.0 / model.mass, device)
        self.faces = wp.array(np.ascontiguousarray(model.faces, np.int32), dtype=wp.int32, device=device)
        self.contact = BodyContacts(self.count, device)
        # A second body face kept off where the first contact would put the particle within a
        # thickness of another (a crease, or where the posed body overlaps itself).
        self.second = BodyContacts(self.count, device)
        self.window_start = wp.clone(self.x)  # positions at the start of the last search's substep
        self.window_time = 0.0  # and when that substep started (s)
        self.body_push = wp.zeros(self.count, dtype=float, device=device)
        self.ground_push = wp.zeros(self.count, dtype=float, device=device)
        self.body_start = _vec3(body_vertices, device)
        self.body_end = _vec3(body_vertices, device)
        self.body_points = _vec3(body_vertices, device)
        self.body_velocities = wp.zeros_like(self.body_points)
        self.body_indices = _ints(np.asarray(body_faces).reshape(-1), device)
        self.body = wp.Mesh(points=self.body_points, velocities=self.body_velocities, indices=self.body_indices)
        self._inside = wp.zeros(2, dtype=wp.int32, device=device)
        self._max_speed = wp.zeros(1, dtype=float, device=device)
        self._finite = wp.zeros(1, dtype=wp.int32, device=device)
        self.self_contact = SelfContact(
            self.x, model.rest, model.faces, model.edges, SELF_SEPARATION * self.thickness,
            max(SELF_EXCLUSION * float(np.median(model.edge_rest)), SELF_SEPARATION * self.thickness + settings.contact_reach),
            device)
        self.time = 0.0
        self.body_speed = settings.max_body_speed
        if settings.solver == "xpbd":
            from sim.xpbd import XpbdIntegrator

            self.integrator = XpbdIntegrator(self)
        else:
            from sim.implicit import MassSpringIntegrator

            self.integrator = MassSpringIntegrator(self)

    # -- pieces the integrators call, in this order, every substep --------------------------------
    def external_forces(self, time: float) -> None:
        """force <- wind and air drag on every face (zero when the air density is 0)."""
        self.force.zero_()
        if self.settings.air_density > 0:
            wp.launch(kernels.aerodynamic_forces, dim=len(self.model.faces),
                      inputs=[self.faces, self.x, self.v, wp.vec3(*self.wind.at(time)), self.settings.air_density,
                              self.settings.drag_coefficient, self.force], device=self.device)

    def place_body(self, weight: float, refit: bool = True) -> None:
        """Body at ``weight`` of the way through the current frame (its BVH refit if ``refit``)."""
        wp.launch(kernels.body_frame, dim=len(self.body_points),
                  inputs=[self.body_start, self.body_end, weight, self.settings.fps, self.body_points,
                          self.body_velocities], device=self.device)
        if refit:
            self.body.refit()

    def update_contacts(self, substep: int, dt: float) -> None:
        """Place the body at the end of this substep; every ``contact_interval`` substeps search each
        particle's closest body point (reaching as far as the fastest body vertex of this frame,
        at least ``max_body_speed``, travels until the next search; a particle that moved more than
        CCD_MIN_PATH relative to the body since the last search takes the face its path entered the
        body by, if any, and one within a thickness of where its push would put it takes that face
        as a second contact); every ``self_contact_interval`` substeps search the garment's
        self-contacts; then put every contact plane where its body face is now."""
        interval = self.settings.contact_interval
        search = substep % interval == 0
        self.place_body((substep + 1) / self.settings.substeps, refit=search)
        if search:
            reach = self.thickness + self.settings.contact_reach + interval * dt * self.body_speed
            started = self.time + substep * dt
            wp.launch(kernels.find_contacts, dim=self.count,
                      inputs=[self.body.id, self.x, self.x_start, reach, self.thickness,
                              int(self.settings.continuous_collision), CCD_MIN_PATH, started + dt - self.window_time,
                              self.window_start, self.contact.face, self.contact.uv, self.contact.local,
                              int(self.settings.crease_contacts), self.second.face, self.second.uv, self.second.local],
                      device=self.device)
            self.window_time = started
        if self.settings.self_contact and substep % self.settings.self_contact_interval == 0:
            self.self_contact.search(self.x_start, self.self_contact.separation + self.settings.contact_reach)
        for c in (self.contact, self.second):
            wp.launch(kernels.track_contacts, dim=self.count,
                      inputs=[self.body.id, c.face, c.uv, c.local, c.point, c.normal, c.velocity], device=self.device)

    def resolve_contacts(self) -> None:
        """Keep particles off the garment's own triangles (layers the body has pushed this substep
        staying put), then push them out of the body and above the ground, which has the last word
        (one sweep each)."""
        if self.settings.self_contact:
            self.self_contact.resolve(self.inverse_mass, self.body_push)
        wp.launch(kernels.resolve_contacts, dim=self.count,
                  inputs=[self.x, self.contact.point, self.contact.normal, self.contact.face, self.second.point,
                          self.second.normal, self.second.face, self.thickness,
                          int(self.settings.ground), 0.0, self.body_push, self.ground_push], device=self.device)

    def apply_friction(self, dt: float) -> None:
        """Coulomb friction for the substep's contact pushes (then forget them)."""
        wp.launch(kernels.apply_friction, dim=self.count,
                  inputs=[self.x, self.x_start, self.contact.normal, self.contact.velocity, self.second.normal,
                          self.second.face, self.friction, dt,
                          self.body_push, self.ground_push], device=self.device)

    # -- the public interface ---------------------------------------------------------------------
    def step_frame(self, body_next: np.ndarray) -> None:
        """Advance one frame (1 / fps seconds) while the body moves to ``body_next`` [V,3]."""
        self.body_start, self.body_end = self.body_end, self.body_start
        self.body_end.assign(np.ascontiguousarray(body_next, np.float32))
        # The search reach covers what the fastest body vertex travels between searches this frame.
        moved = np.linalg.norm(np.asarray(body_next, np.float32) - self.body_start.numpy(), axis=1).max()
        self.body_speed = max(float(moved) * self.settings.fps, self.settings.max_body_speed)
        substeps = self.settings.substeps
        dt = 1.0 / (self.settings.fps * substeps)
        for s in range(substeps):
            self.integrator.substep(dt, self.time + (s + 1) * dt, s)
        self.time += 1.0 / self.settings.fps
        self.place_body(1.0)

    def measure(self) -> FrameMeasure:
        """What ``FrameMeasure`` holds, right now."""
        self._inside.zero_()
        self._max_speed.zero_()
        self._finite.fill_(1)
        wp.launch(kernels.frame_measures, dim=self.count,
                  inputs=[self.body.id, self.x, self.v, self._inside, self._max_speed, self._finite], device=self.device)
        inside = self._inside.numpy()
        finite = bool(self._finite.numpy()[0])
        return FrameMeasure(float(inside[0]) / self.count, float(inside[1]) / self.count,
                            float(self._max_speed.numpy()[0]), finite, int(self.self_contact.crossing_edges().sum()) if finite else 0)

    def diagnose(self) -> str:
        """Which particle and constraint a blow-up starts from: the first non-finite particle (else the
        fastest), and the most violated constraint on it (edge strain, seam spring, body or self contact)."""
        x, v = self.x.numpy().astype(np.float64), self.v.numpy().astype(np.float64)
        bad = ~np.isfinite(x).all(1) | ~np.isfinite(v).all(1)
        particle = int(np.argmax(bad)) if bad.any() else int(np.argmax(np.linalg.norm(v, axis=1)))
        model, found = self.model, []
        mine = np.any(model.edges == particle, axis=1)
        if mine.any():
            e = model.edges[mine]
            strain = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1) / model.edge_rest[mine] - 1.0
            worst = int(np.nanargmax(np.abs(np.nan_to_num(strain, nan=np.inf))))
            found.append((abs(strain[worst]), f"edge {e[worst, 0]}-{e[worst, 1]} strained {100 * strain[worst]:+.0f} %"))
        for s in np.flatnonzero(np.any(model.springs == particle, axis=1)):
            a, b = model.springs[s]
            gap = np.linalg.norm(x[a] - x[b]) - model.spring_rest[s]
            found.append((gap / max(self.thickness, 1e-6), f"seam '{model.seam_names[model.spring_seam[s]]}' spring "
                                                           f"{a}-{b} off its rest length by {1e3 * gap:.1f} mm"))
        if self.contact.face.numpy()[particle] >= 0:
            point, normal = self.contact.point.numpy()[particle], self.contact.normal.numpy()[particle]
            depth = self.thickness - float(np.dot(x[particle] - point, normal))
            found.append((depth / self.thickness, f"body contact {1e3 * depth:.1f} mm deep"))
        if self.settings.self_contact and self.self_contact.face.numpy()[particle] >= 0:
            found.append((0.0, f"self contact with garment triangle {self.self_contact.face.numpy()[particle]}"))
        speed = np.linalg.norm(v[particle])
        state = "non-finite" if bad[particle] else f"at {speed:.1f} m/s"
        worst = max(found, key=lambda item: np.nan_to_num(item[0], nan=np.inf))[1] if found else "no constraint"
        return f"particle {particle} {state}, worst constraint on it: {worst}"

    def positions(self) -> np.ndarray:
        """Particle positions [P,3] (float64 copy)."""
        return self.x.numpy().astype(np.float64)
