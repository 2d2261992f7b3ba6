"""Where a `coin` command's wall time goes before and after its kernels: a timeline of one child
process, its stamps taken on the monotonic clock the parent shares, medians over several runs.

    python benchmarks/startup_timeline.py                       # coin basin /tmp/... --res 64 -q
    python benchmarks/startup_timeline.py --rounds 9 -- basin /tmp/t.zarr --res 512 -q

Stamps: the interpreter up, numpy imported, the CLI imported, the sweep's estimate (numba
imported and the kernels loaded inside it), the store prepared, the command done (when the
command line's run returns), and the process gone as the parent sees it. The child wraps
those functions of coincli to stamp them; nothing else changes. An argument ending in .zarr is
removed before every run.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

CHILD = r'''
import json, sys, time
stamps = [("interpreter up", time.monotonic())]
import numpy
stamps.append(("numpy imported", time.monotonic()))
import coincli.cli as cli
stamps.append(("CLI imported", time.monotonic()))
from coincli.stores.basin_store import BasinStore
from coincli.engines import basin as engine


def stamped(owner, name, label):
    original = getattr(owner, name)

    def wrapper(*args, **kwargs):
        stamps.append((label + " start", time.monotonic()))
        try:
            return original(*args, **kwargs)
        finally:
            stamps.append((label + " end", time.monotonic()))
    setattr(owner, name, wrapper)


stamped(engine, "estimate_sweep", "estimate")
stamped(engine, "load_kernels", "kernel load")
stamped(BasinStore, "prepare", "store prepared")
code = cli.run(sys.argv[1:])
stamps.append(("command done", time.monotonic()))
print(json.dumps(stamps), file=sys.stderr, flush=True)
sys.exit(code)
'''


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("command", nargs="*", default=["basin", "/tmp/coin-timeline.zarr",
                                                       "--res", "64", "-q"])
    args = parser.parse_args()
    rows: dict[str, list[float]] = {}
    for _ in range(args.rounds):
        for arg in args.command:
            if arg.endswith(".zarr"):
                shutil.rmtree(arg, ignore_errors=True)  # its records with it (in .coin/)
        start = time.monotonic()
        child = subprocess.run([sys.executable, "-c", CHILD, *args.command], capture_output=True,
                               text=True, cwd=Path(__file__).resolve().parent.parent)
        gone = time.monotonic()
        if child.returncode != 0:
            sys.exit(f"the command failed: {child.stderr.strip()[-500:]}")
        stamps = json.loads(child.stderr.strip().splitlines()[-1])
        first = {}
        for label, at in stamps + [("process gone", gone)]:
            first.setdefault(label, at)  # the kernels are loaded twice, the second time in 1 ms
        for label, at in first.items():
            rows.setdefault(label, []).append(at - start)
    print(f"coin {' '.join(args.command)}: seconds after the parent started the child "
          f"(medians of {args.rounds})")
    for label, times in sorted(rows.items(), key=lambda item: statistics.median(item[1])):
        print(f"  {label:24s} {statistics.median(times):6.3f}")


if __name__ == "__main__":
    main()
