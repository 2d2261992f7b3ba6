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

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from .enums import Method, Status
from .fractions import (
    DEFAULT_BATCH,
    DEFAULT_MAX_SAMPLES,
    PARAMETERS,
    SOBOL_MAX,
    BatchResult,
    BatchTask,
    Draws,
    Fractions,
    FractionsOver,
    Goal,
    Progression,
    Sampling,
    Tally,
    check_box,
    compute_batch,
    continuation_note,
    initial_states,
    make_fraction_spec,
    make_goal,
    make_result,
    make_sampling,
    parse_over,
    samples_needed,
    scene_at,
    widest,
    wilson_arrays,
)
from .grid import (
    DEFAULT_CHUNK,
    DEFAULT_RES,
    Grid,
    SweepSpec,
    compute_tile,
    make_grid,
    make_spec,
    method_attrs,
    parse_pair,
    split_options,
)
from .integrators import check_step, warm_up
from .params import ParameterError, Scene, check_start, state_array, validate
from .presets import load
from .statics import StabilityReport, analyse
from .throw import Outcome, Trajectory, classify, simulate
from .version import __version__


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


# -- outcome probabilities (coin fractions) -----------------------------------------------------
@dataclass(frozen=True)
class FractionsPlan:
    """A validated Monte Carlo run: the scene of each value (one for a plain run), how samples
    are drawn, when to stop, and the attributes its store carries."""

    scenes: tuple[Scene, ...]
    sampling: Sampling
    goal: Goal
    parameter: str | None
    values: tuple[float, ...] | None
    note: str | None
    attrs: dict

    @property
    def scene(self) -> Scene:
        return self.scenes[0]


def plan_fractions(scene: Scene, *, y0=None, phi0=None, vx=None, vy=None, vphi=None,
                   samples=None, precision=None, of: str = "all",
                   max_samples=DEFAULT_MAX_SAMPLES, seed: int = 0, sampler: str = "sobol",
                   batch: int = DEFAULT_BATCH, over=None, keep=(), force: bool = False
                   ) -> FractionsPlan:
    """Check everything about a Monte Carlo run before any work: the distributions (see
    :func:`coincli.fractions.parse_dist`), that no sample can start too deep in the foundation,
    the goal, and for a continuation (``over``: ``(name, values)`` or ``'NAME=LO:HI:STEPS'``)
    every value's scene and step."""
    validate(scene)
    sampling = make_sampling(scene, sampler=sampler, seed=seed, batch=batch, y0=y0, phi0=phi0,
                             vx=vx, vy=vy, vphi=vphi)
    goal = make_goal(samples=samples, precision=precision, of=of, max_samples=max_samples)
    if sampler == "sobol" and goal.batches(sampling.batch) * sampling.batch > SOBOL_MAX:
        raise ParameterError(f"a Sobol sequence has {SOBOL_MAX:,} points; lower --max-samples "
                             "or use --sampler random")
    keep = tuple(keep or ())
    for name in keep:
        if name not in ("mass", "inertia"):
            raise ParameterError(f"keep: '{name}' is not mass or inertia")
    parameter = values = note = None
    if over is not None:
        parameter, values = parse_over(over) if isinstance(over, str) else over
        values = tuple(float(v) for v in np.atleast_1d(np.asarray(values, dtype=float)))
        if parameter not in PARAMETERS:
            raise ParameterError(f"cannot vary '{parameter}'; one of {', '.join(PARAMETERS)}")
        if not values or not all(math.isfinite(v) for v in values):
            raise ParameterError(f"{parameter}: give finite values to vary it over")
        scenes = tuple(scene_at(scene, parameter, v, keep) for v in values)
        note = continuation_note(scene, parameter, keep)
    else:
        scenes = (scene,)
    for s in scenes:
        check_box(s, sampling)
        method = check_step(s, force=force)
    parameters = scene.to_dict()
    for name in sampling.random_names:
        parameters["initial"][name] = None  # drawn: see sampling
    if parameter is not None:  # varied: see over (the base scene's value is in the note)
        if parameter == "g":
            parameters["g"] = None
        else:
            section = "foundation" if parameter in ("k", "c") else "coin"
            parameters[section][parameter] = None
    attrs = {"coin_fractions": {"format": 1, "command": "coin fractions"},
             "version": __version__, "parameters": parameters,
             "sampling": sampling.to_dict(), "method": method_attrs(scene, method),
             "over": None if parameter is None else {
                 "parameter": parameter, "values": list(values), "keep": list(keep),
                 "note": note}}
    return FractionsPlan(scenes, sampling, goal, parameter, values, note, attrs)


@dataclass(frozen=True)
class FractionsProgress:
    """Passed to a Monte Carlo run's ``progress`` callback after every batch."""

    value: int  # index of the value whose batch just finished (0 for a plain run)
    values: int  # number of values (1 for a plain run)
    values_done: int  # values whose goal is met
    samples: int  # samples counted for this value so far (the prefix of batches, in order)
    standing: tuple[float, float, float]  # P(standing), low, high over that prefix
    widest: float  # the widest half-width the stop rule looks at (NaN: nothing yet)
    precision: float | None  # the goal's half-width (None for a fixed count)
    expected: int  # samples this value will likely need (a guess, for a progress bar)
    computed: int  # samples computed by this run so far (all values)
    elapsed: float  # s of wall time


def fractions(scene: Scene, *, y0=None, phi0=None, vx=None, vy=None, vphi=None,
              samples: int | None = None, precision: float | None = None, of: str = "all",
              max_samples: int = DEFAULT_MAX_SAMPLES, seed: int = 0, sampler: str = "sobol",
              batch: int = DEFAULT_BATCH, store: str | os.PathLike | None = None,
              overwrite: bool = False, threads: int | None = None, workers: int | None = None,
              scheduler: str | None = None, force: bool = False,
              progress: Callable[[FractionsProgress], None] | None = None,
              stop=None) -> Fractions:
    """The outcome probabilities of throws whose initial conditions are drawn at random.

    Each of ``y0, phi0, vx, vy, vphi`` is a fixed value, a uniform range ``(lo, hi)`` or
    ``'LO:HI'``, a ``'normal(MEAN,SD)'`` (truncated: ``'normal(MEAN,SD,LO,HI)'``), or a
    :class:`coincli.fractions.Dist`; numbers may be written ``'2pi'``, ``'pi/2'``, and y0 in
    multiples of the coin's half diagonal, ``'r:5r'``. Not given: the scene's values, except
    vy and vphi, drawn over coin basin's default ranges. Samples are scrambled Sobol points
    (``sampler='sobol'``) or independent draws (``'random'``), reproducible from ``seed``.

    Runs batches of ``batch`` samples on ``threads`` threads (or on Dask: ``workers``,
    ``scheduler``) until the 95 % interval of every probability has half-width <= ``precision``
    (``of='standing'``: of P(standing) only), or ``max_samples`` are spent; ``samples`` fixes
    the count instead. With ``store`` the samples and labels are kept in (and resumed from)
    that Zarr store. ``stop`` (a threading.Event) or Ctrl-C ends the run early: the result then
    says ``stopped='interrupted'``. Returns a :class:`coincli.fractions.Fractions`."""
    plan = plan_fractions(scene, y0=y0, phi0=phi0, vx=vx, vy=vy, vphi=vphi, samples=samples,
                          precision=precision, of=of, max_samples=max_samples, seed=seed,
                          sampler=sampler, batch=batch, force=force)
    return run_fractions(plan, store=store, overwrite=overwrite, threads=threads,
                         workers=workers, scheduler=scheduler, progress=progress, stop=stop)


def fractions_over(scene: Scene, parameter: str, values, *, keep=(), **options) -> FractionsOver:
    """The outcome probabilities at each of ``values`` of one physical ``parameter``
    (thickness, diameter, k, c, mass, inertia, g), the same sample points at every value
    (common random numbers). For thickness and diameter the mass and inertia follow a uniform
    solid disc of the scene's density, except those named in ``keep`` (the result's ``note``
    says which). Options are those of :func:`fractions`; each value is resumable on its own
    in the store. Returns a :class:`coincli.fractions.FractionsOver`."""
    run_options = {k: options.pop(k) for k in ("store", "overwrite", "threads", "workers",
                                               "scheduler", "progress", "stop")
                   if k in options}
    plan = plan_fractions(scene, over=(parameter, values), keep=keep, **options)
    return run_fractions(plan, **run_options)


def run_fractions(plan: FractionsPlan, *, store: str | os.PathLike | None = None,
                  overwrite: bool = False, threads: int | None = None,
                  workers: int | None = None, scheduler: str | None = None,
                  progress: Callable[[FractionsProgress], None] | None = None, stop=None):
    """Run a planned Monte Carlo run (see :func:`fractions`); a Fractions for a plain run, a
    FractionsOver for a continuation."""
    from .io import fractions_store as fstore
    from .io.runner import run_threads, usable_cores

    check_where(threads, workers, scheduler)
    started = time.time()
    sampling, goal = plan.sampling, plan.goal
    size = sampling.batch
    specs = [make_fraction_spec(s) for s in plan.scenes]
    verified = specs[0].ladder.verified
    progs = [Progression(goal, size, verified) for _ in plan.scenes]
    draws = Draws(sampling)
    n_values = len(plan.scenes)
    layout = fstore.Layout(size, goal.batches(size),
                           None if plan.parameter is None else n_values, plan.parameter)
    writer = None
    if store is not None:
        filled = fstore.prepare(store, plan.attrs, layout, None if plan.values is None
                                else np.asarray(plan.values), overwrite=overwrite)
        _resume(plan, progs, draws, layout, store, filled)
        writer = fstore.Writer(store, layout)

    def tasks():
        while True:
            best = None
            for v, prog in enumerate(progs):
                index = prog.peek()
                if index is not None and (best is None or index < best[1]):
                    best = (v, index)
            if best is None:
                return
            v, index = best
            progs[v].next_batch()
            count = goal.count(index, size)
            states = initial_states(plan.scenes[v], sampling, draws.batch(index)[:count])
            yield BatchTask(v, index, count, states)

    if scheduler is not None or workers is not None:
        from .io.dask_tasks import run_dask_tasks

        mode, n_workers = "dask", workers or 0
        runner = run_dask_tasks(compute_batch, ((specs[t.value], t) for t in tasks()),
                                key=lambda item: f"coin-fractions-{item[1].value}-"
                                                 f"{item[1].batch}",
                                scheduler=scheduler, workers=workers)
    else:
        mode, n_workers = "threads", threads or usable_cores()
        if any(p.peek() is not None for p in progs):
            for spec, s in zip(specs, plan.scenes, strict=True):
                warm_up(spec.params, spec.settings, np.asarray(state_array(s)))
        runner = run_threads(lambda t: compute_batch(specs[t.value], t), tasks(), n_workers)
    pending: list[dict[int, BatchResult]] = [{} for _ in plan.scenes]
    written = [p.prefix for p in progs]  # batches below are in the store (or need no store)
    cpu = [0.0] * n_values
    computed = 0
    wall0 = time.perf_counter()
    interrupted = False

    def flush(v: int, upto: int) -> None:
        while written[v] < upto:
            result = pending[v].pop(written[v], None)
            if result is None:
                return
            if writer is not None:
                writer.write(v, result.batch, result.states, result.labels)
            written[v] += 1

    try:
        for result in runner:
            v = result.value
            computed += result.count
            cpu[v] += result.cpu_seconds
            lab = result.labels
            progs[v].add(result.batch, Tally.of(lab["quarter_turns"], lab["status"],
                                                lab["certainty"], verified))
            pending[v][result.batch] = result
            flush(v, progs[v].prefix)
            if progs[v].done:
                pending[v].clear()
            if progress is not None:
                t = progs[v].tally
                lo, hi = wilson_arrays([t.standing], [t.n_counted])
                p = t.standing / t.n_counted if t.n_counted else math.nan
                expected = goal.samples or (
                    progs[v].samples if progs[v].done else min(
                        max(samples_needed(t, goal.precision, goal.of), progs[v].samples + size),
                        goal.batches(size) * size))
                progress(FractionsProgress(v, n_values, sum(p.done for p in progs), t.samples,
                                           (p, float(lo[0]), float(hi[0])),
                                           widest(t, goal.of), goal.precision, int(expected),
                                           computed, time.perf_counter() - wall0))
            if stop is not None and stop.is_set():
                interrupted = True
                break
        runner.close()
    except KeyboardInterrupt:
        interrupted = True
        runner.close()
    if interrupted and goal.samples is not None:  # every batch is in the final prefix
        for v in range(n_values):
            for result in sorted(pending[v].values(), key=lambda r: r.batch):
                if writer is not None:
                    writer.write(v, result.batch, result.states, result.labels)
    wall = time.perf_counter() - wall0
    if store is not None and computed:
        fstore.record_run(store, fstore.run_record(started, wall, sum(cpu), computed, mode,
                                                   n_workers, interrupted))
    total_cost = {"computed": computed, "cpu_seconds": sum(cpu), "wall_seconds": wall,
                  "trajectories_per_second": computed / wall if wall > 0 else math.nan,
                  "cpu_ms_per_trajectory": 1e3 * sum(cpu) / computed if computed else math.nan,
                  "mode": mode, "workers": n_workers}
    path = None if store is None else str(store)
    results = []
    for v, (prog, s) in enumerate(zip(progs, plan.scenes, strict=True)):
        stopped = prog.reason if prog.done else "interrupted"
        cost = total_cost if plan.parameter is None else {"cpu_seconds": cpu[v]}
        results.append(make_result(prog, sampling, s, stopped, cost, path, plan.parameter,
                                   None if plan.values is None else plan.values[v]))
    if plan.parameter is None:
        return results[0]
    return FractionsOver(plan.parameter, list(plan.values), results, plan.note, total_cost,
                         path)


def _resume(plan: FractionsPlan, progs, draws, layout, store, filled) -> None:
    """Count the batches a store holds already (each value's, in its progression), after
    checking that this installation draws the same samples as the one that wrote them."""
    from .io import fractions_store as fstore

    goal, size = plan.goal, plan.sampling.batch
    checked = False
    for v, prog in enumerate(progs):
        have = np.asarray(filled[v] if plan.parameter is not None else filled)
        batches, counts = [], []
        for index in range(min(prog.limit, have.shape[0])):
            need = goal.count(index, size)
            if need and have[index] >= need:
                batches.append(index)
                counts.append(need)
        if not batches:
            continue
        if not checked:
            index, count = batches[0], counts[0]
            drawn = initial_states(plan.scenes[v], plan.sampling, draws.batch(index)[:count])
            stored = fstore.read_initial(store, layout, v, index, count)
            if not np.array_equal(drawn[:, 1:], stored):
                raise ParameterError(f"{store}: the samples drawn here differ from the ones "
                                     "in the store (numpy or scipy changed?); --overwrite "
                                     "starts it again")
            checked = True
        labels = fstore.read_batches(store, layout, v, batches, counts)
        for index in batches:
            lab = labels[index]
            prog.add(index, Tally.of(lab["quarter_turns"], lab["status"], lab["certainty"],
                                     prog.verified))


def open_fractions(store: str | os.PathLike):
    """A `coin fractions` store as an xarray Dataset: ``initial`` ([value,] sample, ic) and the
    labels ([value,] sample); batches not written hold the fill values (``filled`` says which
    are)."""
    from .io.fractions_store import open_fractions as open_store

    return open_store(store)


def render_fractions(result: FractionsOver, out: str | os.PathLike, *,
                     title: str | None = None, dpi: int = 150) -> Path:
    """Plot P(outcome) against the parameter of a continuation, with 95 % interval bands (PNG
    or SVG by the file's suffix)."""
    from .io.fractions_plot import plot_over

    return plot_over(result, out, title=title, dpi=dpi)


__all__ = ["Fractions", "FractionsOver", "FractionsPlan", "FractionsProgress", "Method",
           "Outcome", "Status", "SweepPlan", "SweepProgress", "SweepReport", "Trajectory",
           "basin", "basin_stats", "classify", "fractions", "fractions_over", "load_preset",
           "open_basin", "open_fractions", "plan_fractions", "plan_sweep", "render_basin",
           "render_fractions", "run_fractions", "simulate", "stability", "sweep"]
