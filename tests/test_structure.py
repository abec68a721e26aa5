"""The code's shape: data flows one way (``darts`` never imports ``sim`` or ``exporters``; the
``scenes`` data package imports nothing of ours), no import circle among our modules, and the
commands load only what they need (no torch or Warp to print help or describe the body)."""
from __future__ import annotations

import ast
import subprocess
import sys
from importlib import import_module
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
PACKAGES = ("darts", "sim", "exporters", "scenes")


def _modules() -> dict[str, Path]:
    found = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


def _imports(path: Path, module: str, top_level_only: bool) -> set[str]:
    """The modules ``path`` imports (of every package); ``top_level_only``: those run at import time
    (the module's own body, not functions, not ``if TYPE_CHECKING``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    nodes = tree.body if top_level_only else list(ast.walk(tree))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else []))
            names |= {f"{base}.{alias.name}" for alias in node.names} | {base}
    return names


def test_darts_never_imports_the_simulator_or_the_exporters_and_scenes_is_data():
    for module, path in _modules().items():
        roots = {name.split(".")[0] for name in _imports(path, module, top_level_only=False)}
        if module.split(".")[0] == "darts":
            assert not roots & {"sim", "exporters"}, f"{module} imports {roots & {'sim', 'exporters'}}"
        if module.split(".")[0] == "scenes":
            assert not roots & set(PACKAGES) - {"scenes"}, f"{module} imports {roots & set(PACKAGES)}"


def _resolved(name: str) -> str:
    """``name`` (an imported ``package.attribute``) as the module it comes from: a package's lazily
    exported name (``sim.SimSettings``) is its module's (``sim.engine.settings``)."""
    from importlib import import_module

    package, _, attribute = name.rpartition(".")
    if package in _modules():
        exports = getattr(getattr(import_module(package), "__getattr__", None), "exports", {})
        if attribute in exports:
            return f"{package}.{exports[attribute]}"
    return name


def test_the_simulators_engine_sits_below_its_application():
    """sim.engine (model, state, settings, collider, self-contact, solvers, launches, the frame
    loop) imports nothing of the application above it (sim.api, run, outfit, cli, batch, dataset
    ...), lazily exported names followed; the exporters never import the simulator."""
    modules = _modules()
    for module, path in modules.items():
        names = {_resolved(name) for name in _imports(path, module, top_level_only=False)}
        if module.startswith("sim.engine"):
            upward = {n for n in names if n.split(".")[0] == "sim" and n != "sim" and not n.startswith("sim.engine")}
            assert not upward, f"{module} (engine) imports the application: {sorted(upward)}"
        if module.split(".")[0] == "exporters":
            assert not {n for n in names if n.split(".")[0] == "sim"}, f"{module} imports the simulator"


def test_the_layer_check_follows_lazy_names():
    assert _resolved("sim.SimSettings") == "sim.engine.settings" and _resolved("sim.simulate") == "sim.api"
    assert _resolved("darts.load_body") == "darts.api" and _resolved("sim.engine.model") == "sim.engine.model"


def test_no_import_circle_among_our_modules():
    """Imports inside functions count too: a circle closed lazily is still a circle."""
    modules = _modules()
    graph = {m: {name for name in _imports(p, m, top_level_only=False) if name in modules and name != m}
             for m, p in modules.items()}
    state: dict[str, int] = {}

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                raise AssertionError("import circle: " + " -> ".join(path[path.index(nxt):] + [nxt]))
            if nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])


def _loaded_after(code: str) -> set[str]:
    probe = code + "\nimport sys; print(' '.join(sorted(m for m in sys.modules)))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=ROOT, check=True)
    return set(done.stdout.split())


HEAVY = {"torch", "warp", "pxr", "trimesh", "scipy", "matplotlib", "ray", "gpytoolbox"}


def test_help_and_body_info_load_no_heavy_module():
    for code in ("from darts.cli.main import build_parser; build_parser().format_help()",
                 "from sim.cli import parser; parser().format_help()",
                 "import contextlib, io\nfrom darts.cli.main import main\n"
                 "with contextlib.redirect_stdout(io.StringIO()): assert main(['body', 'info', '--betas', '1']) == 0",
                 "import darts, sim"):
        loaded = _loaded_after(code)
        assert not loaded & HEAVY, f"{code!r} loaded {sorted(loaded & HEAVY)}"


@pytest.mark.parametrize("package", ["darts", "sim", "darts.body", "darts.motion"])
def test_the_api_shows_itself(package):
    """dir() and tab completion list every public name (lazily loaded ones too), each resolves, and
    no helper of the package's own (the lazy loader, its imports) is among them."""
    from importlib import import_module

    module = import_module(package)
    public = [name for name in dir(module) if not name.startswith("_")]
    assert set(module.__all__) - {"__version__"} <= set(public)
    for name in public:
        assert getattr(module, name) is not None
    assert not {"lazy", "lazy_exports", "errors", "import_module"} & set(public)


def test_no_lazily_exported_name_is_also_a_module_of_its_package():
    """Importing a submodule sets the package's attribute of its name, which then shadows a lazily
    exported function of the same name (``darts.motion.resample`` became a module once anything had
    imported ``darts.motion.resample``)."""
    modules = _modules()
    for module, path in modules.items():
        if path.name != "__init__.py":
            continue
        package = import_module(module)
        exports = getattr(getattr(package, "__getattr__", None), "exports", {})
        assert not [name for name in exports if f"{module}.{name}" in modules], module
