"""Settings of a cloth simulation (SI units; vectors in the world frame, Z up)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEFAULT_SOLVER = "xpbd"
#: A particle's path relative to the body longer than this (m) since its last search is traced for
#: a crossing: half the thickness of the thinnest body part (a finger, about 2 cm), so a shorter path
#: cannot have reached past a part's middle and the closest body point is the right way out. It also
#: bounds ``contact_skin``: a particle that moved less than this need not be searched again.
CCD_MIN_PATH = 0.01


@dataclass
class SimSettings:
    """How the solver steps; material-dependent values (thickness, friction) come from the DART."""

    fps: float = 30.0
    # per frame; None: the solver's own default (``Solver.default_substeps``), filled in by ``Simulation``
    substeps: int | None = None
    iterations: int = 2  # XPBD constraint sweeps per substep
    solver: str = DEFAULT_SOLVER
    device: str = "cpu"
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)  # m/s^2
    wind: tuple[float, float, float] = (0.0, 0.0, 0.0)  # m/s
    gust: float = 0.0  # relative amplitude of the wind's gusts, 0..1
    air_density: float = 1.2  # kg/m^3; 0 switches wind and air drag off
    drag_coefficient: float = 1.0
    damping: float = 0.1  # 1/s, velocity decay rate
    ground: bool = True  # the plane z = 0
    contact_reach: float = 0.01  # m searched beyond the thickness for body contacts
    contact_interval: int = 1  # substeps between the body's closest-point searches
    contact_skin: float = 0.005  # m a particle moves (relative to its contact) before it is searched again; 0: always
    bending_interval: int = 1  # XPBD: substeps between bending sweeps
    self_contact_interval: int = 4  # substeps between the garment's self-contact searches (narrow phase)
    # substeps between the self-contact broad phases (candidate triangles for the searches until the next)
    self_contact_broad_interval: int = 10
    # m the most that what a particle and the layers around it travel until the next broad phase may add
    # to its list's reach; a faster particle searches the BVH at every search instead
    self_contact_list_reach: float = 0.01
    # m searched beyond the separation for the garment's self-contacts, plus what each particle and the
    # garment's fast particles travel until the next search (``SelfContact.search``)
    self_contact_reach: float = 0.002
    max_body_speed: float = 5.0  # m/s the search reach allows for at least (more when the body is faster)
    max_speed: float = 50.0  # m/s; faster means the run has blown up
    cg_iterations: int = 30  # conjugate-gradient iterations per mass-spring substep
    self_contact: bool = True  # the garment collides with itself
    continuous_collision: bool = True  # a particle whose path entered the body goes back out that face
    crease_contacts: bool = True  # a particle kept off a second body face within a thickness of its push
    tethers: bool = True  # XPBD: long-range tethers (sim.tethers) hold stretch over many edges at once
    # XPBD: the surface tethers' limits times this (never under the rest chord); the graph path they are
    # measured on runs about 2 % over the surface distance, so a little under 1 lets them bind sooner
    tether_scale: float = 1.0
    # kernel launches recorded once and replayed, the XPBD sweeps as one captured block (``sim.launch``);
    # off: every launch through wp.launch from Python, as before issue 30 (the same results, slower)
    replay_launches: bool = True
    seed: int = 0

    def check(self) -> None:
        """Raise ValueError naming the first setting out of range (the solver's name is the
        registry's to check: ``sim.solvers.solver_class``)."""
        finite = all(np.isfinite(v) for v in (self.fps, self.gust, self.air_density, self.drag_coefficient,
                                               self.damping, self.contact_reach, self.self_contact_reach,
                                               self.self_contact_list_reach, self.contact_skin, self.tether_scale,
                                               self.max_body_speed, self.max_speed, *self.gravity, *self.wind))
        if not finite:
            raise ValueError("settings must be finite numbers")
        rules = [
            (self.fps > 0, f"fps must be > 0, got {self.fps}"),
            (self.substeps is None or self.substeps >= 1, f"substeps must be >= 1, got {self.substeps}"),
            (self.iterations >= 1, f"iterations must be >= 1, got {self.iterations}"),
            (self.contact_interval >= 1, f"contact interval must be >= 1, got {self.contact_interval}"),
            (self.self_contact_interval >= 1, f"self-contact interval must be >= 1, got {self.self_contact_interval}"),
            (self.bending_interval >= 1, f"bending interval must be >= 1, got {self.bending_interval}"),
            (self.cg_iterations >= 1, f"cg iterations must be >= 1, got {self.cg_iterations}"),
            (0 <= self.gust <= 1, f"gust must be in [0, 1], got {self.gust}"),
            (self.air_density >= 0 and self.drag_coefficient >= 0, "air density and drag must be >= 0"),
            (self.damping >= 0, f"damping must be >= 0, got {self.damping}"),
            (self.contact_reach > 0 and self.self_contact_reach > 0 and self.max_speed > 0,
             "contact reaches and max speed must be > 0"),
            (0 <= self.contact_skin <= CCD_MIN_PATH, f"contact skin must be in [0, {CCD_MIN_PATH}] m, got {self.contact_skin}"),
            (self.self_contact_broad_interval >= 1,
             f"self-contact broad-phase interval must be >= 1, got {self.self_contact_broad_interval}"),
            (0.9 <= self.tether_scale <= 1, f"tether scale must be in [0.9, 1], got {self.tether_scale}"),
            (self.self_contact_list_reach >= 0, f"self-contact list reach must be >= 0 m, got {self.self_contact_list_reach}"),
        ]
        for ok, message in rules:
            if not ok:
                raise ValueError(message)
