"""Package names that load their module on first use (PEP 562), so that importing a package costs
only what its caller touches: ``darts body info`` never pays for torch."""
from __future__ import annotations

from importlib import import_module


def lazy_exports(package: str, exports: dict[str, str]):
    """A module ``__getattr__`` for ``package`` that imports ``package.exports[name]`` when ``name``
    is first asked for, and ``__all__``."""

    def __getattr__(name: str):
        if name not in exports:
            raise AttributeError(f"module '{package}' has no attribute '{name}'")
        return getattr(import_module(f"{package}.{exports[name]}"), name)

    return __getattr__, sorted(exports)
