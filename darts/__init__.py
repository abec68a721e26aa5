"""DARTs: Deformable Animation Ready Templates for clothing humans.

The library API (``darts.api``, ``docs/api.md``): ``load_body``, ``load_motion``, ``load_garment``,
``save_garment``, ``pose``, ``template``, ``deform``, ``classify``, ``read_outfit``, ``reconstruct``,
``reconstruct_outfit``; simulation is
``sim.simulate``. Names load their modules on first use. Subpackages: ``darts.body`` (SMPL-format
body model), ``darts.motion`` (AMASS-format motions), ``darts.templates``, ``darts.dart``,
``darts.crdl``, ``darts.regress``. Frames: the body's canonical (rest) frame is Y up, front +Z, left
+X (SMPL); the world frame of posed bodies and motions is AMASS's Z up. Units are metres, seconds,
kilograms.
"""
from darts.errors import DartsInputError as DartsInputError  # re-exported (__all__ is built below)
from darts.lazy import lazy_exports as _lazy_exports

__version__ = "0.1.0"
__getattr__, __dir__, __all__ = _lazy_exports(__name__, {name: "api" for name in (
    "load_body", "load_motion", "load_garment", "save_garment", "pose", "template", "deform", "classify", "read_outfit",
    "reconstruct", "reconstruct_outfit")}, subpackages=("body", "motion", "templates", "dart", "crdl", "regress"),
    eager=("DartsInputError", "__version__"))
