"""The Warp cloth solver (XPBD / mass-spring) that simulates DARTs on posed bodies.

``sim.simulate(garment, motion, ...)`` is the library entry point (``sim.api``); names load on first
use, so ``import sim`` costs nothing until one is asked for.
"""
from darts.lazy import lazy_exports as _lazy_exports

__getattr__, __dir__, __all__ = _lazy_exports(__name__, {
    "simulate": "api", "simulate_many": "api", "run_job": "api", "SimJob": "api", "Simulated": "api",
    "SimSettings": "engine.settings"})
