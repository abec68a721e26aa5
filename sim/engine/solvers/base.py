"""What every cloth solver shares: the model on the device, external forces, self-contact, and the
contact stage run with the body collider.

A solver is built once from the static ``ClothModel`` and the settings; ``step(state_in, state_out,
collider, dt, time, substep)`` advances the cloth by one substep of ``dt`` seconds ending at ``time``
(``substep``: its index in the frame), reading ``state_in`` and writing ``state_out`` (which holds a
copy of ``state_in`` when called). World frame, Z up, SI units.
"""
from __future__ import annotations

import numpy as np

from darts.geometry.warp_runtime import warp
from sim.engine import kernels
from sim.engine.collider import BodyCollider
from sim.engine.launch import Launcher
from sim.engine.model import ClothModel
from sim.engine.self_contact import SelfContact
from sim.engine.settings import SimSettings
from sim.engine.state import ClothState, float_array, int_array
from sim.engine.wind import Wind

wp = warp()

#: Self-contact keeps two layers this many material thicknesses apart (centre to centre).
SELF_SEPARATION = 1.0
#: Triangles with a corner closer than this many median rest edge lengths to a particle on the rest
#: garment (and at least the self-contact search reach: the rest shape is never in contact with
#: itself) are its neighbours, never its contacts.
SELF_EXCLUSION = 1.5


#: metres between the layers of an outfit in ``exclusion_rest``: farther than any exclusion radius
LAYERS_APART = 10.0


def exclusion_rest(model: ClothModel) -> np.ndarray:
    """The rest positions self-contact tells a particle's neighbours by: each layer (garment) of an
    outfit moved ``LAYERS_APART`` from the last along X, so that two garments lying on each other at
    rest are never neighbours and always collide."""
    return model.rest + model.layer[:, None] * np.array([LAYERS_APART, 0.0, 0.0])


def hinge_stiffness(model: ClothModel) -> np.ndarray:
    """Per-hinge bending stiffness kappa = k_b 3 |e|^2 / (A_1 + A_2) (N m), from the rest shape."""
    rest = model.rest
    i, j, k, l = (rest[model.hinges[:, c]] for c in range(4))
    area1 = 0.5 * np.linalg.norm(np.cross(j - i, k - i), axis=1)
    area2 = 0.5 * np.linalg.norm(np.cross(l - i, j - i), axis=1)
    edge2 = np.sum((j - i) ** 2, axis=1)
    return model.hinge_bend * 3.0 * edge2 / np.maximum(area1 + area2, 1e-12)


def hinge_rest_cos_sin(model: ClothModel) -> tuple[np.ndarray, np.ndarray]:
    """Cosine and sine of each hinge's rest angle [H] (``kernels.dihedral_gradient`` takes them)."""
    return np.cos(model.hinge_rest_angle), np.sin(model.hinge_rest_angle)


class Solver:
    """Base of the registered solvers (``name``: the registry key; ``default_substeps``: per frame at
    30 fps; ``iterations_help``: what ``SimSettings.iterations`` means to it, or None)."""

    name = ""
    default_substeps = 10
    iterations_help: str | None = None

    def __init__(self, model: ClothModel, state: ClothState, settings: SimSettings):
        self.model, self.settings = model, settings
        self.device = device = settings.device
        self.launch = Launcher(device, settings.replay_launches)
        self.count = len(model.rest)
        self.mass = float_array(model.mass, device)
        self.inverse_mass = float_array(1.0 / model.mass, device)
        self.faces = int_array(model.faces, device)
        self.force = wp.zeros_like(state.x)
        self.fastest = wp.zeros(model.worlds, dtype=float, device=device)  # each world's largest substep speed this frame (m/s)
        self.wind = Wind(settings.wind, settings.gust, settings.seed)
        thickness = float(model.material["thickness"])
        self.self_contact = SelfContact(
            state.x, exclusion_rest(model), model.faces, model.edges, SELF_SEPARATION * thickness,
            max(SELF_EXCLUSION * float(np.median(model.edge_rest)), SELF_SEPARATION * thickness + settings.self_contact_reach),
            device, model.layer, settings.replay_launches, model.world)
        self.self_contact.friction_coefficient = float(model.material["friction"])
        self.world = self.self_contact.world  # each particle's world (job), one device array for both
        self.damping = float(np.exp(-settings.damping / (settings.fps * settings.substeps)))  # per substep

    def step(self, state_in: ClothState, state_out: ClothState, collider: BodyCollider, dt: float, time: float,
             substep: int) -> None:
        raise NotImplementedError

    # -- pieces the solvers call ---------------------------------------------------------------
    def external_forces(self, state: ClothState, time: float) -> None:
        """force <- wind and air drag on every face (zero when the air density is 0)."""
        self.force.zero_()
        if self.settings.air_density > 0:
            self.launch(kernels.aerodynamic_forces, len(self.model.faces),
                        [self.faces, state.x, state.v, wp.vec3(*self.wind.at(time)), self.settings.air_density,
                         self.settings.drag_coefficient, self.force])

    def find_contacts(self, state_in: ClothState, state_out: ClothState, collider: BodyCollider, dt: float,
                      substep: int) -> None:
        """The body's contacts for this substep (``BodyCollider.update``) and, every
        ``self_contact_interval`` substeps, the garment's self-contacts; with each broad phase, the
        edges that pass through the garment (``SelfContact.find_crossings``, for ``untangle``)."""
        collider.update(state_out.x, state_in.x, substep, dt)
        settings = self.settings
        interval, every = settings.self_contact_interval, settings.self_contact_broad_interval
        if settings.self_contact and substep % interval == 0:
            reach = self.self_contact.separation + settings.self_contact_reach
            broad = None
            if substep % every < interval:
                # The broad phase: what can come within reach before the next broad phase's first
                # search is over, velocities as they are now plus a layer falling freely onto one
                # that is held (1/2 |g| T^2); particles faster than that allows search the BVH.
                lookahead = (every + interval) * dt
                fall = 0.5 * float(np.linalg.norm(settings.gravity)) * lookahead ** 2
                broad = (reach + fall, lookahead, reach + fall + settings.self_contact_list_reach)
            self.self_contact.search(state_in.x, state_in.v, reach, interval * dt, settings.max_speed, broad)
            if broad is not None and settings.untangle_step > 0.0:
                self.self_contact.find_crossings(screen=broad[0])

    def resolve_contacts(self, state: ClothState, collider: BodyCollider) -> None:
        """Push particles out of the body and above the ground, then keep them off the garment's own
        triangles (one sweep each), the layers the body has pushed this substep staying put. The
        garment's own contacts have the last word: with the body's last, each layer of a sleeve folded
        between arm and torso was pushed off its own nearest part, through the layer beside it (the
        top's walk: 294–308 crossing edges against 159–217, three and two runs 1 µm apart)."""
        collider.resolve(state.x)
        if self.settings.self_contact:
            self.self_contact.resolve(self.inverse_mass, collider.body_push)

    def finish(self, state_in: ClothState, state_out: ClothState, collider: BodyCollider, dt: float) -> None:
        """Friction for the substep's contact pushes (the garment's own layers, then the body), the
        garment's cuts through itself shrunk (``SelfContact.untangle``, edges found at each broad
        phase: twice a frame at the defaults), the solver's ``after_friction`` (the seams see the
        untangling's moves), then v = (x_out - x_in) / dt, less (``pre_stabilise``) the push out of
        the depth each particle already had inside its body contact's thickness at the substep's start
        (``kernels.velocities_less_push_out``)."""
        if self.settings.self_contact:
            self.self_contact.friction(state_in.x, self.inverse_mass, collider.body_push)
        collider.friction(state_out.x, state_in.x, dt)
        if self.settings.self_contact and self.settings.untangle_step > 0.0:
            self.self_contact.untangle(state_out.x, self.inverse_mass, self.settings.untangle_step)
        self.after_friction(state_out, dt)
        if self.settings.pre_stabilise:
            c = collider.contact
            self.launch(kernels.velocities_less_push_out, self.count,
                        [state_out.x, state_in.x, dt, c.point, c.normal, c.velocity, c.face, collider.thickness,
                         collider.offset, state_out.v])
        else:
            self.launch(kernels.velocities_from_positions, self.count, [state_out.x, state_in.x, dt, state_out.v])
        self.launch(kernels.track_fastest, self.count, [state_out.v, self.world, self.fastest])

    def after_friction(self, state: ClothState, dt: float) -> None:
        """What a solver projects once more after friction moved the contacts (nothing here)."""
