#!/usr/bin/env python
"""How the package's seams stand, counted from its files: what a maintainer meets before adding a
model, a method or a backend.

    python benchmarks/seams.py                     # this checkout
    python benchmarks/seams.py /path/to/coin-0.10.0 --json

Counted:
- **the CLI past the API**: names the command line (coincli/cli/) imports from the package
  other than coincli.api, and the import statements that do;
- **direct callers of the labelling kernels outside the labeller**: modules outside
  coincli/integrators/ and coincli/labeller.py that call a labelling kernel or its old Python
  wrappers (verified_labels, label_states, run_ladder, run_batch, final_state, warm_up,
  integrate) themselves;
- **homes of the engines and of their claim queues**: the packages that define an engine's run
  (``run_sweep``, ``run_fractions``; the API's facades not counted) and the modules that define
  a queue handing out claimed work (a class with ``take`` and ``settle`` that claims);
- **modules in the io layer**: coincli/io/ then; now its successors, stores/, recordings/,
  charts/ and files.py, each counted;
- **circles**: strongly connected components of more than one module in the package's import
  graph (imports inside functions included);
- **hops from the command to the store**: `coin basin S --res 64 --threads 1` run in a process
  of its own, profiled until its first tile file is renamed into place: the distinct calls from
  one module of the package into another (caller file -> callee file) and the files of the
  package whose code ran: what a reader follows from the command to the store.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

LABELLING = {"verified_labels", "label_states", "run_ladder", "run_batch", "final_state",
             "warm_up", "integrate"}


def modules(package: Path) -> dict[str, Path]:
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts) or "__init__"] = path
    return out


def imports(package: Path, path: Path) -> list[tuple[str, list[str], int]]:
    """(imported module, names, line) of every import of the package in a file (inside
    functions too), modules relative to the package."""
    rel = path.relative_to(package).with_suffix("")
    parts = list(rel.parts[:-1])
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = parts[:len(parts) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            elif (node.module or "").startswith("coincli"):
                target = node.module.removeprefix("coincli").lstrip(".")
            else:
                continue
            names = [a.name for a in node.names]
            if node.module is None or not node.module.strip("."):
                for name in names:  # from . import x: x may be a module
                    sub = ".".join(filter(None, [target, name]))
                    if (package / Path(*sub.split("."))).with_suffix(".py").exists() or \
                            (package / Path(*sub.split("."))).is_dir():
                        found.append((sub, [name], node.lineno))
                    else:
                        found.append((target, [name], node.lineno))
                continue
            found.append((target, names, node.lineno))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("coincli."):
                    found.append((alias.name.removeprefix("coincli."), [], node.lineno))
    return found


def cli_past_api(package: Path) -> dict:
    names, lines = 0, set()
    for path in sorted((package / "cli").rglob("*.py")):
        for target, imported, line in imports(package, path):
            head = target.split(".")[0] if target else ""
            if head in ("cli", "api", ""):
                continue
            names += max(1, len(imported))
            lines.add((str(path), line))
    return {"names": names, "import_lines": len(lines)}


def labelling_callers(package: Path) -> list[str]:
    out = []
    for module, path in modules(package).items():
        if module.startswith("integrators") or module == "labeller" or module == "jit":
            continue
        tree = ast.parse(path.read_text())
        called = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                func = node.func
                name = func.id if isinstance(func, ast.Name) else (
                    func.attr if isinstance(func, ast.Attribute) else None)
                if name in LABELLING:
                    called.add(name)
        imported = {n for _, names, _ in imports(package, path) for n in names}
        if called & imported:
            out.append(f"{module} ({', '.join(sorted(called & imported))})")
    return out


def homes(package: Path) -> dict:
    engines, queues = set(), set()
    for module, path in modules(package).items():
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef) and node.name in ("run_sweep", "run_fractions") \
                    and node.col_offset == 0 and not module.startswith("api"):
                engines.add(module.rsplit(".", 1)[0] if "." in module else module)
            if isinstance(node, ast.ClassDef):
                methods = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
                uses_claims = any(isinstance(n, ast.Attribute) and n.attr == "try_claim"
                                  for n in ast.walk(node))
                if {"take", "settle"} <= methods and uses_claims:
                    queues.add(module)
    return {"engine_homes": sorted(engines), "claim_queue_modules": sorted(queues)}


def io_modules(package: Path) -> dict:
    out = {}
    for name in ("io", "stores", "recordings", "charts"):
        folder = package / name
        if folder.is_dir():
            out[name] = len([p for p in folder.glob("*.py") if p.name != "__init__.py"])
    if (package / "files.py").exists():
        out["files.py"] = 1
    return out


def circles(package: Path) -> list[list[str]]:
    mods = modules(package)
    graph = {m: set() for m in mods}
    for module, path in mods.items():
        for target, _, _ in imports(package, path):
            while target and target not in mods:
                target = target.rsplit(".", 1)[0] if "." in target else ""
            if target and target != module and not module.startswith(target + "."):
                graph[module].add(target)
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return out


HOPS_SCRIPT = r"""
import json, os, sys, threading
from pathlib import Path
package = str(Path(sys.argv[1]).resolve()) + os.sep
store = sys.argv[2]
edges, files, done = set(), set(), []

def profile(frame, event, arg):
    if done or event != "call":
        return
    callee = frame.f_code.co_filename
    if not callee.startswith(package):
        return
    files.add(callee)
    caller = frame.f_back
    while caller is not None and not caller.f_code.co_filename.startswith(package):
        caller = caller.f_back
    if caller is not None and caller.f_code.co_filename != callee:
        edges.add((caller.f_code.co_filename[len(package):], callee[len(package):]))

real_replace = os.replace
def replace(src, dst, *a, **k):
    d = str(dst)
    if not done and store in d and os.sep + "c" + os.sep in d and ".cost" not in d:
        done.append(d)
    return real_replace(src, dst, *a, **k)
os.replace = replace
from coincli.cli import run
threading.setprofile(profile)
sys.setprofile(profile)
run(["basin", store, "--res", "64", "--quiet", "--threads", "1"])
sys.setprofile(None)
print(json.dumps({"edges": sorted(edges), "files": sorted(f[len(package):] for f in files)}))
"""


def hops(tree: Path) -> dict:
    """The module-to-module calls (distinct caller -> callee file pairs) of the package made by
    `coin basin S --res 64` up to its first tile write, and the files whose code ran."""
    with tempfile.TemporaryDirectory() as work:
        out = subprocess.run([sys.executable, "-c", HOPS_SCRIPT, str(tree / "coincli"),
                              os.path.join(work, "s.zarr")], capture_output=True, text=True,
                             env={**os.environ, "PYTHONPATH": str(tree)}, check=True, cwd=work)
    seen = json.loads(out.stdout.strip().splitlines()[-1])
    return {"module_to_module_calls": len(seen["edges"]), "files": len(seen["files"])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("tree", nargs="?", type=Path, default=Path(__file__).resolve().parents[1],
                        help="a checkout (a directory with coincli/)")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--no-hops", action="store_true", help="skip the run of coin basin")
    args = parser.parse_args()
    package = args.tree.resolve() / "coincli"
    result = {"cli_past_api": cli_past_api(package),
              "labelling_callers": labelling_callers(package),
              **homes(package), "io_modules": io_modules(package),
              "circles": circles(package)}
    if not args.no_hops:
        result["hops_to_the_store"] = hops(args.tree.resolve())
    if args.json:
        print(json.dumps(result, indent=1))
        return
    for key, value in result.items():
        print(f"{key}: {value}")


if __name__ == "__main__":
    main()
