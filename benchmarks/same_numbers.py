#!/usr/bin/env python
"""The same numbers as another version: maps, counts and stores of this checkout against another
checkout's (e.g. the last release), through both command lines, which are the same across
versions.

    python benchmarks/same_numbers.py /path/to/coin-0.10.0            # about 5 minutes
    python benchmarks/same_numbers.py /path/to/coin-0.10.0 --json out.json

Each checkout runs as ``python -m coincli`` with its own directory first on ``sys.path`` (its own
kernel cache: the other's kernels compile on its first run). Checked:

- **maps**: the default map at 64 x 64 (the paper's coin) and the thick coin's at 48 x 48: every
  array (quarter_turns, status, settle_time, steps, certainty, rung) equal, element for element;
- **counts**: `coin fractions --samples 16k`: every count of the JSON result equal;
- **a store resumed**: a 512 x 512 map the other version started and was interrupted in (SIGINT
  after 2.5 s, a few tiles in), resumed by this one: every file of the store (but the cost records
  beside it, which name hosts, processes and times) byte-identical to the store the other
  version computes in one go.

Exits 1 if anything differs.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ARRAYS = ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung")


def coin(tree: Path, *args, check: bool = True, **kwargs):
    """``coin ARGS`` of the checkout ``tree`` (run from the root folder: ``python -m`` puts the
    working folder first on the path)."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    return subprocess.run([sys.executable, "-m", "coincli", *map(str, args)], env=env,
                          check=check, capture_output=True, text=True, cwd="/", **kwargs)


def arrays(store: Path) -> dict[str, np.ndarray]:
    import zarr

    group = zarr.open_group(str(store), mode="r")
    return {name: np.asarray(group[name][...]) for name in ARRAYS}


def same_arrays(a: dict, b: dict) -> list[str]:
    """The names of the arrays that differ (NaN equal to NaN)."""
    return [name for name in ARRAYS
            if not np.array_equal(a[name], b[name], equal_nan=a[name].dtype.kind == "f")]


def store_files(store: Path) -> dict[str, bytes]:
    """Every file of a store, by its path inside it; not its records (its ``.coin`` folder, or
    0.10.0's ``NAME.zarr.cost`` beside it): hosts, processes and times."""
    out = {}
    for path in sorted(store.rglob("*")):
        rel = path.relative_to(store)
        if path.is_file() and not any(part.endswith(".cost") or part == ".coin"
                                      for part in rel.parts):
            out[str(rel)] = path.read_bytes()
    return out


def check_map(old: Path, new: Path, work: Path, name: str, *args) -> dict:
    for tree, side in ((old, "old"), (new, "new")):
        coin(tree, "basin", work / f"{name}-{side}.zarr", *args, "-q")
    differ = same_arrays(arrays(work / f"{name}-old.zarr"), arrays(work / f"{name}-new.zarr"))
    return {"check": f"map {name} ({' '.join(args)})", "same": not differ, "differ": differ}


def check_counts(old: Path, new: Path) -> dict:
    results = {}
    for tree, side in ((old, "old"), (new, "new")):
        out = coin(tree, "fractions", "--samples", "16k", "--json", "--threads", "2")
        data = json.loads(out.stdout)
        results[side] = {key: data[key] for key in (
            "samples", "counted", "standing", "lying", "uncertain", "outcomes", "all_decided",
            "all_labelled", "status", "stopped")}
    differ = [key for key in results["old"] if results["old"][key] != results["new"].get(key)]
    return {"check": "fractions --samples 16k", "same": not differ and bool(results["old"]),
            "differ": differ, "compared": sorted(results["old"])}


def check_resume(old: Path, new: Path, work: Path, after: float) -> dict:
    whole, resumed = work / "whole.zarr", work / "resumed.zarr"
    coin(old, "basin", whole, "-q")
    env = {**os.environ, "PYTHONPATH": str(old)}
    started = subprocess.Popen([sys.executable, "-m", "coincli", "basin", str(resumed), "-q"],
                               env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               cwd="/")
    time.sleep(after)
    started.send_signal(signal.SIGINT)
    code = started.wait()
    partial = len(list((resumed / "done" / "c").rglob("*"))) if resumed.exists() else 0
    coin(new, "basin", resumed, "-q")
    a, b = store_files(whole), store_files(resumed)
    differ = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
    return {"check": f"a store of the other version interrupted after {after:g} s (exit {code},"
                     f" {partial} tile files) and resumed here", "same": not differ,
            "differ": differ[:10], "files": len(a)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old", type=Path, help="the other checkout (a directory with coincli/)")
    parser.add_argument("--after", type=float, default=2.5,
                        help="seconds before the other version's sweep is interrupted")
    parser.add_argument("--json", type=Path, help="write the results here too")
    args = parser.parse_args()
    old, new = args.old.resolve(), HERE.parent
    coin(old, "compile")
    coin(new, "compile")
    work = Path(tempfile.mkdtemp(prefix="coin-same-numbers-"))
    try:
        results = [check_map(old, new, work, "paper-64", "--res", "64"),
                   check_map(old, new, work, "thick-48", "--preset", "thick", "--res", "48"),
                   check_counts(old, new),
                   check_resume(old, new, work, args.after)]
    finally:
        shutil.rmtree(work, ignore_errors=True)
    versions = {side: coin(tree, "--version").stdout.strip() for side, tree in
                (("old", old), ("new", new))}
    for r in results:
        print(f"{'same' if r['same'] else 'DIFFERENT':9s}  {r['check']}"
              + ("" if r["same"] else f": {r['differ']}"))
    print(f"old: {versions['old']} ({old}); new: {versions['new']} ({new})")
    if args.json:
        args.json.write_text(json.dumps({"versions": versions, "results": results}, indent=1))
    sys.exit(0 if all(r["same"] for r in results) else 1)


if __name__ == "__main__":
    main()
