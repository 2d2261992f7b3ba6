"""`coin bench`: per-trajectory cost side by side, label agreement, and the full default basin."""

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Annotated

import typer
from rich.table import Table

from ..api import ParameterError
from .app import app
from .common import (
    JsonOpt,
    PresetOpt,
    build_scene,
    compile_first,
    console,
    print_json,
    user_errors,
    whole_option,
)
from .text import say


@app.command("bench")
def bench_command(
    cost_res: Annotated[str, typer.Option("--cost-res", metavar="N|NxM",
                                          help="Cells timed side by side "
                                          "(N or NxM).")] = "8",
    label_res: Annotated[str, typer.Option("--label-res", metavar="N|NxM",
                                           help="Grid for label agreement.")] = "24",
    repeats: Annotated[int, typer.Option("--repeats", help="Rounds of the side-by-side "
                                         "timing (median reported).", parser=whole_option,
                                         metavar="N")] = 3,
    basin_res: Annotated[int, typer.Option("--basin-res", help="Resolution of the full basin "
                                           "sweep timed at the end (0 to skip).",
                                           parser=whole_option, metavar="N")] = 512,
    vy_range: Annotated[str, typer.Option("--vy", "--vy-range", metavar="LO:HI",
                                          help="vy0 range, m/s.")] = "0.05:2",
    vphi_range: Annotated[str, typer.Option("--vphi", "--vphi-range", metavar="LO:HI",
                                            help="vphi0 range, rad/s.")] = "-20:20",
    threads: Annotated[int | None, typer.Option("--threads", help="Threads for the label "
                                                "grids (default: one per core).",
                                                parser=whole_option, metavar="N")] = None,
    preset: PresetOpt = "paper", json_out: JsonOpt = False,
) -> None:
    """Benchmark: cost per trajectory of each method and of the paper's setting side by side, their label accuracy, and the full default basin on all cores."""  # noqa: E501
    from ..api.studies import bench_methods

    with user_errors():
        if basin_res != 0 and basin_res < 2:
            raise ParameterError(f"--basin-res must be 0 (skip) or at least 2, got {basin_res}")
        scene = build_scene(preset)
        compile_first(scene=scene)
        with console.status("") as status:
            def report(text):
                status.update(f"bench: {text}")
            found = bench_methods(scene, vy=vy_range, vphi=vphi_range, cost_res=cost_res,
                                  label_res=label_res, repeats=repeats, threads=threads,
                                  progress=report)
            startup = time_startup(report)
            basin = time_basin_command(basin_res, report) if basin_res else None
    result = {**found.to_dict(), "startup": startup, "basin": basin}
    if json_out:
        print_json(result)
        return
    table = Table(title=f"Cost per trajectory, one thread, median of {repeats} interleaved "
                        f"rounds over the same {result['cost_cells']} cells", title_justify="left")
    for col in ("setting", "ms", "x paper", "right", "uncertain"):
        table.add_column(col, justify="left" if col == "setting" else "right", no_wrap=True)
    for r in result["rows"]:
        right = f"{r['label_agreement_robust']:.2%}"
        uncertain = f"{r['uncertain_robust']:.1%}" if r["verified"] else "-"
        table.add_row(r["name"], f"{r['ms_per_trajectory']:.3g}",
                      f"{r['speedup_vs_paper']:,.0f}", right, uncertain)
    console.print(table)
    n0, n1 = found.label_shape
    say(console, f"Label grid {n0} x {n1}: references (event "
                 f"rtol=1e-12, rk4 h=2.5e-7) agree on {found.reference_agreement:.1%} of cells; "
                 f"{result['robust_cells']} robust cells: right and uncertain are fractions of "
                 "those (a verified setting's right cells are the certain ones with the "
                 "reference's label).")
    say(console, f"Start-up, median of {STARTUP_RUNS} runs: coin --help "
                 f"{startup['help_seconds']:.2f} s, coin simulate (fig. 2, warm, --no-rrd) "
                 f"{startup['simulate_seconds']:.2f} s; importing what every command that "
                 f"runs kernels needs (Python, numpy, typer, rich, numba) "
                 f"{startup['import_floor_seconds']:.2f} s.")
    if basin:
        say(console,
            f"Default basin {basin_res} x {basin_res} ({basin['cells']:,} cells, verified), "
            f"the whole command: {basin['wall_seconds']:.2f} s wall on {basin['threads']} "
            f"threads: start-up {basin['startup_seconds']:.2f} s, kernels "
            f"{basin['kernel_seconds']:.2f} s, tiles and store {basin['store_seconds']:.2f} s, "
            f"other {basin['other_seconds']:.2f} s; {basin['outside_kernels']:.0%} outside "
            f"the kernels, of which those imports "
            f"{startup['import_floor_seconds'] / basin['wall_seconds']:.0%}; peak memory "
            f"{basin['peak_rss_mb']:.0f} MB.")


STARTUP_RUNS = 5


# What every command that runs kernels imports before it can do anything (Python, numpy, typer
# and rich, numba), then an exit without the interpreter's teardown as the command's
# (cli.exit_now): the part of its start-up no work of ours can remove.
IMPORT_FLOOR = "import os, numpy, typer, rich.console, rich.progress, numba\nos._exit(0)"


def _run(args: list[str], cwd: str, *, code: str | None = None) -> tuple[float, float]:
    """(wall seconds, peak resident MB) of one `coin` command (or, given ``code``, of that
    Python code) run as a child process. The peak is that child's own (os.wait4), not the
    largest of every child so far, which RUSAGE_CHILDREN gives: a first compilation earlier in
    the run peaks at about a gigabyte."""
    command = [sys.executable, "-c", code] if code else [sys.executable, "-m", "coincli", *args]
    with tempfile.TemporaryFile() as errors:
        start = time.perf_counter()
        proc = subprocess.Popen(command, cwd=cwd, stdout=subprocess.DEVNULL, stderr=errors)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode != 0:
            errors.seek(0)
            tail = errors.read().decode(errors="replace").strip()[-300:]
            raise RuntimeError(f"{'the import floor' if code else 'coin ' + ' '.join(args)} "
                               f"failed: {tail}")
    return wall, usage.ru_maxrss / 1024


def _wall(args: list[str], cwd: str) -> float:
    return _run(args, cwd)[0]


def time_startup(report) -> dict:
    """Wall time of `coin --help`, of a warm `coin simulate` and of IMPORT_FLOOR (median of
    STARTUP_RUNS each, the three interleaved)."""
    scratch = tempfile.mkdtemp(prefix="coin-bench-")
    help_times, simulate_times, floor_times = [], [], []
    simulate = ["simulate", "--vy", "1.197", "--vphi", "3.508", "--no-rrd"]
    try:
        _wall(simulate, scratch)  # warm: caches loaded once
        for k in range(STARTUP_RUNS):
            report(f"start-up {k + 1}/{STARTUP_RUNS}")
            help_times.append(_wall(["--help"], scratch))
            simulate_times.append(_wall(simulate, scratch))
            floor_times.append(_run([], scratch, code=IMPORT_FLOOR)[0])
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return {"help_seconds": statistics.median(help_times), "help_runs": help_times,
            "simulate_seconds": statistics.median(simulate_times),
            "simulate_runs": simulate_times,
            "import_floor_seconds": statistics.median(floor_times),
            "import_floor_runs": floor_times}


def time_basin_command(res: int, report) -> dict:
    """Run the real `coin basin STORE --res RES` into a scratch store and time it: the whole
    command, and from its run record the tiles' time in the kernels and in the store."""
    from ..api.basins import open_store

    report(f"default basin {res} x {res}, the whole command")
    scratch = tempfile.mkdtemp(prefix="coin-bench-")
    store = os.path.join(scratch, "basin.zarr")
    try:
        wall, peak = _run(["basin", store, "--res", str(res), "--quiet"], scratch)
        record = open_store(store).runs()[-1]  # the command's run, as its store recorded it
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    threads = max(1, record["workers"])
    kernels = record["kernel_seconds"] / threads  # wall: the threads run side by side
    store_time = record["store_seconds"] / threads
    sweep = record["wall_seconds"]
    return {"res": res, "cells": record["cells"], "threads": threads, "wall_seconds": wall,
            "startup_seconds": wall - sweep, "kernel_seconds": kernels,
            "store_seconds": store_time, "other_seconds": max(0.0, sweep - kernels - store_time),
            "outside_kernels": (wall - kernels) / wall, "peak_rss_mb": peak,
            "cells_per_second": record["cells"] / wall}
