"""The package's layers: each module imports only from its own layer and the layers before it
(at module level or inside a function alike: no arrow back up); the command line imports
nothing of the package but the API; no module takes part in a circle of imports; and nothing
below the io layer imports a file format, a plotting library or the terminal."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "coincli"

# parameters, presets -> model -> integrators -> labeller -> simulate, sweeps, analysis -> io
# (stores, recordings, charts, files) -> api -> cli
LAYERS = [
    ("parameters", {"values", "version", "enums", "defaults", "params", "quantities", "presets",
                    "jsonable"}),
    ("model", {"jit", "models", "statics"}),
    ("integrators", {"integrators"}),
    ("labeller", {"labeller"}),
    ("simulate", {"throw", "grid", "stats", "accuracy", "bench", "boundary", "montecarlo",
                  "analysis", "shock", "engines"}),
    ("io", {"stores", "recordings", "charts", "files"}),
    ("api", {"api", "__init__"}),
    ("cli", {"cli", "__main__"}),
]
HEAVY = {"rerun", "zarr", "xarray", "typer", "rich", "matplotlib", "distributed", "dask"}
# where work runs is the engines' concern: they may start Dask, nothing else below io may
DISTRIBUTED = {"distributed", "dask"}


def layer_of(module: str) -> int:
    """Layer index of a module given as a dotted path inside the package ('io.store')."""
    head = module.split(".")[0]
    for index, (_, names) in enumerate(LAYERS):
        if head in names:
            return index
    raise AssertionError(f"coincli.{module} is in no layer: add it to LAYERS")


def imports(path: Path, *, in_functions: bool = True) -> list[tuple[str, bool]]:
    """(imported name, is it inside the package) for every import statement of a file (with
    ``in_functions=False``: not those inside a function)."""
    rel = path.relative_to(PACKAGE).with_suffix("")
    package_parts = list(rel.parts[:-1]) if rel.name != "__init__" else list(rel.parts[:-1])
    found = []
    tree = ast.parse(path.read_text())
    skip = set()
    if not in_functions:
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                skip.update(id(inner) for inner in ast.walk(node))
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            for alias in node.names:
                inside = alias.name.startswith("coincli")
                found.append((alias.name.removeprefix("coincli.") if inside else alias.name,
                              inside))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package_parts[:len(package_parts) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
                if not node.module:  # from . import x: x is a module, or a name of the package
                    for alias in node.names:
                        sub = ".".join(filter(None, [target, alias.name]))
                        file = PACKAGE.joinpath(*sub.split("."))
                        is_module = file.with_suffix(".py").exists() or file.is_dir()
                        found.append((sub if is_module else target or "__init__", True))
                    continue
                found.append((target, True))
            else:
                module = node.module or ""
                inside = module.startswith("coincli")
                found.append((module.removeprefix("coincli").lstrip(".") if inside else module,
                              inside))
    return found


def test_each_module_imports_only_earlier_layers():
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        own = layer_of(module)
        for name, inside in imports(path):
            if inside and name and layer_of(name) > own:
                bad.append(f"coincli.{module} ({LAYERS[own][0]}) imports coincli.{name} "
                           f"({LAYERS[layer_of(name)][0]})")
    assert not bad, "\n".join(bad)


def test_kernels_and_analysis_import_no_io_plotting_or_terminal_library():
    io_layer = next(i for i, (name, _) in enumerate(LAYERS) if name == "io")
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        layer = layer_of(module)
        if layer >= io_layer:
            continue
        forbidden = HEAVY - DISTRIBUTED if module.split(".")[0] == "engines" else HEAVY
        for name, inside in imports(path):
            if not inside and name.split(".")[0] in forbidden:
                bad.append(f"coincli.{module} imports {name}")
    assert not bad, "\n".join(bad)


def test_the_layers_name_only_modules_that_exist():
    for _, names in LAYERS:
        for name in names - {"__init__"}:
            exists = (PACKAGE / f"{name}.py").is_file() or (PACKAGE / name).is_dir()
            assert exists, f"LAYERS names coincli.{name}, which does not exist"


def test_the_command_line_imports_nothing_of_the_package_but_the_api():
    """coincli.cli calls the API (coincli.api and its submodules) and nothing beneath it: no
    engine, store or recording, no parser or constant taken from below (the API re-exports
    what a front end needs: coincli.api.options, coincli.api.words, coincli.api.errors)."""
    allowed = {layer_of("api"), layer_of("cli")}
    bad = []
    for path in sorted((PACKAGE / "cli").rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        for name, inside in imports(path):
            if inside and layer_of(name or "__init__") not in allowed:
                bad.append(f"coincli.{module} imports coincli.{name}")
            if inside and name in ("", "__init__"):  # coincli itself: its names are the API's
                bad.append(f"coincli.{module} imports from coincli, not coincli.api")
    assert not bad, "\n".join(bad)


def module_of(name: str, modules: set[str]) -> str:
    """The module an imported dotted name is (or is in): 'montecarlo.tally' for
    'montecarlo.tally', 'montecarlo' (the package) for 'montecarlo', '' for coincli."""
    parts = name.split(".") if name and name != "__init__" else []
    while parts and ".".join(parts) not in modules:
        parts.pop()
    return ".".join(parts)


def import_graph() -> dict[str, set[str]]:
    """Every module of the package (a package by its own name, coincli as '') and the modules
    it imports, at module level or inside a function."""
    files = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        files[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    modules = set(files)
    return {module: {module_of(name, modules) for name, inside in imports(path) if inside}
            - {module} for module, path in files.items()}


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for after in sorted(graph.get(node, ())):
            if after not in index:
                visit(after)
                low[node] = min(low[node], low[after])
            elif after in stack:
                low[node] = min(low[node], index[after])
        if low[node] == index[node]:
            group = []
            while True:
                member = stack.pop()
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_no_module_is_in_a_circle_of_imports():
    """No module imports, however indirectly, a module that imports it back: within a layer
    too, and counting the imports made inside functions (they run, later)."""
    found = circles(import_graph())
    assert not found, "\n".join(" -> ".join(f"coincli.{m}" for m in group) for group in found)


def test_a_circle_is_found():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert circles(graph) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set()}) == []
