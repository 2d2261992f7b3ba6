"""The public API: what the CLI, the benchmarks, the tests and a notebook call.

    import coincli
    base = coincli.load_preset("paper")
    run = coincli.simulate(base, vy=1.197, vphi=3.508)     # a Trajectory
    outcome = coincli.classify(base, vy=1.197, vphi=3.508) # an Outcome: quarter_turns, status...
    ds = coincli.basin(base, vy=(0.05, 2.0), vphi=(-20.0, 20.0), res=64)   # xarray.Dataset
    coincli.basin_stats(ds).standing
    coincli.render_basin(ds, "basin.png")

A facade: each function checks its options, builds a plan and calls the one engine of its job (a
sweep's :func:`coincli.sweeps.engine.run_sweep`, a Monte Carlo run's
:func:`coincli.io.fractions_run.run_fractions`, the analysis's
:func:`coincli.analysis.analyze_basin`). Options are keywords; results are named (objects with
``to_dict()``, Datasets). Everything that takes a basin takes a Dataset from :func:`basin` or
:func:`open_basin`, or the path of a store.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .enums import Certainty, Engine, Method, Status, StopReason
from .grid import DEFAULT_CHUNK, DEFAULT_RES
from .integrators import warm_up
from .io.rrd import record
from .io.trajectory import Trajectory
from .montecarlo import DEFAULT_BATCH, DEFAULT_MAX_SAMPLES, Fractions, FractionsOver
from .montecarlo.plan import FractionsPlan, FractionsProgress, plan_fractions
from .params import ParameterError, Scene, validate
from .presets import load
from .shock import MinimalShock, minimal_shock
from .statics import StabilityReport, analyse
from .stats import BasinStats
from .sweeps.engine import SweepProgress, SweepReport, SweepStart, check_progress, run_sweep
from .sweeps.executors import check_where, executor_for
from .sweeps.plan import SweepEstimate, SweepPlan, SweepTooLong, estimate_sweep, plan_sweep
from .throw import Outcome, classify
from .throw import simulate as simulate_throw


def load_preset(name_or_path: str = "paper") -> Scene:
    """The scene of a shipped preset (``coin presets`` lists them) or of a TOML file."""
    return load(name_or_path).scene


def simulate(scene: Scene, *, sample_dt: float | None = None, record_events: bool = False,
             force: bool = False, engine: Engine = Engine.AUTO, control=None,
             **overrides) -> Trajectory:
    """Integrate one throw (a :class:`Trajectory`), verified on the ladder of settings unless
    ``verify=False``.

    ``overrides`` change the scene for this throw, by the flat names of
    :meth:`Scene.with_overrides`: initial conditions (``vy=1.197, vphi=3.508``, ``phi0="pi/2"``,
    ``y0="2r"``), physical parameters (``k=5000``) and integration settings (``rtol=1e-8``).
    With ``sample_dt`` the state is kept every ``sample_dt`` seconds of simulated time (exact
    times for the adaptive methods); with ``record_events`` every contact onset and lift-off is
    kept with its state. ``force`` allows a fixed step beyond the method's stable step.
    ``engine`` chooses what runs the kernel (the same result to rounding: compiled code fuses
    multiplies and adds, :mod:`coincli.jit`); ``control`` (from
    :func:`coincli.integrators.new_control`) lets another thread stop it."""
    return Trajectory.of(simulate_throw(scene, sample_dt=sample_dt, record_events=record_events,
                                        force=force, engine=engine, control=control,
                                        **overrides))


def stability(scene: Scene) -> StabilityReport:
    """The static energy table and critical stiffnesses of the paper's section 3, and E_crit."""
    return analyse(validate(scene))


# -- basins -------------------------------------------------------------------------------------
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
    from .io.basin_store import BasinStore, check_store_writable

    check_progress(progress)
    executor = executor_for(threads, workers, scheduler)
    target = BasinStore(store)
    check_store_writable(target.path)
    return run_sweep(plan, target, executor, overwrite=overwrite, progress=progress, stop=stop,
                     max_seconds=max_seconds, on_start=on_start)


def basin(scene: Scene, *, res=DEFAULT_RES, chunk=DEFAULT_CHUNK, store: str | os.PathLike |
          None = None, overwrite: bool = False, force: bool = False,
          threads: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: Callable[[SweepProgress], None] | None = None, stop=None,
          mirror: bool = True, x0=None, y0=None, phi0=None, vx=None, vy=None, vphi=None,
          rrd: str | os.PathLike | None = None, spawn: bool = False, connect: str | None = None,
          notebook=False):
    """The basin map of two initial conditions as an xarray Dataset.

    Swept axes are given as ``name=(lo, hi)`` or ``'LO:HI'`` (``phi0='-pi:pi'``,
    ``y0='r:5r'``: :mod:`coincli.quantities`; vy and vphi sweep (0.05, 2) m/s and (-20, 20)
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
    check_progress(progress)
    plan = plan_sweep(scene, res=res, chunk=chunk, force=force, mirror=mirror, x0=x0, y0=y0,
                      phi0=phi0, vx=vx, vy=vy, vphi=vphi)
    where = _live(rrd, spawn, connect, notebook)
    if store is None:
        if where is not None:
            raise ParameterError("a live recording of a sweep reads its tiles from the store: "
                                 "give store=PATH")
        return _basin_in_memory(plan, executor_for(threads, workers, scheduler), progress,
                                stop)
    from .io.sweep_recording import sweep_recorder

    recorder = sweep_recorder(plan, store, where)
    if recorder is None:
        report = sweep(plan, store, overwrite=overwrite, threads=threads, workers=workers,
                       scheduler=scheduler, progress=progress, stop=stop)
    else:
        with recorder:
            report = sweep(plan, store, overwrite=overwrite, threads=threads, workers=workers,
                           scheduler=scheduler, progress=_both(progress, recorder.progress),
                           stop=stop)
        _warn_if_failed(recorder)
    if report.interrupted:
        raise KeyboardInterrupt(f"sweep interrupted: {report.tiles_done} of "
                                f"{report.tiles_total} tiles are in {report.path}")
    return open_basin(store)


def _basin_in_memory(plan: SweepPlan, executor, progress, stop):
    from .io.dataset import Basin, to_dataset
    from .sweeps.memory import MemoryMap

    if executor.dask:
        raise ParameterError("a sweep on Dask writes its tiles to a store: give store=PATH",
                             parameters=("store",))
    target = MemoryMap()
    report = run_sweep(plan, target, executor, progress=progress, stop=stop)
    if report.interrupted:
        raise KeyboardInterrupt("sweep interrupted")
    return to_dataset(Basin(attrs=plan.attrs, arrays=target.arrays, done=target.done,
                            tile_seconds=target.tile_seconds, runs=target.runs))


def _live(rrd, spawn: bool, connect, notebook=False):
    """The checked destination of a live recording (None if none is asked for)."""
    if rrd is None and not spawn and connect is None and notebook is False:
        return None  # Rerun's code is not even imported
    from .io.rerun_stream import check_destination

    return check_destination(rrd, spawn, connect, notebook)


def _both(first, second):
    """A callback calling ``first`` then ``second`` with the same arguments (either may be
    None)."""
    if first is None or second is None:
        return first or second
    return lambda *args: (first(*args), second(*args))


def _warn_if_failed(recorder, stacklevel: int = 3) -> None:
    """A RuntimeWarning if ``recorder``'s recording failed, attributed to the line that
    called the public function that calls this (``stacklevel``)."""
    if recorder is None or recorder.error is None:
        return
    from .io.paths import explain

    warnings.warn(f"the live recording failed: {explain(recorder.error)}", RuntimeWarning,
                  stacklevel=stacklevel)


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
    from .io.basin_store import BasinStore
    from .io.export import read_export

    if Path(path).is_file():
        return read_export(path)
    return BasinStore.open(path).read()


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
    from .io.basin_store import BasinStore
    from .io.dataset import decoded_attrs
    from .io.export import open_export

    if isinstance(basin, str | os.PathLike):
        if Path(basin).is_file():
            return decoded_attrs(open_export(basin))
        return dict(BasinStore.open(basin).attrs)
    return decoded_attrs(basin)


def cell_scene(basin, *, cell=None, **values) -> Scene:
    """The Scene of one cell of a basin (Dataset or store path): the basin's parameters with
    the cell's initial state exactly as the sweep gave it, so that ``simulate`` replays the
    throw the map shows (the label comes out the same). The cell nearest to ``values`` of
    both swept axes (``vy=1.2, vphi=3.5``; ``phi0="pi/2"``), or ``cell=(i, j)`` by index."""
    from .io.basin_store import BasinStore
    from .io.cells import cell_scene as scene_of
    from .io.cells import locate

    if isinstance(basin, str | os.PathLike):
        attrs = BasinStore.open(basin).attrs
    else:
        attrs = _as_basin(basin).attrs
    return scene_of(attrs, locate(attrs, cell=cell, **values))


def verify_basin(store: str | os.PathLike):
    """Check a store without computing anything: every tile's chunks (checksums) against its
    digest, and every metadata file (a :class:`coincli.io.basin_store.StoreCheck`:
    ``intact``, ``damaged`` tiles with the reason, ``done`` tiles; ``to_dict()``)."""
    from .io.basin_store import BasinStore

    return BasinStore.open(store).check()


def _as_basin(basin):
    """A Basin view of a Dataset, of a store path (or NetCDF export), or of a Basin."""
    from .io.dataset import Basin, from_dataset

    if isinstance(basin, Basin):
        return basin
    if isinstance(basin, str | os.PathLike):
        return _read_basin(basin)
    return from_dataset(basin)


def basin_stats(basin) -> BasinStats:
    """Outcome counts and fractions, P(standing) with its 95 % Wilson interval, the cells
    without a label, the certain and uncertain cells of a verified sweep with the outcome
    probabilities over the certain ones, the tiles (done, damaged) and the cost, of a Dataset
    or a store path: a :class:`coincli.stats.BasinStats` (``to_dict()`` is what ``coin basin
    stats --json`` prints; ``stats["standing"]`` reads it as that mapping). A store is read
    one tile at a time, each checked, so memory stays flat at any resolution; damaged tiles
    count as not computed."""
    from .io.basin_store import BasinStore

    if isinstance(basin, str | os.PathLike) and not Path(basin).is_file():
        return BasinStore.open(basin).stats()
    return _as_basin(basin).stats()


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
    from .io.rerun_stream import notebook_viewer

    return notebook_viewer(width=width, height=height)


def show_basin(basin, *, rrd: str | os.PathLike | None = None, spawn: bool = False,
               connect: str | None = None, notebook=False) -> None:
    """A basin (Dataset or store path, finished or partial) in Rerun's viewer, as
    `coin basin show`: n in the paper's colours, each class named, the uncertain, undecided,
    unsettled and non-finite cells over it, cells not computed (or damaged) marked; to the
    .rrd file ``rrd``, a new viewer (``spawn``) and/or a running one (``connect``), or alone
    in the notebook's cell (``notebook``)."""
    from .io.basin_view import show_basin as show

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
    from .sweeps.executors import usable_cores

    check_progress(progress)
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
    from .io.analysis_view import AnalysisRecorder

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

    check_progress(progress)
    where = _live(rrd, spawn, connect, notebook)
    if where is None:
        return run(plan, store=store, overwrite=overwrite, threads=threads, workers=workers,
                   scheduler=scheduler, progress=progress, stop=stop)
    from .io.fractions_view import FractionsRecorder

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
    from .montecarlo.estimate import estimate_fractions as estimate
    from .sweeps.executors import usable_cores

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
    from .io.fractions_store import FractionsStore, differences

    target = FractionsStore(store)
    try:
        filled = target.read_filled()
        stored = target.attrs()
    except Exception:  # noqa: BLE001 - an unreadable store is the run's to report
        return None
    if differences(stored, plan.attrs):
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


__all__ = ["BasinStats", "Certainty", "Engine", "Fractions", "FractionsOver", "FractionsPlan",
           "FractionsProgress", "Method", "MinimalShock", "Outcome", "ParameterError", "Scene",
           "Status", "StopReason", "SweepEstimate", "SweepPlan", "SweepProgress", "SweepReport",
           "SweepStart", "SweepTooLong", "Trajectory", "analyze", "basin", "basin_attrs",
           "basin_stats", "cell_scene", "classify", "compile_kernels", "estimate_fractions",
           "estimate_sweep", "export_basin", "fractions", "fractions_over", "load_preset",
           "minimal_shock", "open_basin", "open_fractions", "plan_fractions", "plan_sweep",
           "record", "render_analysis", "render_basin", "render_fractions", "run_fractions",
           "show_basin", "simulate", "stability", "sweep", "verify_basin", "viewer"]
