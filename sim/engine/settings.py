"""Settings of a cloth simulation (SI units; vectors in the world frame, Z up).

``SimSettings`` is the one declaration of every setting. Those a user sets carry, in their field's
metadata, a help line and (where it is not derived from the name) their ``darts-sim`` flag and
batch key; ``user_settings()`` lists them, and the ``darts-sim`` parser (``sim.cli``), a batch
spec's ``[sim]`` keys (``sim.batch.spec``) and the docs' settings table (``scripts/docs_tables.py``,
``docs/simulation.md``) are all made from it. The others are the solver's tuning, set from Python.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields

from darts import arguments
from darts.errors import DartsInputError

DEFAULT_SOLVER = "xpbd"
#: m kept between the posed body's parts where they overlap or come closer (``SimSettings.body_gap``,
#: and ``sim.body_track.build_body_track``'s default: every body track is the one darts-sim simulates against)
DEFAULT_BODY_GAP = 0.01
#: A particle's path relative to the body longer than this (m) since its last search is traced for
#: a crossing: half the thickness of the thinnest body part (a finger, about 2 cm), so a shorter path
#: cannot have reached past a part's middle and the closest body point is the right way out. It also
#: bounds ``contact_skin``: a particle that moved less than this need not be searched again.
CCD_MIN_PATH = 0.01


def _user(default, help: str, flag: str | None = None, key: str | None = None):
    """A field users set: ``flag`` defaults to ``--name`` with dashes (``--no-name`` for a switch on
    by default), ``key`` (a batch spec's ``[sim]`` key) to the field's name."""
    return field(default=default, metadata={"help": help, "flag": flag, "key": key})


@dataclass
class SimSettings:
    """How the solver steps; material-dependent values (thickness, friction) come from the DART."""

    fps: float = _user(30.0, "simulation and output frame rate, frames/s")
    # per frame; None: the solver's own default, filled in by ``sim.engine.solvers.resolved_settings``
    substeps: int | None = _user(None, "substeps per frame")
    iterations: int = _user(2, "XPBD constraint sweeps per substep")
    solver: str = _user(DEFAULT_SOLVER, "the solver (sim.engine.solvers' registry)")
    device: str = _user("cpu", "Warp device: cpu or cuda[:N]")
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)  # m/s^2
    wind: tuple[float, float, float] = _user((0.0, 0.0, 0.0), "wind in m/s (world frame, Z up)")
    gust: float = _user(0.0, "relative gust strength of the wind, 0..1")
    air_density: float = 1.2  # kg/m^3; 0 switches wind and air drag off
    drag_coefficient: float = 1.0
    damping: float = 0.1  # 1/s, velocity decay rate
    ground: bool = _user(True, "no ground plane at z = 0")
    contact_reach: float = 0.01  # m searched beyond the thickness for body contacts
    contact_interval: int = 1  # substeps between the body's closest-point searches
    contact_skin: float = 0.005  # m a particle moves (relative to its contact) before it is searched again; 0: always
    # substeps between searches of every particle, moved or not (another body part may have closed over one
    # riding its contact: the skin alone would not notice)
    contact_refresh_interval: int = 10
    # m a body contact moves a particle at most per sweep: one found deep inside (cloth left in the body's
    # own overlap as it opens) comes out over several sweeps, not at tens of m/s in one
    contact_push_limit: float = 0.01
    # m the same in a crease (two contact planes): the move onto both grows as the planes turn to face each
    # other, and such moves threw a sleeve's folds through each other where the arm presses it to the torso
    crease_push_limit: float = 0.003
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
    # m a substep moves an edge that passes through the garment and the triangle it passes through apart, the way
    # that shrinks the contour where the garment cuts itself (``SelfContact.untangle``; the edges found at each
    # self-contact broad phase); 0: a cut the contacts let through stays until it opens by itself
    untangle_step: float = 0.001
    # a push out of a depth a particle already had inside its contact's thickness at the substep's start
    # is a correction, left out of its velocity (``kernels.velocities_less_push_out``); off: v = dx / h
    pre_stabilise: bool = True
    max_body_speed: float = 5.0  # m/s the search reach allows for at least (more when the body is faster)
    max_speed: float = _user(50.0, "m/s; a faster particle stops the run as unstable")
    cg_iterations: int = 30  # conjugate-gradient iterations per mass-spring substep
    self_contact: bool = _user(True, "let the garment pass through itself (faster)")
    continuous_collision: bool = _user(
        True, "push particles inside the body out at the closest body point only, without tracing their path back "
              "to the face they entered by", flag="--no-ccd", key="ccd")
    crease_contacts: bool = _user(
        True, "keep each particle off its closest body face only, not also off a second face within a thickness of "
              "where that push puts it (creases, where the body overlaps itself)", flag="--no-crease", key="crease")
    overlap_release: bool = _user(
        True, "keep cloth off body faces buried inside another body part too (where the posed body overlaps "
              "itself: calves in thighs in a squat), pushing it from one buried face to another",
        flag="--no-overlap-release", key="overlap_release")
    body_gap: float = _user(
        DEFAULT_BODY_GAP, "m kept between body parts where the posed body overlaps itself or comes closer (thighs and belly "
               "in a squat, arms and chest): their surfaces are pressed flat against each other before simulating "
               "(sim.body_separation); 0: the body as skinned")
    tethers: bool = _user(
        True, "xpbd: without the long-range tethers (sim.engine.tethers) that hold the garment's length over many edges at "
              "once (it then stretches and waistbands slide unless many more substeps are taken)")
    waist_friction: float = _user(
        3.0, "Coulomb friction of a waistband against the body (on the waist line, tapering to the material's 3 cm "
             "below it): an elastic waistband grips the skin; 0: the material's everywhere")
    # XPBD: the surface tethers' limits times this (never under the rest chord); the graph path they are
    # measured on runs about 2 % over the surface distance, so a little under 1 lets them bind sooner
    tether_scale: float = 1.0
    # a model of several garments: each frame, every particle keeps a thickness more off the body per
    # garment under it (``sim.engine.layers``); off: the model's ``body_offset`` as it is
    layer_offsets: bool = True
    # kernel launches recorded once and replayed, the XPBD sweeps as one captured block (``sim.engine.launch``);
    # off: every launch through wp.launch from Python, as before issue 30 (the same results, slower)
    replay_launches: bool = True
    seed: int = _user(0, "seed of the wind gusts (runs are deterministic)")

    def __post_init__(self):
        """Each value checked to be of its field's kind (a number, a whole number, a str, a bool, three
        numbers) and within range (``check``): a DartsInputError naming the setting, when made."""
        for f in fields(self):
            value = getattr(self, f.name)
            kind = str(f.type)
            if kind == "int | None" and value is None:
                continue
            setattr(self, f.name, _CHECKS[kind](value, f.name))
        self.check()

    def check(self) -> None:
        """Raise DartsInputError naming the first setting out of range (the solver's name is the
        registry's to check: ``sim.engine.solvers.solver_class``)."""
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
            (self.waist_friction >= 0, f"waist friction must be >= 0, got {self.waist_friction}"),
            (0 <= self.body_gap <= 0.05, f"body gap must be in [0, 0.05] m, got {self.body_gap}"),
            (self.contact_reach > 0 and self.self_contact_reach > 0 and self.max_speed > 0,
             "contact reaches and max speed must be > 0"),
            (0 <= self.contact_skin <= CCD_MIN_PATH, f"contact skin must be in [0, {CCD_MIN_PATH}] m, got {self.contact_skin}"),
            (self.contact_push_limit > 0, f"contact push limit must be > 0 m, got {self.contact_push_limit}"),
            (self.crease_push_limit > 0, f"crease push limit must be > 0 m, got {self.crease_push_limit}"),
            (self.contact_refresh_interval >= 1,
             f"contact refresh interval must be >= 1 substep, got {self.contact_refresh_interval}"),
            (self.self_contact_broad_interval >= 1,
             f"self-contact broad-phase interval must be >= 1, got {self.self_contact_broad_interval}"),
            (0.9 <= self.tether_scale <= 1, f"tether scale must be in [0.9, 1], got {self.tether_scale}"),
            (self.self_contact_list_reach >= 0, f"self-contact list reach must be >= 0 m, got {self.self_contact_list_reach}"),
        ]
        for ok, message in rules:
            if not ok:
                raise DartsInputError(None, message)


#: How a value of each field type is checked (``darts.arguments``): numbers are finite, whole numbers ints.
_CHECKS = {
    "float": arguments.number, "int": lambda v, name: arguments.number(v, name, whole=True),
    "int | None": lambda v, name: arguments.number(v, name, whole=True), "str": arguments.text,
    "bool": arguments.switch, "tuple[float, float, float]": arguments.vector,
}


@dataclass(frozen=True)
class UserSetting:
    """A setting users set (``SimSettings``' declaration): its field ``name``, value ``kind``
    (float, int, str, bool, vector), ``default``, ``darts-sim`` ``flag``, batch ``key`` and ``help``.
    A switch (bool) on by default is turned off by its ``--no-...`` flag."""

    name: str
    kind: str
    default: object
    flag: str
    key: str
    help: str

    @property
    def default_text(self) -> str:
        if self.default is None:
            return "the solver's"
        if self.kind == "bool":
            return "on" if self.default else "off"
        if self.kind == "vector":
            return ",".join(f"{v:g}" for v in self.default)
        return f"{self.default:g}" if isinstance(self.default, float) else str(self.default)


_KINDS = {"float": "float", "int": "int", "int | None": "int", "str": "str", "bool": "bool",
          "tuple[float, float, float]": "vector"}


def user_settings() -> list[UserSetting]:
    """Every ``SimSettings`` field users set, in declaration order."""
    found = []
    for f in fields(SimSettings):
        if "help" not in f.metadata:
            continue
        kind = _KINDS[str(f.type)]
        dashed = f.name.replace("_", "-")
        flag = f.metadata["flag"] or (f"--no-{dashed}" if kind == "bool" and f.default else f"--{dashed}")
        found.append(UserSetting(f.name, kind, f.default, flag, f.metadata["key"] or f.name, f.metadata["help"]))
    return found
