"""Package names that load their module on first use (PEP 562), so that importing a package costs
only what its caller touches: ``darts body info`` never pays for torch."""
from __future__ import annotations

import sys
from importlib import import_module


def lazy_exports(package: str, exports: dict[str, str], subpackages: tuple[str, ...] = (), eager: tuple[str, ...] = ()):
    """(``__getattr__``, ``__dir__``, ``__all__``) for ``package``: ``__getattr__`` imports
    ``package.exports[name]`` when ``name`` is first asked for, and a subpackage of ``subpackages``
    when it is; ``__dir__`` lists the public surface (``__all__``, which is ``exports`` and the
    package's own ``eager`` names, and the subpackages) so that ``dir()`` and tab completion show
    it without loading anything."""
    public = sorted({*exports, *eager})

    def __getattr__(name: str):
        if name in exports:
            return getattr(import_module(f"{package}.{exports[name]}"), name)
        if name in subpackages:
            return import_module(f"{package}.{name}")
        raise AttributeError(f"module '{package}' has no attribute '{name}'")

    __getattr__.exports = dict(exports)  # name -> module, for tools that follow the lazy names

    def __dir__() -> list[str]:
        dunders = (name for name in vars(sys.modules[package]) if name.startswith("__"))
        return sorted({*public, *subpackages, *dunders})

    return __getattr__, __dir__, public
