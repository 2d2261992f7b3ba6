#!/usr/bin/env python
"""What the next maintainer inherits, counted: modules over 600 lines, functions over 80 lines,
and every use of another library's private name (an attribute or an import whose name starts
with one underscore, of a module that is not ours).

    python benchmarks/house.py [PACKAGE_DIR] [--json]
    python benchmarks/house.py --timing [--rounds 5] [--against CHECKOUT [--against-cache DIR]]

The private names are found in the syntax tree: ``x._name`` where ``x`` is a name imported from
another library (``numba.core.caching._CacheLocator``, ``rr.components.X._Y``) or where
``_name`` is no name the package defines itself (``dispatcher._cache``); ``from lib import
_name`` / ``from lib._module import ...``; ``getattr(lib, "_name")``; a keyword ``_name=``.
Dunder names (``__version__``) and a named tuple's ``_replace``, ``_fields``... are public.

With ``--timing``, what a user waits for, medians of interleaved rounds: `coin --help`, a warm
`coin simulate --vy 1.197 --vphi 3.508 --no-rrd`, the default 512 x 512 `coin basin` (the whole
command, into a fresh store) and the same with `--rrd` (its ratio to the plain one, pair by
pair); with ``--against`` another checkout of coincli (its own kernel cache in
``--against-cache``) is timed in the same rounds, each command of one right after the other's.
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from pathlib import Path

MODULE_LINES = 600
FUNCTION_LINES = 80


# a named tuple's public methods, spelt with an underscore so as not to clash with fields
NAMEDTUPLE_API = frozenset({"_replace", "_fields", "_asdict", "_make", "_field_defaults"})


def private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__") and name not in NAMEDTUPLE_API


def foreign_names(tree: ast.AST) -> set[str]:
    """The local names bound to other libraries' modules and objects by the file's imports."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if not alias.name.startswith("coincli"):
                    names.add((alias.asname or alias.name).split(".")[0])
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module and \
                not node.module.startswith("coincli"):
            names.update(alias.asname or alias.name for alias in node.names)
    return names


def root_name(node: ast.AST) -> str | None:
    while isinstance(node, ast.Attribute):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def own_private_names(files) -> set[str]:
    """The private names the package defines itself: functions, classes, module globals and
    attributes it assigns (``self._x = ...``, ``obj._x = ...``)."""
    names = set()
    for path in files:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                names.add(node.name)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                names.add(node.id)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                names.add(node.attr)
            elif isinstance(node, ast.arg):
                names.add(node.arg)
    return {name for name in names if private(name)}


def private_uses(path: Path, own: set[str] = frozenset()) -> list[str]:
    tree = ast.parse(path.read_text())
    foreign = foreign_names(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and not node.level and node.module and \
                not node.module.startswith("coincli"):
            parts = node.module.split(".")
            if any(private(part) for part in parts):
                found.append(f"{path}:{node.lineno}: from {node.module} import ...")
            found += [f"{path}:{node.lineno}: from {node.module} import {alias.name}"
                      for alias in node.names if private(alias.name)]
        elif isinstance(node, ast.Import):
            found += [f"{path}:{node.lineno}: import {alias.name}" for alias in node.names
                      if any(private(part) for part in alias.name.split("."))]
        elif isinstance(node, ast.Attribute) and private(node.attr) and (
                root_name(node) in foreign or (node.attr not in own
                                               and root_name(node) not in ("self", "cls"))):
            found.append(f"{path}:{node.lineno}: {ast.unparse(node)}")
        elif isinstance(node, ast.Call) and getattr(node.func, "id", None) in (
                "getattr", "hasattr", "setattr") and len(node.args) >= 2 and \
                isinstance(node.args[1], ast.Constant) and isinstance(node.args[1].value, str) \
                and private(node.args[1].value) and root_name(node.args[0]) in foreign:
            found.append(f"{path}:{node.lineno}: {ast.unparse(node)}")
        elif isinstance(node, ast.keyword) and node.arg and private(node.arg):
            found.append(f"{path}:{node.lineno}: keyword {node.arg}=")
    return found


def long_functions(path: Path) -> list[str]:
    tree = ast.parse(path.read_text())
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            lines = node.end_lineno - node.lineno + 1
            if lines > FUNCTION_LINES:
                out.append(f"{path}:{node.lineno}: {node.name} ({lines} lines)")
    return out


def measure(package: Path) -> dict:
    files = sorted(package.rglob("*.py"))
    own = own_private_names(files)
    return {
        "modules_over_600_lines": [f"{p.relative_to(package.parent)} "
                                   f"({len(p.read_text().splitlines())} lines)"
                                   for p in files
                                   if len(p.read_text().splitlines()) > MODULE_LINES],
        "functions_over_80_lines": [line for p in files for line in long_functions(p)],
        "private_names_of_other_libraries": [line for p in files
                                             for line in private_uses(p, own)],
    }


COMMANDS = {
    "coin --help": ["--help"],
    "warm coin simulate --no-rrd": ["simulate", "--vy", "1.197", "--vphi", "3.508", "--no-rrd"],
    "default 512 x 512 coin basin": ["basin", "{store}", "--quiet"],
    "the same with --rrd": ["basin", "{store}", "--quiet", "--rrd", "{rrd}"],
}


def timing(rounds: int, against: str | None, against_cache: str | None) -> dict:
    """Medians of interleaved rounds of COMMANDS, for this checkout and ``against``."""
    import os
    import shutil
    import statistics
    import subprocess
    import tempfile
    import time

    here = str(Path(__file__).resolve().parents[1])
    sides = {"this": {"PYTHONPATH": here}}
    if against:
        sides["against"] = {"PYTHONPATH": against,
                            **({"XDG_CACHE_HOME": against_cache} if against_cache else {})}
    times = {side: {name: [] for name in COMMANDS} for side in sides}
    work = Path(tempfile.mkdtemp(prefix="coin-house-"))
    try:
        for _ in range(rounds + 1):  # the first round warms the caches and is not counted
            for name, args in COMMANDS.items():
                for side, env in sides.items():
                    store, rrd = work / f"{side}.zarr", work / f"{side}.rrd"
                    shutil.rmtree(store, ignore_errors=True)
                    shutil.rmtree(f"{store}.cost", ignore_errors=True)
                    rrd.unlink(missing_ok=True)
                    command = [sys.executable, "-m", "coincli",
                               *(a.format(store=store, rrd=rrd) for a in args)]
                    t0 = time.perf_counter()
                    subprocess.run(command, check=True, capture_output=True, cwd=work,
                                   env={**os.environ, **env})
                    times[side][name].append(time.perf_counter() - t0)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    out = {}
    for side, by_name in times.items():
        row = {name: statistics.median(values[1:]) for name, values in by_name.items()}
        plain, recorded = by_name["default 512 x 512 coin basin"], by_name["the same with --rrd"]
        row["recorded ratio"] = statistics.median(r / p for p, r in zip(plain[1:], recorded[1:],
                                                                         strict=True))
        out[side] = row
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("package", nargs="?", default=str(Path(__file__).resolve().parents[1]
                                                         / "coincli"))
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--timing", action="store_true")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--against", help="another checkout to time beside this one")
    parser.add_argument("--against-cache", help="its kernel cache (XDG_CACHE_HOME)")
    args = parser.parse_args()
    if args.timing:
        result = timing(args.rounds, args.against, args.against_cache)
        if args.json:
            json.dump(result, sys.stdout, indent=2)
            print()
            return
        for side, row in result.items():
            print(side)
            for name, value in row.items():
                print(f"  {name}: {value:.3f}" + ("" if name == "recorded ratio" else " s"))
        return
    result = measure(Path(args.package))
    if args.json:
        json.dump(result, sys.stdout, indent=2)
        print()
        return
    for key, items in result.items():
        print(f"{key.replace('_', ' ')}: {len(items)}")
        for item in items:
            print(f"  {item}")


if __name__ == "__main__":
    main()
