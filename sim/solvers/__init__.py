"""The registry of cloth solvers: every module of this package that defines a ``Solver`` subclass
with a ``name`` is one, found at first use, so that a new solver is a new file here and nothing
else changes (``darts-sim --solver NAME``, ``SimSettings.solver``)."""
from __future__ import annotations

import importlib
import pkgutil

_REGISTRY: dict[str, type] = {}


def _discover() -> dict[str, type]:
    if not _REGISTRY:
        from sim.solvers.base import Solver

        for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
            if info.name != "base":
                importlib.import_module(f"{__name__}.{info.name}")
        for cls in Solver.__subclasses__():
            if getattr(cls, "name", None):
                _REGISTRY[cls.name] = cls
    return _REGISTRY


def solver_names() -> tuple[str, ...]:
    """Names of the registered solvers, sorted."""
    return tuple(sorted(_discover()))


def solver_class(name: str) -> type:
    """The solver registered as ``name`` (KeyError naming the known ones if none is)."""
    solvers = _discover()
    if name not in solvers:
        raise KeyError(f"unknown solver '{name}' (one of {', '.join(sorted(solvers))})")
    return solvers[name]
