"""The public API: what the CLI, the benchmarks, the tests and a notebook call.

    import coincli
    scene = coincli.load_preset("paper").with_overrides(vy=1.197, vphi=3.508)
    run = coincli.simulate(scene)            # a Trajectory
    outcome = coincli.classify(scene)        # an Outcome: quarter_turns, status, settle_time
    ds = coincli.basin(scene, vy=(0.05, 2.0), vphi=(-20.0, 20.0), res=64)   # xarray.Dataset
    coincli.basin_stats(ds)["standing"]
    coincli.render_basin(ds, "basin.png")

Options are keywords; results are named (dataclasses, named tuples, Datasets). Everything that
takes a basin takes a Dataset from :func:`basin` or :func:`open_basin`, or the path of a store.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from .enums import Method, Status
from .grid import (
    DEFAULT_CHUNK,
    DEFAULT_RES,
    Grid,
    SweepSpec,
    compute_tile,
    make_grid,
    make_spec,
    parse_pair,
    split_options,
)
from .integrators import check_step, warm_up
from .params import ParameterError, Scene, check_start, validate
from .presets import load
from .statics import StabilityReport, analyse
from .throw import Outcome, Trajectory, classify, simulate


def load_preset(name_or_path: str = "paper") -> Scene:
    """The scene of a shipped preset (``coin presets`` lists them) or of a TOML file."""
    return load(name_or_path).scene


def stability(scene: Scene) -> StabilityReport:
    """The static energy table and critical stiffnesses of the paper's section 3, and E_crit."""
    return analyse(validate(scene))


# -- basins -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepPlan:
    """A validated sweep: the scene (fixed initial values applied), its method, the grid and
    what every tile needs, and the attributes the store or Dataset will carry."""

    scene: Scene
    spec: SweepSpec
    attrs: dict

    @property
    def grid(self) -> Grid:
        return self.spec.grid


def plan_sweep(scene: Scene, *, res=DEFAULT_RES, chunk=DEFAULT_CHUNK, force: bool = False,
               **initial) -> SweepPlan:
    """Check everything about a sweep before any work: the ranges (two initial conditions
    swept, ``name=(lo, hi)`` or ``'LO:HI'``; vy and vphi sweep their defaults unless given), the
    other initial values, the resolution, the tiles, the method and its step."""
    from .io.schema import basin_attrs

    ranges, fixed = split_options(initial)
    scene = validate(scene.with_overrides(**fixed))
    grid = make_grid(scene, ranges, parse_pair("res", res, 2), parse_pair("chunk", chunk, 1))
    for axis in grid.axes:  # every swept value must make a valid scene too
        for value in (axis.lo, axis.hi):
            validate(scene.with_overrides(**{axis.name: value}))
    _check_starts(scene, grid)
    method = check_step(scene, force=force)
    spec = make_spec(scene, grid)
    return SweepPlan(scene, spec, basin_attrs(scene, method, spec))


def _check_starts(scene: Scene, grid: Grid) -> None:
    """No cell may start deeper in the foundation than the scene allows: the deepest pose has
    the lowest y0 and the angle that reaches furthest down (checked over every phi0 cell)."""
    coords = {axis.name: axis.coords for axis in grid.axes}
    y0 = float(np.min(coords["y0"])) if "y0" in coords else scene.y0
    phis = coords.get("phi0", np.array([scene.initial.phi0]))
    reach = scene.coin.r_d * np.abs(np.sin(phis)) + scene.coin.r_t * np.abs(np.cos(phis))
    check_start(scene, y0, float(phis[int(np.argmax(reach))]))


@dataclass(frozen=True)
class SweepProgress:
    """Passed to a sweep's ``progress`` callback after every tile."""

    tiles_done: int  # complete tiles, including those done before this run
    tiles_total: int
    cells_done: int  # cells computed by this run so far
    cells_todo: int  # cells this run set out to compute
    elapsed: float  # s of wall time since this run started


@dataclass(frozen=True)
class SweepReport:
    """What one invocation of :func:`sweep` did."""

    path: str
    tiles_total: int
    tiles_done: int  # complete tiles in the store now
    tiles_before: int  # complete tiles when this run started
    cells: int  # cells computed by this run
    wall_seconds: float
    mode: str  # "threads" or "dask"
    workers: int
    interrupted: bool

    @property
    def tiles_computed(self) -> int:
        return self.tiles_done - self.tiles_before

    @property
    def complete(self) -> bool:
        return self.tiles_done == self.tiles_total


def sweep(plan: SweepPlan, store: str | os.PathLike, *, overwrite: bool = False,
          threads: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: Callable[[SweepProgress], None] | None = None,
          stop=None) -> SweepReport:
    """Compute the tiles of ``plan`` that ``store`` does not hold yet (creating it if needed),
    on ``threads`` threads (default: one per core) or on Dask (``workers`` local processes, or
    the cluster at ``scheduler``). ``stop`` (anything with ``is_set()``, e.g. a
    threading.Event) asks it to finish the tiles in flight and return; so does Ctrl-C. A store
    with other parameters is refused (ParameterError naming them) unless ``overwrite``."""
    from .io import store as store_io
    from .io.runner import run_dask, run_threads, run_tile_task, usable_cores

    check_where(threads, workers, scheduler)
    started = time.time()
    path = Path(store)
    spec = plan.spec
    grid = plan.grid
    done = store_io.prepare(path, plan.attrs, spec, overwrite=overwrite)
    tiles = [t for t in grid.tiles() if not done[t]]
    total = len(grid.tiles())
    before = total - len(tiles)
    if scheduler is not None or workers is not None:
        mode, n_workers = "dask", workers or 0
        # workers open the store by this path: make it absolute (same path on every machine)
        runner = run_dask(str(path.resolve()), spec, tiles, scheduler=scheduler, workers=workers)
    else:
        mode, n_workers = "threads", threads or usable_cores()
        runner = run_threads(partial(run_tile_task, str(path), spec), tiles, n_workers)
    cells_todo = sum(grid.tile_cells(t) for t in tiles)
    if tiles and mode == "threads":
        _load_kernels(spec)
    wall0 = time.perf_counter()
    interrupted = False
    finished = cells = 0
    try:
        if tiles:
            for _tile, tile_cells, _cpu in runner:
                finished += 1
                cells += tile_cells
                if progress is not None:
                    progress(SweepProgress(before + finished, total, cells, cells_todo,
                                           time.perf_counter() - wall0))
                if stop is not None and stop.is_set():
                    interrupted = True
                    break
        runner.close()  # cancel what is queued, wait for the tiles in flight
    except KeyboardInterrupt:
        interrupted = True
        runner.close()
    wall = time.perf_counter() - wall0
    done_now = store_io.read_done(path)
    n_done = int(done_now.sum())
    cells = sum(grid.tile_cells(t) for t in tiles if done_now[t])  # tiles in flight included
    if tiles:
        store_io.record_run(path, store_io.run_record(started, wall, n_done - before, cells,
                                                      mode, n_workers, interrupted))
    return SweepReport(str(path), total, n_done, before, cells, wall, mode, n_workers,
                       interrupted)


def basin(scene: Scene, *, res=DEFAULT_RES, chunk=DEFAULT_CHUNK, store: str | os.PathLike |
          None = None, overwrite: bool = False, force: bool = False,
          threads: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: Callable[[SweepProgress], None] | None = None, stop=None,
          x0=None, y0=None, phi0=None, vx=None, vy=None, vphi=None):
    """The basin map of two initial conditions as an xarray Dataset.

    Swept axes are given as ``name=(lo, hi)`` (vy and vphi sweep (0.05, 2) m/s and (-20, 20)
    rad/s unless given); a plain number fixes a value. ``res`` cells per axis (N or (N, M)),
    tiles of ``chunk`` cells. Without ``store`` the map is computed in memory and returned; with
    ``store`` it is computed into (or resumed from) that Zarr store, the same store
    ``coin basin`` writes, and the store is returned opened. Every label is verified (see
    coincli.integrators.ladder) unless the scene's integration says ``verify=False``
    (``scene.with_overrides(verify=False)``). Interrupted (``stop`` set, or
    Ctrl-C), it raises KeyboardInterrupt; a store keeps every finished tile for a resume."""
    plan = plan_sweep(scene, res=res, chunk=chunk, force=force, x0=x0, y0=y0,
                      phi0=phi0, vx=vx, vy=vy, vphi=vphi)
    if store is not None:
        report = sweep(plan, store, overwrite=overwrite, threads=threads, workers=workers,
                       scheduler=scheduler, progress=progress, stop=stop)
        if report.interrupted:
            raise KeyboardInterrupt(f"sweep interrupted: {report.tiles_done} of "
                                    f"{report.tiles_total} tiles are in {report.path}")
        return open_basin(store)
    if workers is not None or scheduler is not None:
        raise ParameterError("a sweep on Dask writes its tiles to a store: give store=PATH")
    return _basin_in_memory(plan, threads, progress, stop)


def _basin_in_memory(plan: SweepPlan, threads, progress, stop):
    from .io.dataset import Basin, to_dataset
    from .io.runner import run_threads, usable_cores
    from .io.schema import FILLS, VARIABLES

    check_where(threads, None, None)
    grid, spec = plan.grid, plan.spec
    arrays = {name: np.full(grid.shape, FILLS[name], dtype=VARIABLES[name][0])
              for name in spec.array_names}
    done = np.zeros(grid.tile_grid, np.uint8)
    seconds = np.full(grid.tile_grid, np.nan)
    tiles = grid.tiles()
    _load_kernels(spec)
    wall0 = time.perf_counter()
    cells = 0
    runner = run_threads(partial(compute_tile, spec), tiles, threads or usable_cores())
    try:
        for result in runner:
            s0, s1 = grid.tile_slices(result.tile)
            for name, block in result.arrays.items():
                arrays[name][s0, s1] = block
            done[result.tile] = 1
            seconds[result.tile] = result.cpu_seconds
            cells += result.cells
            if progress is not None:
                progress(SweepProgress(int(done.sum()), len(tiles), cells, grid.n_cells,
                                       time.perf_counter() - wall0))
            if stop is not None and stop.is_set():
                raise KeyboardInterrupt("sweep interrupted")
    finally:
        runner.close()
    run = {"wall_seconds": round(time.perf_counter() - wall0, 3), "tiles": len(tiles),
           "cells": cells, "mode": "threads", "workers": threads or usable_cores(),
           "interrupted": False}
    return to_dataset(Basin(attrs=plan.attrs, arrays=arrays, done=done, tile_seconds=seconds,
                            runs=[run]))


def _load_kernels(spec: SweepSpec) -> None:
    """Load the compiled kernels before the clock starts (and before the threads race to)."""
    warm_up(spec.params, spec.settings, np.asarray(spec.grid.base_state, dtype=np.float64))


def check_where(threads, workers, scheduler) -> None:
    if workers is not None and scheduler is not None:
        raise ParameterError("give --workers (a local cluster) or --scheduler (an existing "
                             "one), not both")
    for option, value in (("--threads", threads), ("--workers", workers)):
        if value is not None and value < 1:
            raise ParameterError(f"{option} must be at least 1, got {value}")
    if threads is not None and (workers is not None or scheduler is not None):
        raise ParameterError("--threads is for a local run; a Dask run uses one thread per "
                             "worker")
    if scheduler is not None and "://" not in scheduler:
        raise ParameterError(f"--scheduler '{scheduler}' is not an address like "
                             "tcp://HOST:PORT")


def open_basin(store: str | os.PathLike):
    """A basin store as an xarray Dataset (in memory; cells of unfinished tiles read as not
    computed, status NOT_COMPUTED)."""
    from .io.dataset import to_dataset
    from .io.store import read_basin

    return to_dataset(read_basin(store))


def _as_basin(basin):
    """A Basin view of a Dataset, of a store path, or of a Basin."""
    from .io.dataset import Basin, from_dataset
    from .io.store import read_basin

    if isinstance(basin, Basin):
        return basin
    if isinstance(basin, str | os.PathLike):
        return read_basin(basin)
    return from_dataset(basin)


def basin_stats(basin) -> dict:
    """Outcome counts and fractions, P(standing) with its 95 % Wilson interval, the cells
    without a label, the certain and uncertain cells of a verified sweep with the outcome
    probabilities over the certain ones, and the cost, of a Dataset or a store path (plain
    values: ``coin basin stats --json`` prints this)."""
    from .stats import BasinCounts, cost_summary

    view = _as_basin(basin)
    a = view.arrays
    counts = BasinCounts()
    counts.add(a["quarter_turns"], a["status"], a["certainty"])
    out = counts.summary()
    out["cost"] = cost_summary(out["computed"], view.tile_seconds, view.done, view.runs)
    return out


def render_basin(basin, out: str | os.PathLike, *, title: str | None = None, dpi: int = 150,
                 n_max: int | None = None) -> Path:
    """Draw a basin (Dataset or store path) to a PNG in the paper's colours."""
    from .io.basin_render import render_png

    return render_png(_as_basin(basin), out, title=title, dpi=dpi, n_max=n_max)


# -- boundaries ---------------------------------------------------------------------------------
def analyze(basin, *, box: int = 5, bands: int = 4, points: int | None = None,
            eps: tuple[float, ...] | None = None, seed: int = 0, threads: int | None = None,
            radius: float = 5.0, balls: int = 1000, max_dilation: int = 6,
            direction: str = "random", confidence: float = 0.95,
            progress: Callable[[str, int, int], None] | None = None, stop=None):
    """How fractal the boundaries of a basin (Dataset or store path) are, on the whole map and
    per band of its first swept axis: a :class:`coincli.analysis.BasinAnalysis`
    (``.whole``, ``.bands``; ``.to_dict()`` is what ``coin basin analyze --json`` prints).

    On the map (``box`` cells per box, uncertain and not-computed cells left out): basin entropy
    S_b and boundary basin entropy S_bb with the log-2 criterion, the ball test for fractal
    boundaries (balls of ``radius`` cells, ``balls`` of them), box-counting alpha, the Wada
    merging test (up to ``max_dilation`` cells). With the simulator: the uncertainty exponent
    alpha by the perturbation method from ``points`` random initial conditions (default 150,000;
    0 skips it) perturbed by each of ``eps`` (relative to each axis's range; default 6 values,
    1e-9 to 1e-4), classified with verified labels on ``threads`` threads (default: one per
    core); D = 2 - alpha. ``seed`` makes it reproducible. ``progress(stage, done, total)``;
    ``stop`` (an Event) or Ctrl-C interrupts it (KeyboardInterrupt)."""
    from .analysis import DEFAULT_POINTS, AnalysisOptions, analyze_basin
    from .io.runner import usable_cores

    view = _as_basin(basin)
    opts = AnalysisOptions(box=int(box), bands=int(bands),
                           points=DEFAULT_POINTS if points is None else int(points),
                           seed=int(seed), threads=int(threads or usable_cores()),
                           radius=float(radius), balls=int(balls),
                           max_dilation=int(max_dilation), direction=direction,
                           confidence=float(confidence),
                           **({} if eps is None else {"eps": tuple(float(e) for e in eps)}))
    a = view.arrays
    return analyze_basin(a["quarter_turns"], a["status"], a["certainty"], view.attrs,
                         options=opts, progress=progress, stop=stop)


def render_analysis(analysis, out: str | os.PathLike, *, title: str | None = None,
                    dpi: int = 150) -> Path:
    """Draw an analysis (of :func:`analyze`): f(eps) on log-log axes with the fits, and S_b,
    S_bb and alpha by band; PNG or SVG by the file's extension."""
    from .io.analysis_charts import plot_analysis

    return plot_analysis(analysis, Path(out), title=title, dpi=dpi)


__all__ = ["Method", "Outcome", "Status", "SweepPlan", "SweepProgress", "SweepReport", "Trajectory",
           "analyze", "basin", "basin_stats", "classify", "load_preset", "open_basin",
           "plan_sweep", "render_analysis", "render_basin", "simulate", "stability", "sweep"]
