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

import contextlib
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from .enums import Certainty, Engine, Method, Status, StopReason
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
    with_mirror,
)
from .integrators import check_step, warm_up
from .integrators.batch import verified_labels
from .io.rrd import record
from .io.runner import check_where
from .montecarlo import DEFAULT_BATCH, DEFAULT_MAX_SAMPLES, Fractions, FractionsOver
from .montecarlo.plan import FractionsPlan, FractionsProgress, plan_fractions
from .params import ParameterError, Scene, check_start, require_scene, validate
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

    def __repr__(self) -> str:  # one line in a notebook; everything: .attrs
        from .integrators.ladder import describe

        g = self.grid
        axes = " x ".join(f"{a.name} {a.lo:g}:{a.hi:g} ({a.n})" for a in g.axes)
        tiles = math.prod(g.tile_grid)
        return (f"SweepPlan({axes}, {tiles} tile{'s' * (tiles != 1)}, {g.work_cells:,} of "
                f"{g.n_cells:,} cells computed, {describe(self.scene.integration)})")


def plan_sweep(scene: Scene, *, res=DEFAULT_RES, chunk=DEFAULT_CHUNK, force: bool = False,
               mirror: bool = True, **initial) -> SweepPlan:
    """Check everything about a sweep before any work: the ranges (two initial conditions
    swept, ``name=(lo, hi)`` or ``'LO:HI'``; vy and vphi sweep their defaults unless given), the
    other initial values, the resolution, the tiles, the method and its step. ``mirror``: where
    the sweep is its own mirror image, compute one tile of each mirror pair
    (:attr:`coincli.grid.Grid.mirror_flips`; the plan's ``attrs`` say which axes)."""
    from .io.schema import basin_attrs

    ranges, fixed = split_options(initial)
    scene = validate(require_scene(scene).with_overrides(**fixed))
    grid = make_grid(scene, ranges, parse_pair("res", res, 2), parse_pair("chunk", chunk, 1),
                     use_mirror=mirror)
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

    tiles_done: int  # complete tiles, including those done before this run and by others
    tiles_total: int
    cells_done: int  # cells this run has filled so far (mirror images included)
    cells_todo: int  # cells this run set out to fill
    elapsed: float  # s of wall time since this run started
    written: tuple[tuple[int, int], ...] = ()  # the tiles this update wrote (its mirror too)


@dataclass(frozen=True)
class SweepEstimate:
    """How long a sweep should take, from a pilot: a few dozen cells spread over the grid
    (always the same ones), timed one by one on this machine."""

    seconds: float  # wall time: cells x CPU s a cell / workers (CPU s if workers is None)
    cells: int  # cells to compute
    cpu_per_cell: float  # CPU s a cell, the mean over the pilot
    workers: int | None  # threads or Dask workers assumed; None: a cluster of unknown size
    pilot_cells: int  # cells timed
    at_least: bool  # a pilot cell ran out of the pilot's time: the sweep takes longer still


class SweepTooLong(ParameterError):
    """A sweep whose estimate is over the limit it was given (``max_seconds``)."""

    def __init__(self, estimate: SweepEstimate, limit: float):
        self.estimate = estimate
        self.limit = limit
        super().__init__(f"this sweep would take {'at least' if estimate.at_least else 'about'} "
                         f"{format_duration(estimate.seconds)}, over the limit of "
                         f"{format_duration(limit)}")


@dataclass(frozen=True)
class SweepStart:
    """Passed to a sweep's ``on_start`` callback once the store is open, before any work."""

    path: str
    tiles_total: int
    tiles_done: int  # complete and verified
    damaged: tuple  # tiles whose data failed their check: recomputed now
    repaired: tuple  # metadata files rewritten
    cells_todo: int
    estimate: SweepEstimate | None


@dataclass(frozen=True)
class SweepReport:
    """What one invocation of :func:`sweep` did."""

    path: str
    tiles_total: int
    tiles_done: int  # complete tiles in the store now (as far as this run saw)
    tiles_before: int  # complete tiles when this run started
    cells: int  # cells this run filled (mirror images included)
    wall_seconds: float
    mode: str  # "threads" or "dask"
    workers: int
    interrupted: bool
    tiles_computed: int = 0  # tiles this run wrote (a computed tile's mirror image included)
    tiles_elsewhere: int = 0  # tiles other processes finished while this one ran
    damaged: tuple = ()  # tiles found damaged at the start (recomputed if not interrupted)
    estimate: SweepEstimate | None = None
    kernel_seconds: float = 0.0  # wall time of the tiles in the kernels, summed over threads
    store_seconds: float = 0.0  # wall time of the tiles' writes, summed over threads
    mirrored_cells: int = 0  # of ``cells``, those written as mirror images of computed ones

    @property
    def complete(self) -> bool:
        return self.tiles_done == self.tiles_total


PILOT_CELLS = 24  # cells a pilot times
PILOT_SECONDS = 1.0  # at most this much CPU time


def pilot_cells(grid: Grid, count: int = PILOT_CELLS) -> list[tuple[int, int]]:
    """``count`` cells spread evenly over the grid (the R2 low-discrepancy sequence): always
    the same cells for the same grid."""
    g = 1.324717957244746  # the plastic number
    a0, a1 = 1 / g, 1 / g ** 2
    n0, n1 = grid.shape
    out = []
    for k in range(1, 4 * count):
        cell = (int(((0.5 + a0 * k) % 1.0) * n0), int(((0.5 + a1 * k) % 1.0) * n1))
        if cell not in out:
            out.append(cell)
        if len(out) == min(count, n0 * n1):
            break
    return out


def estimate_sweep(plan: SweepPlan, threads: int | None = None, *, workers: int | None = None,
                   scheduler: str | None = None, cells: int | None = None,
                   budget: float = PILOT_SECONDS) -> SweepEstimate:
    """Estimate the wall time of computing ``cells`` cells of ``plan`` (default: all) on
    ``threads`` threads (default one per core), ``workers`` local Dask workers, or a cluster
    (``scheduler``: the estimate is then in CPU seconds). The pilot times the cells of
    :func:`pilot_cells` (24, or a sixteenth of ``cells`` if fewer) one after another for at
    most ``budget`` CPU seconds; a cell still running then is stopped, and the estimate is a
    lower bound (``at_least``)."""
    import threading

    from .enums import Status
    from .integrators.batch import new_control
    from .io.runner import usable_cores

    grid, spec = plan.grid, plan.spec
    cells = grid.work_cells if cells is None else int(cells)
    cores = usable_cores()
    n = None if scheduler is not None else min(workers or threads or cores, cores)
    _load_kernels(spec)
    c0, c1 = grid.axes[0].coords, grid.axes[1].coords
    base = np.asarray(grid.base_state, dtype=np.float64)
    control = new_control()
    timer = threading.Timer(budget, control.__setitem__, (0, 1))
    timer.daemon = True
    timer.start()
    cpu, timed, at_least = 0.0, 0, False
    try:
        # a few dozen cells, but never more than a sixteenth of the sweep
        for i, j in pilot_cells(grid, min(PILOT_CELLS, max(1, cells // 16))):
            state = base.copy()
            state[grid.axes[0].index] = c0[i]
            state[grid.axes[1].index] = c1[j]
            before = time.thread_time()
            out = verified_labels(spec.params, spec.settings, spec.ladder, state[None, :],
                                  control)
            cpu += time.thread_time() - before
            timed += 1
            if out.status[0] == Status.INTERRUPTED:
                at_least = True
                break
            if cpu >= budget:
                break
    finally:
        timer.cancel()
    per_cell = cpu / max(timed, 1)  # with a cell stopped short: a lower bound
    return SweepEstimate(per_cell * cells / (n or 1), cells, per_cell, n, timed, at_least)


def format_duration(seconds: float) -> str:
    """'40 s', '12 min', '3.5 h', '9.3 days', '2.1 years'."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    if seconds < 48 * 3600:
        return f"{seconds / 3600:.1f} h"
    if seconds < 730 * 86400:
        return f"{seconds / 86400:.1f} days"
    return f"{seconds / (365.25 * 86400):.1f} years"


def sweep(plan: SweepPlan, store: str | os.PathLike, *, overwrite: bool = False,
          threads: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: Callable[[SweepProgress], None] | None = None, stop=None,
          max_seconds: float | None = None,
          on_start: Callable[[SweepStart], None] | None = None) -> SweepReport:
    """Compute the tiles of ``plan`` that ``store`` does not hold yet (creating it if needed),
    on ``threads`` threads (default: one per core) or on Dask (``workers`` local processes, or
    the cluster at ``scheduler``).

    Tiles already in the store are checked first: a damaged one (a chunk that does not read
    back, or data that do not match the tile's digest) is recomputed like a missing one.
    Several processes (here or on other machines sharing the store) may run the same sweep at
    once: each claims a tile before computing it, and returns only once every tile is done,
    whoever computed it. ``stop`` (anything with ``is_set()``, e.g. a threading.Event) asks it
    to finish the tiles in flight and return; KeyboardInterrupt (Ctrl-C, a notebook's
    interrupt) stops the tiles in flight at once, unwritten, and returns too (``interrupted``).

    ``on_start`` receives a :class:`SweepStart` (damaged tiles, the estimate) before any work;
    with ``max_seconds`` or ``on_start`` the sweep is first estimated (:func:`estimate_sweep`)
    and, over ``max_seconds``, refused with :class:`SweepTooLong` before anything is created.
    A store with other parameters is refused (ParameterError naming them) unless
    ``overwrite``. OSErrors (a read-only or full disk) are raised as they come; a store or
    output that cannot be written is found before any work."""
    from .io import store as store_io
    from .io.claims import Claims, TileQueue
    from .io.runner import (
        SchedulerLost,
        hard_stop,
        run_dask,
        run_threads,
        run_tile_task,
        usable_cores,
    )
    from .io.schema import parameters_digest

    check_where(threads, workers, scheduler)
    _check_progress(progress)
    started = time.time()
    path = Path(store)
    spec, grid = plan.spec, plan.grid
    store_io.check_store_writable(path)
    dask = scheduler is not None or workers is not None
    where = dict(threads=threads, workers=workers, scheduler=scheduler)
    want_estimate = max_seconds is not None or on_start is not None
    fresh = overwrite or not store_io.is_store(path)
    estimate = None
    if fresh and want_estimate:  # refuse before creating anything
        estimate = estimate_sweep(plan, **where)
        if max_seconds is not None and estimate.seconds > max_seconds:
            raise SweepTooLong(estimate, max_seconds)
    state = store_io.prepare(path, plan.attrs, spec, overwrite=overwrite)
    todo = [t for t in spec.work_order() if not all(state.done[u] for u in grid.task_tiles(t))]
    total = len(grid.tiles())
    before = total - sum(len(grid.task_tiles(t)) for t in todo)
    cells_todo = sum(grid.tile_cells(u) for t in todo for u in grid.task_tiles(t))
    if not fresh and want_estimate and todo:
        estimate = estimate_sweep(plan, **where, cells=sum(grid.tile_cells(t) for t in todo))
        if max_seconds is not None and estimate.seconds > max_seconds:
            raise SweepTooLong(estimate, max_seconds)
    damaged = tuple(sorted(state.damaged))
    if on_start is not None:
        on_start(SweepStart(str(path), total, before, damaged, tuple(state.repaired),
                            cells_todo, estimate if todo else None))
    if dask:
        mode, n_workers = "dask", workers or 0
    else:
        mode, n_workers = "threads", threads or usable_cores()
    if not todo:
        return SweepReport(str(path), total, total, total, 0, 0.0, mode, n_workers, False,
                           damaged=damaged, estimate=estimate)
    def is_done(tile) -> bool:  # by another process, since the check above
        return all(store_io.tile_done(path, u, grid) if u in state.damaged  # check the data
                   else store_io.has_digest(path, u) for u in grid.task_tiles(tile))

    def tiles_elsewhere() -> int:
        return sum(len(grid.task_tiles(t)) for t in queue.done_elsewhere)

    claims = Claims(store_io.claims_dir(path))
    queue = TileQueue(todo, claims, is_done=is_done)
    cluster_workers: list[int] = []  # the Dask cluster's workers, each time it was looked at
    # every tile binds the parameters it is computed with, whatever the store's metadata say
    # when it is written (another process may have overwritten the store meanwhile: its tiles
    # then do not verify there, and are computed again)
    parameters = parameters_digest(plan.attrs)
    if dask:
        # workers open the store by this path: make it absolute (same path on every machine)
        runner = run_dask(str(path.resolve()), spec, queue, scheduler=scheduler,
                          workers=workers, stop=stop, on_workers=cluster_workers.append,
                          parameters=parameters)
    else:
        _load_kernels(spec)
        runner = run_threads(partial(run_tile_task, str(path), spec, parameters=parameters),
                             queue, n_workers, stop)
    wall0 = time.perf_counter()
    interrupted = False
    lost = None
    computed = cells = mirrored = 0
    kernel_seconds = store_seconds = 0.0
    try:
        for done in runner:
            kernel_seconds += done.compute_seconds
            store_seconds += done.write_seconds
            if done.written:
                computed += done.tiles
                cells += done.cells
                mirrored += done.cells - grid.tile_cells(done.tile)
            if progress is not None:
                progress(SweepProgress(before + computed + tiles_elsewhere(), total,
                                       cells, cells_todo, time.perf_counter() - wall0,
                                       grid.task_tiles(done.tile) if done.written else ()))
    except KeyboardInterrupt:
        interrupted = True
        hard_stop(runner)  # the tiles in flight stop now, unwritten
    except SchedulerLost as exc:  # raised once the run is recorded: the store keeps its tiles
        lost = exc
    finally:
        claims.close()
    n_workers = max(cluster_workers, default=n_workers)
    interrupted = interrupted or not queue.finished or (stop is not None and stop.is_set())
    wall = time.perf_counter() - wall0
    elsewhere = tiles_elsewhere()
    n_done = total if not interrupted else before + computed + elsewhere
    interrupted = interrupted and n_done < total  # a stop that came after the last tile
    with contextlib.suppress(OSError):  # a cost record lost is no reason to fail a sweep
        store_io.record_run(path, store_io.run_record(
            started, wall, computed, cells, mode, n_workers, interrupted,
            kernel_seconds=kernel_seconds, store_seconds=store_seconds))
    if lost is not None:
        raise lost
    return SweepReport(str(path), total, n_done, before, cells, wall, mode, n_workers,
                       interrupted, computed, elsewhere, damaged, estimate, kernel_seconds,
                       store_seconds, mirrored)


def basin(scene: Scene, *, res=DEFAULT_RES, chunk=DEFAULT_CHUNK, store: str | os.PathLike |
          None = None, overwrite: bool = False, force: bool = False,
          threads: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: Callable[[SweepProgress], None] | None = None, stop=None,
          mirror: bool = True, x0=None, y0=None, phi0=None, vx=None, vy=None, vphi=None,
          rrd: str | os.PathLike | None = None, spawn: bool = False, connect: str | None = None,
          notebook=False):
    """The basin map of two initial conditions as an xarray Dataset.

    Swept axes are given as ``name=(lo, hi)`` (vy and vphi sweep (0.05, 2) m/s and (-20, 20)
    rad/s unless given); a plain number fixes a value. ``res`` cells per axis (N or (N, M)),
    tiles of ``chunk`` cells (where the sweep is its own mirror image, one tile of each mirror
    pair is computed and the other mirrored, unless ``mirror=False``: see
    :attr:`coincli.grid.Grid.mirror_flips`). Without ``store`` the map is computed in memory and
    returned; with ``store`` it is computed into (or resumed from) that Zarr store, the same
    store ``coin basin`` writes, and the store is returned opened. Every label is verified (see
    coincli.integrators.ladder) unless the scene's integration says ``verify=False``
    (``scene.with_overrides(verify=False)``). Interrupted (``stop`` set, or Ctrl-C, which stops
    the tiles in flight at once), it raises KeyboardInterrupt; a store keeps every finished
    tile for a resume.

    ``rrd`` (an .rrd file), ``spawn`` (a new viewer) and ``connect`` (a running viewer's URL,
    ``rerun+http://host:port/proxy``) stream the map to Rerun as it fills in, as
    `coin basin STORE --rrd FILE` does; in a notebook, ``notebook`` (alone): a viewer of
    :func:`viewer` shown in an earlier cell, which fills in live, or True, a viewer in this
    cell that shows the map once the cell has run. The recording reads the tiles back from the
    store, so it needs ``store``. A recording that fails (a full disk, a viewer gone) does not
    fail the sweep: it is said in a RuntimeWarning."""
    _check_progress(progress)
    plan = plan_sweep(scene, res=res, chunk=chunk, force=force, mirror=mirror, x0=x0, y0=y0,
                      phi0=phi0, vx=vx, vy=vy, vphi=vphi)
    where = _live(rrd, spawn, connect, notebook)
    if where is not None and store is None:
        raise ParameterError("a live recording of a sweep reads its tiles from the store: give "
                             "store=PATH")
    if store is not None:
        with _recording_sweep(plan, store, where, progress) as (_, progress):
            report = sweep(plan, store, overwrite=overwrite, threads=threads, workers=workers,
                           scheduler=scheduler, progress=progress, stop=stop)
        if report.interrupted:
            raise KeyboardInterrupt(f"sweep interrupted: {report.tiles_done} of "
                                    f"{report.tiles_total} tiles are in {report.path}")
        return open_basin(store)
    if workers is not None or scheduler is not None:
        raise ParameterError("a sweep on Dask writes its tiles to a store: give store=PATH")
    return _basin_in_memory(plan, threads, progress, stop)


def _live(rrd, spawn: bool, connect, notebook=False):
    """The checked destination of a live recording (None if none is asked for)."""
    if rrd is None and not spawn and connect is None and notebook is False:
        return None  # Rerun's code is not even imported
    from .io.live import check_destination

    return check_destination(rrd, spawn, connect, notebook)


def _both(first, second):
    """A callback calling ``first`` then ``second`` with the same arguments (either may be
    None)."""
    if first is None or second is None:
        return first or second
    return lambda *args: (first(*args), second(*args))


def _warn_if_failed(recorder) -> None:
    """A RuntimeWarning if ``recorder``'s recording failed, attributed to the caller's line
    (the first frame outside this package: the API is called from several depths)."""
    if recorder is None or recorder.error is None:
        return
    import inspect
    import warnings

    from .io.paths import explain

    package = str(Path(__file__).parent)
    frames = inspect.stack(context=0)
    level = next((i for i, frame in enumerate(frames)
                  if not frame.filename.startswith(package)
                  and Path(frame.filename).name != "contextlib.py"), len(frames))
    warnings.warn(f"the live recording failed: {explain(recorder.error)}", RuntimeWarning,
                  stacklevel=level + 1)


@contextlib.contextmanager
def _recording_sweep(plan: SweepPlan, store, where, progress):
    """(the recorder or None, the progress callback to give the sweep): the live recording of
    a sweep into ``store`` at ``where``, if any: by a process of its own
    (:mod:`coincli.io.sweep_recording`), or in this one for a notebook's viewer; a failed
    recording is warned of once the sweep is done."""
    if where is None:
        yield None, progress
        return
    verified = plan.spec.ladder.verified
    if where.notebook is not False:  # a notebook's viewer belongs to this process
        from .io.live import InlineSweep

        recorder = InlineSweep(store, plan.attrs, where, verified=verified)
    else:
        from .io.sweep_recording import SweepRecorder

        recorder = SweepRecorder().start().record(store, plan.attrs, where, verified=verified)
    with recorder:
        yield recorder, _both(progress, recorder.progress)
    _warn_if_failed(recorder)


def _basin_in_memory(plan: SweepPlan, threads, progress, stop):
    from .io.claims import TileQueue
    from .io.dataset import Basin, to_dataset
    from .io.runner import hard_stop, run_threads, usable_cores
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
    runner = run_threads(partial(compute_tile, spec), TileQueue(spec.work_order()),
                         threads or usable_cores(), stop)
    try:
        for computed in runner:
            for result in with_mirror(computed, grid):
                s0, s1 = grid.tile_slices(result.tile)
                for name, block in result.arrays.items():
                    arrays[name][s0, s1] = block
                done[result.tile] = 1
                seconds[result.tile] = result.cpu_seconds
                cells += result.cells
            if progress is not None:
                progress(SweepProgress(int(done.sum()), len(tiles), cells, grid.n_cells,
                                       time.perf_counter() - wall0,
                                       grid.task_tiles(computed.tile)))
    except KeyboardInterrupt:
        hard_stop(runner)
        raise
    if not done.all():
        raise KeyboardInterrupt("sweep interrupted")
    run = {"wall_seconds": round(time.perf_counter() - wall0, 3), "tiles": len(tiles),
           "cells": cells, "mode": "threads", "workers": threads or usable_cores(),
           "interrupted": False}
    return to_dataset(Basin(attrs=plan.attrs, arrays=arrays, done=done, tile_seconds=seconds,
                            runs=[run]))


def _check_progress(progress) -> None:
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be a function (or None), got {type(progress).__name__}")


def _load_kernels(spec: SweepSpec) -> None:
    """Load the compiled kernels before the clock starts (and before the threads race to)."""
    warm_up(spec.params, spec.settings, np.asarray(spec.grid.base_state, dtype=np.float64),
            (verified_labels,))


def compile_kernels() -> bool:
    """Compile every kernel for this machine now, unless this version is compiled here already
    (:func:`coincli.jit.kernels_cached`): what the first run of any of them would do, in about
    ``coincli.jit.FIRST_COMPILE_SECONDS``. Whatever the scene, the kernels take the same
    argument types, so the default scene's compile serves every later one. True if it
    compiled. Silent: a caller that wants to show the wait does (``coin compile``)."""
    from . import jit
    from .params import model_params, run_settings

    if jit.kernels_cached():
        return False
    scene = Scene()
    warm_up(model_params(scene), run_settings(scene.integration),
            np.array([0.0, scene.y0, 0.0, 0.0, 1.0, 3.0]))
    return True


def open_basin(store: str | os.PathLike):
    """A basin store (or a NetCDF file of :func:`export_basin`) as an xarray Dataset, in
    memory; every tile of a store checked: cells of unfinished or damaged tiles read as not
    computed (the damaged tiles are listed in the attribute ``damaged_tiles``).

    The variables are on the two swept axes, first swept axis first (``ds.dims``); ``done``
    and ``tile_cpu_seconds`` per tile. Missing labels, on every route (this function,
    :func:`basin`, ``xarray.open_zarr`` of a store, ``xarray.open_dataset`` of an export):
    ``quarter_turns`` is float32, NaN where a cell has no label (not computed or non-finite),
    and ``status`` says why (``coincli.Status.NOT_COMPUTED``...); on disk it is int16 with
    ``missing_value`` -32768, which ``mask_and_scale=False`` shows. ``settle_time`` is NaN and
    ``steps`` and ``rung`` -1 where not computed.

    Attributes that are not strings or numbers (parameters, sweep, method, runs,
    damaged_tiles...) are JSON text, so that ``ds.to_netcdf("m.nc")`` works;
    :func:`basin_attrs` gives them decoded (``basin_attrs(ds)["parameters"]["coin"]``).

    Plotting: :func:`render_basin` draws the first swept axis horizontally (as the paper);
    xarray's ``ds.quarter_turns.plot()`` puts the first dimension on the vertical axis, so
    ``ds.quarter_turns.plot(x=ds.quarter_turns.dims[0])`` (``x="vy"``) draws it as render
    does."""
    from .io.dataset import to_dataset

    return to_dataset(_read_basin(store))


def _read_basin(path):
    """The Basin of a store, or of a NetCDF export (a file)."""
    from .io.export import read_export
    from .io.store import read_basin

    if Path(path).is_file():
        return read_export(path)
    return read_basin(path)


def export_basin(basin, path: str | os.PathLike) -> Path:
    """Write a basin (Dataset or store path) to ``path``: NetCDF-4 (``.nc``: every variable
    and attribute, as :func:`open_basin` gives them; ``xarray.open_dataset`` or
    :func:`open_basin` reads it back) or CSV (``.csv``: one row per cell, the two swept
    coordinates, n, pose, status, certainty, settle_time, steps, rung, header names with
    units, empty fields where a value is missing). An existing file is replaced; the file is
    complete or absent. Returns the path."""
    from .io.export import check_export_path
    from .io.export import export_basin as export

    path = check_export_path(path)
    return export(_as_basin(basin), path)


def basin_attrs(basin) -> dict:
    """The attributes of a basin (Dataset, store path or NetCDF export) as plain nested
    values: parameters, sweep, method, version, coin_basin and, of a Dataset, runs,
    damaged_tiles, store. A Dataset holds the nested ones as JSON text (NetCDF has no nested
    attributes); this decodes them, whichever route the Dataset came by."""
    from .io.dataset import decoded_attrs
    from .io.export import open_export
    from .io.store import open_view

    if isinstance(basin, str | os.PathLike):
        if Path(basin).is_file():
            return decoded_attrs(open_export(basin))
        return dict(open_view(basin).attrs)
    return decoded_attrs(basin)


def cell_scene(basin, *, cell=None, **values) -> Scene:
    """The Scene of one cell of a basin (Dataset or store path): the basin's parameters with
    the cell's initial state exactly as the sweep gave it, so that ``simulate`` replays the
    throw the map shows (the label comes out the same). The cell nearest to ``values`` of
    both swept axes (``vy=1.2, vphi=3.5``), or ``cell=(i, j)`` by index."""
    from .io.cells import cell_scene as scene_of
    from .io.cells import locate
    from .io.store import open_view

    if isinstance(basin, str | os.PathLike):
        attrs = open_view(basin).attrs
    else:
        attrs = _as_basin(basin).attrs
    return scene_of(attrs, locate(attrs, cell=cell, **values))


def verify_basin(store: str | os.PathLike):
    """Check a store without computing anything: every tile's chunks (checksums) against its
    digest, and every metadata file (a :class:`coincli.io.store.StoreCheck`: ``intact``,
    ``damaged`` tiles with the reason, ``done`` tiles)."""
    from .io.store import check

    return check(store)


def _as_basin(basin):
    """A Basin view of a Dataset, of a store path (or NetCDF export), or of a Basin."""
    from .io.dataset import Basin, from_dataset

    if isinstance(basin, Basin):
        return basin
    if isinstance(basin, str | os.PathLike):
        return _read_basin(basin)
    return from_dataset(basin)


def _tiles(done: np.ndarray, damaged) -> dict:
    return {"tiles_total": int(done.size), "tiles_done": int(np.count_nonzero(done)),
            "tiles_damaged": [list(map(int, t)) for t in sorted(damaged)]}


def basin_stats(basin) -> dict:
    """Outcome counts and fractions, P(standing) with its 95 % Wilson interval, the cells
    without a label, the certain and uncertain cells of a verified sweep with the outcome
    probabilities over the certain ones, the tiles (done, damaged) and the cost, of a Dataset or
    a store path (plain values, ready for ``json.dumps``, a value that cannot be known None:
    ``coin basin stats --json`` prints this). A store is read one tile at a time, each
    checked, so memory stays flat at any resolution; damaged tiles count as not computed."""
    from .jsonable import jsonable

    if isinstance(basin, str | os.PathLike):
        return jsonable(_store_stats(basin))
    return jsonable(_dataset_stats(basin))


def _dataset_stats(basin) -> dict:
    from .stats import BasinCounts, cost_summary

    view = _as_basin(basin)
    a = view.arrays
    counts = BasinCounts()
    counts.add(a["quarter_turns"], a["status"], a["certainty"])
    out = counts.summary()
    out.update(_tiles(view.done, view.damaged))
    out["cost"] = cost_summary(out["computed"], view.tile_seconds, view.done, view.runs)
    out["metadata_damaged"], out["parameters_changed"] = [], []  # a store's, checked on reading
    out["warnings"] = _stats_warnings(out)
    return out


def _store_stats(path) -> dict:
    from .io.store import Tile, damaged_metadata, open_view, read_costs, scan
    from .stats import BasinCounts, cost_summary

    view = open_view(path)
    grid = view.grid
    counts = BasinCounts()
    done = np.zeros(grid.tile_grid, np.uint8)
    damaged = []
    for tile, state, data, _ in scan(view, with_data=True):
        if state is Tile.DONE:
            counts.add(data["quarter_turns"], data["status"], data["certainty"])
            done[tile] = 1
        else:
            counts.add_not_computed(grid.tile_cells(tile))
            if state is Tile.DAMAGED:
                damaged.append(tile)
    out = counts.summary()
    out.update(_tiles(done, damaged))
    seconds, runs = read_costs(view.path, grid.tile_grid)
    out["cost"] = cost_summary(out["computed"], seconds, done, runs)
    out["metadata_damaged"] = damaged_metadata(view)
    out["parameters_changed"] = list(view.problems)
    out["warnings"] = _stats_warnings(out)
    return out


def _stats_warnings(stats: dict) -> list[str]:
    """What the numbers of a basin's statistics do not say: a partial store's fractions are of
    the tiles computed so far, which are no random sample of the map (a sweep computes the
    highest-energy tiles first); changed parameters and damaged metadata (what verifying the
    store finds)."""
    out = []
    done, total = stats["tiles_done"], stats["tiles_total"]
    if done < total:
        out.append(f"partial store: {done} of {total} tiles computed "
                   f"({100 * done / total:.1f} %); the fractions and intervals are over the "
                   "computed cells only, which are no random sample of the map: they need not "
                   "hold for the whole map")
    out += [f"parameters changed in {problem}" for problem in stats.get("parameters_changed", [])]
    metadata = stats.get("metadata_damaged", [])
    if metadata:
        out.append(f"{len(metadata)} metadata file{'s' if len(metadata) > 1 else ''} damaged "
                   f"({', '.join(metadata[:4])}{' ...' if len(metadata) > 4 else ''}): "
                   "verifying the store lists them, resuming the sweep rewrites them")
    return out


def render_basin(basin, out: str | os.PathLike | None = None, *, ax=None, field: str = "n",
                 title: str | None = None, dpi: int = 150, n_max: int | None = None, marks=()):
    """Draw a basin (Dataset or store path) and return the matplotlib Figure: the count n in
    the paper's colours (``field="n"``; colour scale fixed to |n| <= ``n_max``, 24 by
    default) or the time each outcome was decided (``field="settle_time"``), the first swept
    axis horizontal. ``ax``: a matplotlib Axes to draw into (its colour bar takes room from
    it alone: ``fig, (a, b) = plt.subplots(1, 2, layout="constrained")`` then one map into
    each); without it, a new Figure. ``out``: also write the figure to a PNG, SVG or PDF (by
    the extension). ``marks``: throws to mark on the map, (value of the first swept axis,
    value of the second) pairs, each a white circle with a black edge (:func:`cell_scene`
    gives the Scene of one)."""
    from .io.basin_render import render_map

    try:
        return render_map(_as_basin(basin), out, title=title, dpi=dpi, n_max=n_max,
                          field=field, marks=marks, ax=ax)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None


def viewer(*, width: int | None = None, height: int | None = None):
    """A Rerun viewer shown in the notebook's cell now (``width`` and ``height`` in pixels),
    for the work of later cells: ``coincli.basin(..., store=..., notebook=v)``,
    ``fractions(..., notebook=v)``, ``analyze(..., notebook=v)``, ``show_basin(ds,
    notebook=v)`` show in it as they run (a viewer made in the cell that runs the work is
    ready only once the cell has run: Jupyter hands the kernel its "ready" between cells)."""
    from .io.rrd import notebook_viewer

    return notebook_viewer(width=width, height=height)


def show_basin(basin, *, rrd: str | os.PathLike | None = None, spawn: bool = False,
               connect: str | None = None, notebook=False) -> None:
    """A basin (Dataset or store path, finished or partial) in Rerun's viewer, as
    `coin basin show`: n in the paper's colours, each class named, the uncertain, undecided,
    unsettled and non-finite cells over it, cells not computed (or damaged) marked; to the
    .rrd file ``rrd``, a new viewer (``spawn``) and/or a running one (``connect``), or alone
    in the notebook's cell (``notebook``)."""
    from .io.live import show_basin as show

    where = _live(rrd, spawn, connect, notebook)
    if where is None:
        raise ParameterError("show_basin() needs a destination: rrd=PATH, spawn=True, "
                             "connect=URL or notebook=True")
    show(_as_basin(basin), where)


# -- boundaries ---------------------------------------------------------------------------------
def analyze(basin, *, box: int = 5, bands: int = 4, points: int | None = None,
            eps: tuple[float, ...] | None = None, seed: int = 0, threads: int | None = None,
            radius: float = 5.0, balls: int = 1000, max_dilation: int = 6,
            direction: str = "random", confidence: float = 0.95,
            progress: Callable[[str, int, int], None] | None = None, stop=None,
            on_band: Callable | None = None, rrd: str | os.PathLike | None = None,
            spawn: bool = False, connect: str | None = None, notebook=False):
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
    ``on_band(index, rows, f)`` as each band's f(eps) (a
    :class:`coincli.boundary.UncertainFraction`) is measured, ``rows`` its first row and the
    one past its last along the first axis;
    ``stop`` (an Event) or Ctrl-C interrupts it (KeyboardInterrupt). ``rrd``, ``spawn`` and
    ``connect`` (or ``notebook``, alone: in the notebook's cell, shown once the cell ends)
    record it for Rerun as it goes (as `coin basin analyze --rrd FILE`): the map
    with its bands, each band's f(eps) as it is measured, the fits and the measures; a
    recording that fails is a RuntimeWarning, the analysis is returned all the same."""
    from .analysis import DEFAULT_POINTS, AnalysisOptions, analyze_basin
    from .io.runner import usable_cores

    _check_progress(progress)
    where = _live(rrd, spawn, connect, notebook)
    view = _as_basin(basin)
    opts = AnalysisOptions(box=int(box), bands=int(bands),
                           points=DEFAULT_POINTS if points is None else int(points),
                           seed=int(seed), threads=int(threads or usable_cores()),
                           radius=float(radius), balls=int(balls),
                           max_dilation=int(max_dilation), direction=direction,
                           confidence=float(confidence),
                           **({} if eps is None else {"eps": tuple(float(e) for e in eps)}))
    a = view.arrays
    if on_band is not None and not callable(on_band):
        raise TypeError(f"on_band must be a function (or None), got {type(on_band).__name__}")
    if where is None:
        return analyze_basin(a["quarter_turns"], a["status"], a["certainty"], view.attrs,
                             options=opts, progress=progress, on_band=on_band, stop=stop)
    from .io.live import AnalysisRecorder

    with AnalysisRecorder(view, where, bands=opts.bands, eps=opts.eps) as recorder:
        result = analyze_basin(a["quarter_turns"], a["status"], a["certainty"], view.attrs,
                               options=opts, progress=progress,
                               on_band=_both(on_band, recorder.band), stop=stop)
        recorder.result(result)
    _warn_if_failed(recorder)
    return result


def render_analysis(analysis, out: str | os.PathLike | None = None, *, ax=None,
                    panels=("fractions", "entropy", "alpha"), title: str | None = None,
                    dpi: int = 150):
    """Draw an analysis (of :func:`analyze`) and return the matplotlib Figure: the panels
    "fractions" (f(eps) on log-log axes with the fits), "entropy" (S_b and S_bb by band) and
    "alpha" (alpha by band), side by side in a new Figure, or into ``ax`` (one Axes a panel:
    ``render_analysis(a, ax=ax, panels=["alpha"])``). ``out``: also write it to a PNG, SVG
    or PDF (by the extension)."""
    from .io.analysis_charts import plot_analysis

    try:
        return plot_analysis(analysis, None if out is None else Path(out), title=title,
                             dpi=dpi, ax=ax, panels=panels)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None


# -- outcome probabilities (coin fractions) -----------------------------------------------------
def fractions(scene: Scene, *, y0=None, phi0=None, vx=None, vy=None, vphi=None,
              samples: int | None = None, precision: float | None = None, of: str = "all",
              max_samples: int = DEFAULT_MAX_SAMPLES, seed: int = 0, sampler: str = "sobol",
              batch: int = DEFAULT_BATCH, store: str | os.PathLike | None = None,
              overwrite: bool = False, threads: int | None = None, workers: int | None = None,
              scheduler: str | None = None, force: bool = False,
              progress: Callable[[FractionsProgress], None] | None = None,
              stop=None, rrd: str | os.PathLike | None = None, spawn: bool = False,
              connect: str | None = None, notebook=False) -> Fractions:
    """The outcome probabilities of throws whose initial conditions are drawn at random.

    Each of ``y0, phi0, vx, vy, vphi`` is a fixed value, a uniform range ``(lo, hi)`` or
    ``'LO:HI'``, a ``'normal(MEAN,SD)'`` (truncated: ``'normal(MEAN,SD,LO,HI)'``), or a
    :class:`coincli.montecarlo.Dist`; numbers may be written ``'2pi'``, ``'pi/2'``, and y0 in
    multiples of the coin's half diagonal, ``'r:5r'``. Not given: the scene's values, except
    vy and vphi, drawn over coin basin's default ranges. Samples are scrambled Sobol points
    (``sampler='sobol'``) or independent draws (``'random'``), reproducible from ``seed``.

    Runs batches of ``batch`` samples on ``threads`` threads (or on Dask: ``workers``,
    ``scheduler``) until the 95 % interval of every probability has half-width <= ``precision``
    (``of='standing'``: of P(standing) only), or ``max_samples`` are spent; ``samples`` fixes
    the count instead (``max_samples`` is spent in whole batches). With ``store`` the samples
    and labels are kept in (and resumed from) that Zarr store. Setting ``stop`` (a
    threading.Event) ends the run early with what it has: the result then says
    ``stopped=StopReason.INTERRUPTED``. Ctrl-C (a notebook's interrupt) raises
    KeyboardInterrupt, as it does in :func:`basin`; a store keeps every batch counted so far
    for a resume. ``rrd``, ``spawn`` and ``connect`` stream the running estimates to Rerun
    (as `coin fractions --rrd FILE`; see :func:`run_fractions`). Returns a
    :class:`coincli.montecarlo.Fractions`."""
    plan = plan_fractions(scene, y0=y0, phi0=phi0, vx=vx, vy=vy, vphi=vphi, samples=samples,
                          precision=precision, of=of, max_samples=max_samples, seed=seed,
                          sampler=sampler, batch=batch, force=force)
    return _raise_if_interrupted(
        run_fractions(plan, store=store, overwrite=overwrite, threads=threads,
                      workers=workers, scheduler=scheduler, progress=progress, stop=stop,
                      rrd=rrd, spawn=spawn, connect=connect, notebook=notebook), stop)


def _raise_if_interrupted(result, stop):
    """KeyboardInterrupt for a run that Ctrl-C (not ``stop``) cut short; else the result."""
    if not result.interrupted or (stop is not None and stop.is_set()):
        return result
    runs = result.results if isinstance(result, FractionsOver) else [result]
    done = sum(r.samples for r in runs)
    kept = f"; {result.store} keeps them for a resume" if result.store else ""
    raise KeyboardInterrupt(f"fractions interrupted after {done:,} samples{kept}")


def fractions_over(scene: Scene, parameter: str, values, *, keep=(), **options) -> FractionsOver:
    """The outcome probabilities at each of ``values`` of one physical ``parameter``
    (thickness, diameter, k, c, mass, inertia, g), the same sample points at every value
    (common random numbers). For thickness and diameter the mass and inertia follow a uniform
    solid disc of the scene's density, except those named in ``keep`` (the result's ``note``
    says which). Options are those of :func:`fractions` (Ctrl-C and ``stop`` as there); each
    value is resumable on its own in the store. Returns a
    :class:`coincli.montecarlo.FractionsOver`."""
    run_options = {k: options.pop(k) for k in ("store", "overwrite", "threads", "workers",
                                               "scheduler", "progress", "stop", "rrd",
                                               "spawn", "connect", "notebook")
                   if k in options}
    plan = plan_fractions(scene, over=(parameter, values), keep=keep, **options)
    return _raise_if_interrupted(run_fractions(plan, **run_options), run_options.get("stop"))


def run_fractions(plan: FractionsPlan, *, store: str | os.PathLike | None = None,
                  overwrite: bool = False, threads: int | None = None,
                  workers: int | None = None, scheduler: str | None = None,
                  progress: Callable[[FractionsProgress], None] | None = None,
                  stop=None, rrd: str | os.PathLike | None = None, spawn: bool = False,
                  connect: str | None = None, notebook=False
                  ) -> Fractions | FractionsOver:
    """Run a Monte Carlo run planned by :func:`plan_fractions` (see :func:`fractions` for the
    options): a Fractions for a plain run, a FractionsOver for a continuation. Unlike
    :func:`fractions`, it does not raise on Ctrl-C: it returns what it has, with
    ``stopped=StopReason.INTERRUPTED`` (as :func:`sweep` returns a report).

    ``rrd`` (an .rrd file), ``spawn`` (a new viewer) and ``connect`` (a running viewer's URL)
    stream the estimates to Rerun as the run goes, as `coin fractions --rrd FILE` does
    (``notebook``, alone: in the notebook's cell, shown once the cell ends): each
    probability with its 95 % band against the samples, or, over a parameter, against the
    parameter as each value finishes. A recording that fails does not fail the run: it is
    said in a RuntimeWarning."""
    from .io.fractions_run import run_fractions as run

    _check_progress(progress)
    where = _live(rrd, spawn, connect, notebook)
    if where is None:
        return run(plan, store=store, overwrite=overwrite, threads=threads, workers=workers,
                   scheduler=scheduler, progress=progress, stop=stop)
    from .io.live import FractionsRecorder

    with FractionsRecorder(plan, where) as recorder:
        result = run(plan, store=store, overwrite=overwrite, threads=threads,
                     workers=workers, scheduler=scheduler,
                     progress=_both(progress, recorder.progress), stop=stop)
        recorder.result(result)
    _warn_if_failed(recorder)
    return result


def estimate_fractions(plan: FractionsPlan, *, threads: int | None = None,
                       workers: int | None = None, scheduler: str | None = None,
                       store: str | os.PathLike | None = None):
    """How long a planned run should take and how many samples its stop rule likely needs,
    from a pilot of a few hundred samples (timed on this machine): a
    :class:`coincli.montecarlo.estimate.FractionsEstimate` (``budget_suffices`` says whether
    the sample budget covers a precision goal). On ``threads`` threads (default one per core),
    ``workers`` Dask workers, or a cluster (``scheduler``: the estimate is then CPU time);
    samples that ``store`` holds already are not counted."""
    from .io.runner import usable_cores
    from .montecarlo.estimate import estimate_fractions as estimate

    check_where(threads, workers, scheduler)
    n = None if scheduler is not None else workers or min(threads or usable_cores(),
                                                          usable_cores())
    held = None
    if store is not None and Path(store).is_dir():
        held = _held_samples(plan, store)
    return estimate(plan, n, held)


def _held_samples(plan: FractionsPlan, store) -> list[int] | None:
    """The samples of this run a fractions store holds, per value (None if it holds another
    run): those of the batches the run can use that are whole in the store (a batch missing
    or cut short is to compute, whatever the store holds beyond the run)."""
    from .io import fractions_store as fstore

    try:
        filled = fstore.read_filled(store)
        stored = dict(fstore.open_attrs(store))
    except Exception:  # noqa: BLE001 - an unreadable store is the run's to report
        return None
    if fstore.differences(stored, plan.attrs):
        return None
    rows = filled.reshape(len(plan.scenes), -1) if plan.parameter is not None else filled[None]
    goal, batch = plan.goal, plan.sampling.batch
    uses = [goal.count(b, batch) for b in range(goal.batches(batch))]
    return [sum(n for n, held in zip(uses, row, strict=False) if held >= n) for row in rows]


def open_fractions(store: str | os.PathLike):
    """A `coin fractions` store as an xarray Dataset: ``initial`` ([value,] sample, ic) and the
    labels ([value,] sample); batches not written hold the fill values (``filled`` says which
    are)."""
    from .io.fractions_store import open_fractions as open_store

    return open_store(store)


def render_fractions(result: FractionsOver, out: str | os.PathLike | None = None, *, ax=None,
                     panels=("standing", "outcomes"), title: str | None = None,
                     dpi: int = 150):
    """Plot P(outcome) against the parameter of a continuation, with 95 % interval bands, and
    return the matplotlib Figure: the panels "standing" (P(standing) and the uncertain
    fraction) and "outcomes" (P(n) of the most probable n), stacked in a new Figure, or into
    ``ax`` (one Axes a panel). ``out``: also write it to a PNG, SVG or PDF (by the
    extension)."""
    from .io.fractions_plot import plot_over

    if not isinstance(result, FractionsOver):
        raise TypeError(f"render_fractions draws a continuation (coincli.fractions_over), got "
                        f"{type(result).__name__}")
    try:
        return plot_over(result, out, title=title, dpi=dpi, ax=ax, panels=panels)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None


__all__ = ["Certainty", "Engine", "Fractions", "FractionsOver", "FractionsPlan",
           "FractionsProgress", "Method", "Outcome", "ParameterError", "Scene", "Status",
           "StopReason", "SweepEstimate", "SweepPlan", "SweepProgress", "SweepReport", "SweepStart",
           "SweepTooLong", "Trajectory", "analyze", "basin", "basin_attrs", "basin_stats",
           "cell_scene", "classify", "compile_kernels", "estimate_fractions", "estimate_sweep",
           "export_basin", "fractions", "fractions_over", "load_preset", "open_basin",
           "open_fractions", "plan_fractions", "plan_sweep", "record", "render_analysis",
           "render_basin", "render_fractions", "run_fractions", "show_basin", "simulate",
           "stability", "sweep", "verify_basin", "viewer"]
