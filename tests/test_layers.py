"""The package's layers: each module imports only from its own layer and the layers before it,
and nothing below the io layer imports a file format, a plotting library or the terminal."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "coincli"

# parameters, presets -> models -> integrators, the labeller -> simulate, analysis -> sweeps -> io
# -> api -> cli
LAYERS = [
    ("parameters", {"version", "enums", "defaults", "params", "quantities", "presets",
                    "jsonable"}),
    ("model", {"jit", "models", "statics"}),
    ("integrators", {"integrators", "labeller"}),
    ("analysis", {"throw", "grid", "stats", "accuracy", "bench", "boundary", "montecarlo",
                  "analysis", "shock"}),
    ("sweeps", {"engines"}),
    ("io", {"stores", "recordings", "charts", "files"}),
    ("api", {"api", "__init__"}),
    ("cli", {"cli", "__main__"}),
]
HEAVY = {"rerun", "zarr", "xarray", "typer", "rich", "matplotlib", "distributed", "dask"}
# where work runs is the sweeps layer's concern: it may start Dask, nothing below it may
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
    sweeps_layer = next(i for i, (name, _) in enumerate(LAYERS) if name == "sweeps")
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        layer = layer_of(module)
        if layer >= io_layer:
            continue
        forbidden = HEAVY - DISTRIBUTED if layer == sweeps_layer else HEAVY
        for name, inside in imports(path):
            if not inside and name.split(".")[0] in forbidden:
                bad.append(f"coincli.{module} imports {name}")
    assert not bad, "\n".join(bad)
