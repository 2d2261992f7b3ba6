#!/usr/bin/env python
"""What a live recording costs a sweep: `coin basin STORE -q` against the same command with
`--rrd FILE`, run alternately (quiet first in odd pairs, recorded first in even ones, so that
both see the same load on a shared machine), each into a fresh store. Prints each run's wall
and CPU seconds (the process and its children) to stderr, then one line: the version, the
machine, the date, the medians, and the median and range of the per-pair ratios.

    python benchmarks/live_overhead.py                      # the default 512 x 512 sweep, 5 pairs
    python benchmarks/live_overhead.py --pairs 9 -- --res 256 --threads 2

Issue 30's target: the recorded run at most 10 % slower (ratio <= 1.10). The kernels must be
compiled already (`coin compile`); one pair, not counted, warms the caches. With `--write`, the
line also goes between the markers ``<!-- live-overhead:start -->`` ... ``:end -->`` of
docs/performance.md.
"""

from __future__ import annotations

import argparse
import datetime
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from docs_tables import PERFORMANCE, machine, replace_between  # noqa: E402


def run(command: list[str], cwd: Path) -> tuple[float, float]:
    """Wall and CPU seconds (user + system, of the process and whatever it started) of one
    run; fails on a non-zero exit."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                          text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)} failed (exit {done.returncode}): "
                 f"{done.stderr.strip()[-500:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=5)
    parser.add_argument("--coin", default=str(Path(sys.executable).with_name("coin")),
                        help="the coin executable (default: this Python's)")
    parser.add_argument("--write", action="store_true",
                        help="put the result line in docs/performance.md too")
    parser.add_argument("args", nargs="*", help="more arguments of `coin basin` (after --)")
    options = parser.parse_args()

    work = Path(tempfile.mkdtemp(prefix="coin-live-overhead-"))
    quiet = [options.coin, "basin", "q.zarr", "-q", *options.args]
    recorded = [options.coin, "basin", "r.zarr", "-q", *options.args, "--rrd", "r.rrd"]

    def fresh() -> None:
        for name in ("q.zarr", "q.zarr.cost", "r.zarr", "r.zarr.cost"):
            shutil.rmtree(work / name, ignore_errors=True)
        (work / "r.rrd").unlink(missing_ok=True)

    times: dict[str, list[tuple[float, float]]] = {"quiet": [], "rrd": []}
    try:
        fresh()
        run(quiet, work)  # warm-up: file caches, the kernels' cache, Rerun's modules
        run(recorded, work)
        for pair in range(options.pairs):
            order = [("quiet", quiet), ("rrd", recorded)]
            for name, command in order if pair % 2 == 0 else order[::-1]:
                fresh()
                wall, cpu = run(command, work)
                times[name].append((wall, cpu))
                print(f"pair {pair + 1} {name:5s} {wall:6.2f} s wall {cpu:6.2f} s CPU "
                      f"(load {os.getloadavg()[0]:.2f})", file=sys.stderr, flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    from coincli import __version__

    def median(name: str, k: int) -> float:
        return statistics.median(t[k] for t in times[name])

    ratios = [r[0] / q[0] for q, r in zip(times["quiet"], times["rrd"], strict=True)]
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    line = (f"coincli {__version__}, {machine()}, {date}: `coin basin STORE -q"
            f"{''.join(' ' + a for a in options.args)}` {median('quiet', 0):.2f} s wall "
            f"({median('quiet', 1):.2f} s CPU), with --rrd {median('rrd', 0):.2f} s "
            f"({median('rrd', 1):.2f} s CPU); ratio median {statistics.median(ratios):.3f} "
            f"(range {min(ratios):.3f}-{max(ratios):.3f}) over {options.pairs} alternating "
            f"pairs: `python benchmarks/live_overhead.py --pairs {options.pairs}"
            f"{' -- ' + ' '.join(options.args) if options.args else ''}`.")
    print(line)
    if options.write:
        replace_between(PERFORMANCE, "live-overhead", line)


if __name__ == "__main__":
    main()
