"""`coin bench`: per-trajectory cost side by side, label agreement, and the full default basin."""

from __future__ import annotations

import os
import resource
import shutil
import tempfile
from typing import Annotated

import typer
from rich.table import Table

from ..params import ParameterError
from . import app
from .accuracy_cmd import parse_range, parse_res
from .common import (
    JsonOpt,
    PresetOpt,
    announce_compilation,
    build_scene,
    console,
    print_json,
    user_errors,
)


@app.command("bench")
def bench_command(
    cost_res: Annotated[str, typer.Option("--cost-res", help="Cells timed side by side "
                                          "(N or NxM).")] = "8",
    label_res: Annotated[str, typer.Option("--label-res", help="Grid for label agreement.")] = "24",
    repeats: Annotated[int, typer.Option("--repeats", help="Rounds of the side-by-side "
                                         "timing (median reported).")] = 3,
    basin_res: Annotated[int, typer.Option("--basin-res", help="Resolution of the full basin "
                                           "sweep timed at the end (0 to skip).")] = 512,
    vy_range: Annotated[str, typer.Option("--vy", "--vy-range", metavar="LO:HI",
                                          help="vy0 range, m/s.")] = "0.05:2",
    vphi_range: Annotated[str, typer.Option("--vphi", "--vphi-range", metavar="LO:HI",
                                            help="vphi0 range, rad/s.")] = "-20:20",
    threads: Annotated[int, typer.Option("--threads", help="Threads for the label grids.")] = (
        os.cpu_count() or 1),
    preset: PresetOpt = "paper", json_out: JsonOpt = False,
) -> None:
    """Benchmark: cost per trajectory of each method and of the paper's setting side by side, their label accuracy, and the full default basin on all cores."""  # noqa: E501
    from .. import bench
    from ..accuracy import vy_vphi_grid

    with user_errors():
        if threads < 1 or repeats < 1:
            raise ParameterError("--threads and --repeats must be at least 1")
        if basin_res != 0 and basin_res < 2:
            raise ParameterError(f"--basin-res must be 0 (skip) or at least 2, got {basin_res}")
        scene = build_scene(preset)
        vy, vphi = parse_range(vy_range, "--vy"), parse_range(vphi_range, "--vphi")
        cost_grid = vy_vphi_grid(scene, vy, vphi, parse_res(cost_res))
        label_grid = vy_vphi_grid(scene, vy, vphi, parse_res(label_res))
    announce_compilation()
    with console.status("") as status:
        say = lambda text: status.update(f"bench: {text}")  # noqa: E731
        rows = bench.side_by_side(scene, cost_grid, repeats, say)
        check = bench.label_check(scene, label_grid, rows, threads, say)
        basin = time_basin(scene, basin_res, say) if basin_res else None
    from ..integrators.registry import setting_text

    paper = next(r for r in rows if r.full_run)
    result = {
        "cost_cells": cost_grid.shape[0] * cost_grid.shape[1],
        "label_cells": int(check.robust.size), "robust_cells": int(check.robust.sum()),
        "reference_agreement": check.agreement_ab,
        "rows": [{"name": r.name, "method": r.setting.method.label,
                  "setting": setting_text(r.setting.method, r.setting.dt, r.setting.rtol),
                  "dt": r.setting.dt,
                  "rtol": r.setting.rtol, "full_run": r.full_run,
                  "ms_per_trajectory": r.seconds_per_trajectory * 1e3,
                  "rounds_ms": [t * 1e3 for t in r.repeats],
                  "speedup_vs_paper": paper.seconds_per_trajectory / r.seconds_per_trajectory,
                  "label_agreement_robust": r.label_agreement} for r in rows],
        "basin": basin,
    }
    if json_out:
        print_json(result)
        return
    table = Table(title=f"Cost per trajectory, one thread, median of {repeats} interleaved "
                        f"rounds over the same {result['cost_cells']} cells", title_justify="left")
    for col in ("setting", "ms / trajectory", "x faster than paper",
                f"label agreement ({result['robust_cells']} robust cells)"):
        table.add_column(col, justify="left" if col == "setting" else "right")
    for r in result["rows"]:
        name = r["name"] if r["full_run"] else (
            f"{r['method']} {r['setting']}, stop when settled")
        table.add_row(name, f"{r['ms_per_trajectory']:.4g}", f"{r['speedup_vs_paper']:.0f}",
                      f"{r['label_agreement_robust']:.2%}")
    console.print(table)
    console.print(f"Label grid {label_grid.shape[0]} x {label_grid.shape[1]}: references (event "
                  f"rtol=1e-12, rk4 h=2.5e-7) agree on {check.agreement_ab:.1%} of cells; "
                  f"{result['robust_cells']} robust cells.")
    if basin:
        console.print(f"Full default basin {basin_res} x {basin_res} ({basin['cells']:,} "
                      f"trajectories): {basin['wall_seconds']:.1f} s wall, "
                      f"{basin['trajectories_per_second']:,.0f} trajectories/s on "
                      f"{os.cpu_count()} cores, peak memory {basin['peak_rss_mb']:.0f} MB.")


def time_basin(scene, res: int, say) -> dict:
    """Sweep the default basin at ``res`` x ``res`` into a scratch store through the API (what
    `coin basin` runs) and time it."""
    from .. import api

    say(f"full default basin {res} x {res}")
    scratch = tempfile.mkdtemp(prefix="coin-bench-")
    try:
        plan = api.plan_sweep(scene, res=res)
        report = api.sweep(plan, os.path.join(scratch, "basin.zarr"))
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return {"res": res, "cells": report.cells, "wall_seconds": report.wall_seconds,
            "trajectories_per_second": report.cells / report.wall_seconds,
            "peak_rss_mb": peak}
