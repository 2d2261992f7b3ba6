#!/usr/bin/env python
"""The first compilation of the kernels, on an empty cache: where its time and memory go, kernel
by kernel, and what the first default map of a fresh install costs as a whole.

    python benchmarks/first_compile.py               # prints the table and the map's line
    python benchmarks/first_compile.py --repeats 3   # each measurement 3 times (medians)
    python benchmarks/first_compile.py --write       # also into docs/performance.md

Kernel by kernel: what `coin compile` compiles (``coincli.compile_kernels()``), in a child
process with an empty cache (NUMBA_CACHE_DIR and XDG_CACHE_HOME in a temporary folder), numba's
event API (``numba.core.event``, the "numba:compile" events) recording each kernel's
compilation: its own CPU seconds (those of the kernels compiled inside it taken out), how much
memory it left the process holding (resident set) and how much it raised the process's peak.
A kernel numba inlines into its callers (``@kernel(inline=True)``) is compiled inside each of
them and has no row of its own.

The first default map: `coin basin STORE --res 32` in a child process with an empty cache,
timed from outside: wall and CPU seconds (the command and whatever it started), and the peak
memory of the command's processes together (their resident sets summed, sampled every 20 ms).

Both go to benchmarks/first-compile.json; with ``--write`` also between the markers
``<!-- first-compile:start -->`` ... ``:end -->`` of docs/performance.md. The kernels' run time
is not measured here: compare it before and after a change with benchmarks/side_by_side.py.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
OUT = HERE / "first-compile.json"
ROWS = 8  # the kernels shown by name, the costliest first; the others share one row


def fresh_cache_env(folder: Path) -> dict:
    """The environment of a command on an empty kernel cache in ``folder``."""
    return {**os.environ, "NUMBA_CACHE_DIR": str(folder / "numba"),
            "XDG_CACHE_HOME": str(folder / "xdg")}


def compile_kernels_here() -> dict:
    """(Child.) compile_kernels in this process, numba's compile events recorded."""
    import numba.core.event as event

    def peak_mb() -> float:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    def rss_mb() -> float:
        return int(Path("/proc/self/statm").read_text().split()[1]) * os.sysconf(
            "SC_PAGE_SIZE") / 2**20

    rows: dict[str, dict] = {}
    open_ = []  # compilations under way: name, cpu, rss and peak at start, the inner ones' own

    class Compilations(event.Listener):
        def on_start(self, ev):
            fn = ev.data["dispatcher"].py_func
            name = (f"{fn.__module__.removeprefix('coincli.')}.{fn.__qualname__}"
                    if fn.__module__.startswith("coincli") else "numba's own functions")
            open_.append([name, [time.process_time(), rss_mb(), peak_mb()], [0.0, 0.0, 0.0]])

        def on_end(self, ev):
            name, start, inner = open_.pop()
            spent = [now - then for now, then in zip((time.process_time(), rss_mb(), peak_mb()),
                                                     start, strict=True)]
            row = rows.setdefault(name, {"kernel": name, "compilations": 0, "cpu_s": 0.0,
                                         "kept_mb": 0.0, "peak_mb": 0.0})
            row["compilations"] += 1
            for key, total, within in zip(("cpu_s", "kept_mb", "peak_mb"), spent, inner,
                                          strict=True):
                row[key] += total - within
            if open_:
                open_[-1][2] = [a + b for a, b in zip(open_[-1][2], spent, strict=True)]

    wall0, cpu0 = time.perf_counter(), time.process_time()
    import coincli

    with event.install_listener("numba:compile", Compilations()):
        coincli.compile_kernels()
    return {"wall_s": time.perf_counter() - wall0, "cpu_s": time.process_time() - cpu0,
            "peak_mb": peak_mb(), "kernels": sorted(rows.values(), key=lambda r: -r["cpu_s"])}


def kernels() -> dict:
    """The per-kernel compilation, in a child process on an empty cache."""
    with tempfile.TemporaryDirectory(prefix="coin-first-compile-") as folder:
        done = subprocess.run([sys.executable, __file__, "--child"], env=fresh_cache_env(
            Path(folder)), capture_output=True, text=True, cwd=folder)
    if done.returncode != 0:
        sys.exit(f"the compilation failed: {done.stderr.strip()[-2000:]}")
    return json.loads(done.stdout)


def first_map(coin: str) -> dict:
    """`coin basin STORE --res 32` on an empty cache: wall and CPU seconds, peak memory of its
    processes together."""
    import psutil

    with tempfile.TemporaryDirectory(prefix="coin-first-map-") as folder:
        command = [coin, "basin", str(Path(folder) / "s.zarr"), "--res", "32"]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        child = subprocess.Popen(command, env=fresh_cache_env(Path(folder)), cwd=folder,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        peak = 0
        root = psutil.Process(child.pid)
        while child.poll() is None:
            try:
                peak = max(peak, sum(p.memory_info().rss for p in
                                     [root, *root.children(recursive=True)]))
            except psutil.Error:  # a process ended while being read
                pass
            time.sleep(0.02)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if child.returncode != 0:
            sys.exit(f"{' '.join(command)} failed: {child.stderr.read().strip()[-2000:]}")
    return {"command": "coin basin s.zarr --res 32", "wall_s": wall,
            "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "peak_mb": peak / 2**20}


def median_run(runs: list[dict]) -> dict:
    """The run of median wall time (all its figures from that one run), with every run's."""
    ranked = sorted(runs, key=lambda r: r["wall_s"])
    return {**ranked[(len(ranked) - 1) // 2], "runs": runs}


def table(result: dict) -> str:
    """The markdown of docs/performance.md's "First compile" section."""
    from docs_tables import provenance

    compile_ = result["compile"]
    rows = compile_["kernels"]
    shown, rest = rows[:ROWS], rows[ROWS:]
    lines = [provenance(result["measured"]), "",
             "| kernel (its own compilation) | CPU seconds | MB kept | MB more at the peak |",
             "|---|---:|---:|---:|"]
    lines += [f"| `{r['kernel']}` | {r['cpu_s']:.1f} | {r['kept_mb']:.0f} | {r['peak_mb']:.0f} |"
              for r in shown]
    lines.append(f"| the other {len(rest)} | {sum(r['cpu_s'] for r in rest):.1f} | "
                 f"{sum(r['kept_mb'] for r in rest):.0f} | {sum(r['peak_mb'] for r in rest):.0f} |")
    lines.append(f"| **all** (`coin compile`, one process) | {compile_['cpu_s']:.1f} "
                 f"({compile_['wall_s']:.1f} s wall) | | peak {compile_['peak_mb']:.0f} |")
    first = result["first_map"]
    lines += ["", f"The first default map of a fresh install, `{first['command']}` on an empty "
              f"cache (the compilation, then the map): {first['wall_s']:.1f} s wall, "
              f"{first['cpu_s']:.1f} s CPU, peak memory {first['peak_mb']:.0f} MB."]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--coin", default=str(Path(sys.executable).with_name("coin")),
                        help="the coin executable (default: this Python's)")
    parser.add_argument("--write", action="store_true",
                        help="put the table in docs/performance.md too")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    options = parser.parse_args()
    if options.child:
        json.dump(compile_kernels_here(), sys.stdout)
        return

    sys.path.insert(0, str(HERE))
    from docs_tables import PERFORMANCE, machine, replace_between

    sys.path.insert(0, str(REPO))
    from coincli import __version__

    compiles, maps = [], []
    for _ in range(options.repeats):
        compiles.append(kernels())
        maps.append(first_map(options.coin))
        print(f"compile {compiles[-1]['cpu_s']:.1f} s CPU, {compiles[-1]['wall_s']:.1f} s wall, "
              f"peak {compiles[-1]['peak_mb']:.0f} MB; first map {maps[-1]['wall_s']:.1f} s "
              f"wall, {maps[-1]['cpu_s']:.1f} s CPU, peak {maps[-1]['peak_mb']:.0f} MB "
              f"(load {os.getloadavg()[0]:.2f})", file=sys.stderr, flush=True)
    command = "python benchmarks/first_compile.py" + (
        f" --repeats {options.repeats}" if options.repeats > 1 else "")
    result = {"measured": {"version": __version__, "machine": machine(),
                           "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d"),
                           "command": command, "load": os.getloadavg()[0]},
              "compile": median_run(compiles), "first_map": median_run(maps)}
    result["compile"]["median_cpu_s"] = statistics.median(c["cpu_s"] for c in compiles)
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    text = table(result)
    print(text)
    if options.write:
        replace_between(PERFORMANCE, "first-compile", text)


if __name__ == "__main__":
    main()
