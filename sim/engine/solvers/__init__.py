"""The registry of cloth solvers: every module of this package with a ``Solver`` subclass that sets
a ``name`` is one, so that a new solver is a new file here and nothing else changes (``darts-sim
--solver NAME``, ``SimSettings.solver``).

The registry reads each module's source (``ast``) for the class's ``name`` and ``default_substeps``
and imports the module (Warp, the kernels) only when the solver is asked for: ``darts-sim --help``
lists the solvers and their defaults without loading Warp.
"""
from __future__ import annotations

import ast
import importlib
import pkgutil
from dataclasses import dataclass, replace
from pathlib import Path

from darts.errors import DartsInputError


@dataclass(frozen=True)
class SolverEntry:
    """A registered solver: the module and class that define it, and its substeps per frame."""

    module: str
    cls: str
    default_substeps: int


_REGISTRY: dict[str, SolverEntry] = {}


def _class_constants(node: ast.ClassDef) -> dict:
    """The constants a class body assigns (``name = "xpbd"``, ``default_substeps = 20``)."""
    found = {}
    for item in node.body:
        if isinstance(item, ast.Assign) and isinstance(item.value, ast.Constant):
            for target in item.targets:
                if isinstance(target, ast.Name):
                    found[target.id] = item.value.value
    return found


def _module_classes(module: str) -> list[tuple[ast.ClassDef, dict]]:
    tree = ast.parse((Path(__path__[0]) / f"{module}.py").read_text(encoding="utf-8"))
    return [(node, _class_constants(node)) for node in tree.body if isinstance(node, ast.ClassDef)]


def _discover() -> dict[str, SolverEntry]:
    if not _REGISTRY:
        base = {node.name: constants for node, constants in _module_classes("base")}["Solver"]
        for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
            if info.name == "base":
                continue
            for node, constants in _module_classes(info.name):
                if isinstance(constants.get("name"), str) and any(getattr(b, "id", None) == "Solver" for b in node.bases):
                    substeps = constants.get("default_substeps", base["default_substeps"])
                    _REGISTRY[constants["name"]] = SolverEntry(f"{__name__}.{info.name}", node.name, substeps)
    return _REGISTRY


def solver_names() -> tuple[str, ...]:
    """Names of the registered solvers, sorted."""
    return tuple(sorted(_discover()))


def _entry(name: str) -> SolverEntry:
    solvers = _discover()
    if name not in solvers:
        raise KeyError(f"unknown solver '{name}' (one of {', '.join(sorted(solvers))})")
    return solvers[name]


def default_substeps(name: str) -> int:
    """Substeps per frame the solver ``name`` takes when the settings name none."""
    return _entry(name).default_substeps


def solver_class(name: str) -> type:
    """The solver registered as ``name`` (imported now; KeyError naming the known ones if none is)."""
    entry = _entry(name)
    return getattr(importlib.import_module(entry.module), entry.cls)


def resolved_settings(settings):
    """``settings`` checked (``SimSettings.check``; DartsInputError naming the first bad one, an unknown
    solver included), with ``substeps`` set to the solver's own default where it is None."""
    settings.check()
    if settings.solver not in solver_names():
        raise DartsInputError(None, f"unknown solver '{settings.solver}' (one of {', '.join(solver_names())})")
    if settings.substeps is None:
        settings = replace(settings, substeps=default_substeps(settings.solver))
    return settings
