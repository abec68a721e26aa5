"""The body as a collider: a triangle mesh that moves frame to frame, and each particle's contact with it.

World frame (Z up, metres, seconds). Per frame the body moves linearly from its previous vertices
to the next ones; every substep places it. Every ``contact_interval`` substeps its BVH is refit and
each particle's closest body point searched (with the continuous test and crease contacts of
``collider_kernels.find_contacts``); in between, each contact plane follows its body face
(``collider_kernels.track_contacts``). ``resolve`` pushes particles a thickness outside those planes and above
the ground; ``friction`` turns the pushes of a substep into Coulomb friction.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.engine import collider_kernels
from sim.engine.launch import Launcher
from sim.engine.settings import CCD_MIN_PATH, SimSettings
from sim.engine.state import int_array, vec3_array

wp = warp()

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


#: Body parts a waistband grips (``BodyCollider``'s ``grip``): not an arm or a hand brushing past it.
GRIP_PARTS = ("upper_torso", "lower_torso", "hips")


def gripping_faces(faces: np.ndarray, parts: np.ndarray | None) -> np.ndarray:
    """[F] float32: 1 for a body face whose three corners lie on ``GRIP_PARTS`` (``parts`` [V], indices
    into ``darts.body.segmentation.PART_NAMES``), else 0; all 1 without ``parts``."""
    from darts.body.segmentation import PART_INDEX

    faces = np.asarray(faces).reshape(-1, 3)
    if parts is None:
        return np.ones(len(faces), np.float32)
    on = np.isin(np.asarray(parts), [PART_INDEX[name] for name in GRIP_PARTS])
    return on[faces].all(1).astype(np.float32)


class BodyCollider:
    """The moving body mesh (vertices [V,3], faces [F,3]) and its contacts with ``count`` particles
    of a cloth ``thickness`` (m) thick with Coulomb ``friction``; ``offset`` [count] (m) keeps a
    particle that much further off the body (an outer layer's, over the layers under it). ``grip``
    [count]: each particle's friction where its contact face grips (a waistband's, on the torso and
    hips: ``gripping_faces`` of the body's ``parts`` [V]; every face without them; ``ClothModel.grip``);
    the material's ``friction`` elsewhere and on the ground. ``world`` [count] and ``body_world`` [V]:
    each particle's and each body vertex's world in a many-world model (``sim.worlds``; default all
    0): a particle's search reach follows its own world's body."""

    def __init__(self, body_faces: np.ndarray, body_vertices: np.ndarray, count: int, thickness: float,
                 friction: float, grip: np.ndarray, settings: SimSettings, offset: np.ndarray | None = None,
                 parts: np.ndarray | None = None, world: np.ndarray | None = None,
                 body_world: np.ndarray | None = None):
        device = self.device = settings.device
        self.launch = Launcher(device, settings.replay_launches)
        self.settings, self.count = settings, count
        self.thickness, self.friction_coefficient = float(thickness), float(friction)
        self.grip = wp.array(np.asarray(grip, np.float32), dtype=float, device=device)
        self.face_grips = wp.array(gripping_faces(body_faces, parts), dtype=float, device=device)
        offset = np.zeros(count) if offset is None else np.asarray(offset, np.float64)
        self.offset = wp.array(offset.astype(np.float32), dtype=float, device=device)  # what ``LayerCover`` writes
        self.max_offset = float(offset.max(initial=0.0))  # m, the largest of them
        self.end_host = np.ascontiguousarray(body_vertices, np.float32)  # where the body is now, on the host
        self.start = vec3_array(body_vertices, device)
        self.end = vec3_array(body_vertices, device)
        self.points = vec3_array(body_vertices, device)
        self.velocities = wp.zeros_like(self.points)
        self.mesh = wp.Mesh(points=self.points, velocities=self.velocities,
                            indices=int_array(np.asarray(body_faces).reshape(-1), device))
        self.contact = BodyContacts(count, device)
        # A second body face kept off where the first contact would put the particle within a
        # thickness of another (a crease, or where the posed body overlaps itself).
        self.second = BodyContacts(count, device)
        self.window_start = None  # positions at the start of the last search's substep
        self.window_time = 0.0  # and when that substep started (s)
        self.query_time = wp.full(count, -1.0, dtype=float, device=device)  # each particle's last query (s)
        self.query_offset = wp.zeros(count, dtype=wp.vec3, device=device)
        self.body_push = wp.zeros(count, dtype=float, device=device)
        self.ground_push = wp.zeros(count, dtype=float, device=device)
        self.body_world = np.zeros(len(body_vertices), np.int64) if body_world is None else np.asarray(body_world)
        self.worlds = int(self.body_world.max(initial=0)) + 1
        self.world = wp.array(np.zeros(count, np.int32) if world is None else np.asarray(world, np.int32), dtype=wp.int32,
                              device=device)
        self.speed = np.full(self.worlds, settings.max_body_speed)  # each world's fastest body vertex (m/s)
        self.reach = wp.zeros(self.worlds, dtype=float, device=device)  # each world's search reach (m)
        self.body_speed = wp.zeros(self.worlds, dtype=float, device=device)
        self.time = 0.0  # s since the run started, at the start of the current frame
        self.unrefreshed = 0  # substeps since every particle was last searched (the first search takes all)

    def begin_frame(self, body_next: np.ndarray) -> None:
        """The body will move from where it is now to ``body_next`` [V,3] during the next frame; the
        search reach covers what its fastest vertex (each world's own) travels between searches."""
        self.start, self.end = self.end, self.start
        body_next = np.ascontiguousarray(body_next, np.float32)
        self.end.assign(body_next)
        moved = np.linalg.norm(body_next - self.end_host, axis=1)  # from the host's copy: no read back
        self.end_host = body_next
        self.speed = np.array([max(float(moved[self.body_world == w].max()) * self.settings.fps,
                                   self.settings.max_body_speed) for w in range(self.worlds)])

    def end_frame(self) -> None:
        """Place the body at the end of the frame just stepped."""
        self.time += 1.0 / self.settings.fps
        self.place(1.0)

    def place(self, weight: float, refit: bool = True) -> None:
        """Body at ``weight`` of the way through the current frame (its BVH refit if ``refit``)."""
        self.launch(collider_kernels.body_frame, len(self.points),
                    [self.start, self.end, weight, self.settings.fps, self.points, self.velocities])
        if refit:
            self.mesh.refit()

    def update(self, x, x_start, substep: int, dt: float) -> None:
        """Place the body at the end of substep ``substep`` (of the current frame); every
        ``contact_interval`` substeps search each particle's closest body point within reach (the
        thickness, ``contact_reach`` and what the fastest body vertex travels until the next search)
        with the continuous test from ``x_start`` (positions at the substep's start) and crease
        contacts — the particles that moved by the contact skin since their last search, and every
        particle each ``contact_refresh_interval`` substeps; then put every contact plane where its
        body face is now."""
        settings = self.settings
        if self.window_start is None:
            self.window_start = wp.clone(x_start)
        self.unrefreshed += 1
        interval = settings.contact_interval
        search = substep % interval == 0
        self.place((substep + 1) / settings.substeps, refit=search)
        if search:
            self.reach.assign((self.thickness + self.max_offset + settings.contact_reach + settings.contact_skin
                               + interval * dt * self.speed).astype(np.float32))
            self.body_speed.assign(self.speed.astype(np.float32))
            started = self.time + substep * dt
            # every particle, however little it moved, at the first search once the refresh interval is over
            skin = settings.contact_skin
            if self.unrefreshed >= settings.contact_refresh_interval:
                skin, self.unrefreshed = 0.0, 0
            self.launch(collider_kernels.find_contacts, self.count,
                        [self.mesh.id, x, x_start, self.world, self.reach, self.thickness,
                         int(settings.continuous_collision), CCD_MIN_PATH, started + dt - self.window_time, started,
                         started + dt, self.window_start, skin, self.body_speed, self.query_time, self.query_offset,
                         self.contact.face, self.contact.uv, self.contact.local, int(settings.crease_contacts), self.second.face,
                         self.second.uv, self.second.local, int(settings.overlap_release)])
            self.window_time = started
        c, s = self.contact, self.second
        self.launch(collider_kernels.track_contacts, self.count,
                    [self.mesh.id, c.face, c.uv, c.local, c.point, c.normal, c.velocity, s.face, s.uv, s.local,
                     s.point, s.normal, s.velocity])

    def resolve(self, x) -> None:
        """Push particles ``thickness`` outside their contact planes (both, in a crease; at most
        ``contact_push_limit`` a sweep, ``crease_push_limit`` in a crease) and above the ground, which
        has the last word; the pushes add up for ``friction``."""
        c, s = self.contact, self.second
        settings = self.settings
        self.launch(collider_kernels.resolve_contacts, self.count,
                    [x, c.point, c.normal, c.face, s.point, s.normal, s.face, self.thickness, self.offset,
                     settings.contact_push_limit, settings.crease_push_limit, int(settings.ground), 0.0, self.body_push,
                     self.ground_push])

    def launch_key(self) -> tuple:
        """The host values ``resolve`` and ``friction`` launch with (for ``sim.engine.launch.Replay``)."""
        settings = self.settings
        return (self.thickness, settings.contact_push_limit, settings.crease_push_limit, settings.ground,
                self.friction_coefficient)

    def friction(self, x, x_start, dt: float) -> None:
        """Coulomb friction for the substep's contact pushes (then forget them)."""
        self.launch(collider_kernels.apply_friction, self.count,
                    [x, x_start, self.contact.normal, self.contact.velocity, self.contact.face, self.second.normal,
                     self.second.face, self.friction_coefficient, self.grip, self.face_grips, dt, self.body_push,
                     self.ground_push])

    def contact_depth(self, particle: int, x: np.ndarray) -> float | None:
        """How far (m) ``particle`` at ``x`` [3] is inside its contact's thickness (None: no contact)."""
        if self.contact.face.numpy()[particle] < 0:
            return None
        point, normal = self.contact.point.numpy()[particle], self.contact.normal.numpy()[particle]
        return self.thickness + float(self.offset.numpy()[particle]) - float(np.dot(x - point, normal))
