"""The public functions of basin maps: sweeping one (into a store or in memory), reading,
exporting, checking, counting, drawing and showing it.

Everything that takes a basin takes a Dataset from :func:`basin` or :func:`open_basin`, or the
path of a store (or of a NetCDF export)."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from ..engines.basin import SweepProgress, SweepReport, SweepStart, check_progress, run_sweep
from ..engines.basin_plan import SweepPlan, plan_sweep
from ..engines.executors import executor_for
from ..grid import DEFAULT_CHUNK, DEFAULT_RES
from ..params import ParameterError, Scene
from ..stats import BasinStats
from .recording import both, live_destination, warn_if_failed


def sweep(plan: SweepPlan, store: str | os.PathLike, *, overwrite: bool = False,
          threads: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: Callable[[SweepProgress], None] | None = None, stop=None,
          max_seconds: float | None = None,
          on_start: Callable[[SweepStart], None] | None = None,
          worker_timeout: float | None = None) -> SweepReport:
    """Compute the tiles of ``plan`` that ``store`` does not hold yet (creating it if needed),
    on ``threads`` threads (default: one per core) or on Dask (``workers`` local processes, or
    the cluster at ``scheduler``; a cluster left without a worker is waited for, saying so on
    the logger ``coincli.dask``, and with ``worker_timeout`` the run stops after that many
    seconds without one: :class:`coincli.engines.executors.NoWorkers`, a SchedulerLost).

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
    from ..stores.basin_store import BasinStore

    check_progress(progress)
    executor = executor_for(threads, workers, scheduler, worker_timeout)
    target = BasinStore(store)
    target.check_writable(overwrite)  # a complete store needs no write: read-only is enough
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
    where = live_destination(rrd, spawn, connect, notebook)
    if store is None:
        if where is not None:
            raise ParameterError("a live recording of a sweep reads its tiles from the store: "
                                 "give store=PATH")
        return _basin_in_memory(plan, executor_for(threads, workers, scheduler), progress,
                                stop)
    from ..recordings.sweep_recording import sweep_recorder

    recorder = sweep_recorder(plan, store, where)
    if recorder is None:
        report = sweep(plan, store, overwrite=overwrite, threads=threads, workers=workers,
                       scheduler=scheduler, progress=progress, stop=stop)
    else:
        with recorder:
            report = sweep(plan, store, overwrite=overwrite, threads=threads, workers=workers,
                           scheduler=scheduler, progress=both(progress, recorder.progress),
                           stop=stop)
        warn_if_failed(recorder)
    if report.interrupted:
        raise KeyboardInterrupt(f"sweep interrupted: {report.tiles_done} of "
                                f"{report.tiles_total} tiles are in {report.path}")
    return open_basin(store)


def _basin_in_memory(plan: SweepPlan, executor, progress, stop):
    from ..stores.dataset import to_dataset
    from ..stores.memory import MemoryMap

    if executor.dask:
        raise ParameterError("a sweep on Dask writes its tiles to a store: give store=PATH",
                             parameters=("store",))
    target = MemoryMap()
    report = run_sweep(plan, target, executor, progress=progress, stop=stop)
    if report.interrupted:
        raise KeyboardInterrupt("sweep interrupted")
    return to_dataset(target.basin())


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
    from ..stores.dataset import to_dataset

    return to_dataset(read_basin(store))


def read_basin(path):
    """The Basin of a store, or of a NetCDF export (a file)."""
    from ..charts.export import read_export
    from ..stores.basin_store import BasinStore

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
    from ..charts.export import check_export_path
    from ..charts.export import export_basin as export

    path = check_export_path(path)
    return export(as_basin(basin), path)


def basin_attrs(basin) -> dict:
    """The attributes of a basin (Dataset, store path or NetCDF export) as plain nested
    values: parameters, sweep, method, version, coin_basin and, of a Dataset, runs,
    damaged_tiles, store. A Dataset holds the nested ones as JSON text (NetCDF has no nested
    attributes); this decodes them, whichever route the Dataset came by."""
    from ..charts.export import open_export
    from ..stores.basin_store import BasinStore
    from ..stores.dataset import decoded_attrs

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
    from ..stores.basin_store import BasinStore
    from ..stores.cells import cell_scene as scene_of
    from ..stores.cells import locate

    if isinstance(basin, str | os.PathLike):
        attrs = BasinStore.open(basin).attrs
    else:
        attrs = as_basin(basin).attrs
    return scene_of(attrs, locate(attrs, cell=cell, **values))


def verify_basin(store: str | os.PathLike):
    """Check a store without computing anything: every tile's chunks (checksums) against its
    digest, and every metadata file (a :class:`coincli.stores.basin_store.StoreCheck`:
    ``intact``, ``damaged`` tiles with the reason, ``done`` tiles; ``to_dict()``)."""
    from ..stores.basin_store import BasinStore

    return BasinStore.open(store).check()


def as_basin(basin):
    """A Basin view of a Dataset, of a store path (or NetCDF export), or of a Basin."""
    from ..stores.dataset import Basin, from_dataset

    if isinstance(basin, Basin):
        return basin
    if isinstance(basin, str | os.PathLike):
        return read_basin(basin)
    return from_dataset(basin)


def basin_stats(basin) -> BasinStats:
    """Outcome counts and fractions, P(standing) with its 95 % Wilson interval, the cells
    without a label, the certain and uncertain cells of a verified sweep with the outcome
    probabilities over the certain ones, the tiles (done, damaged) and the cost, of a Dataset
    or a store path: a :class:`coincli.stats.BasinStats` (``to_dict()`` is what ``coin basin
    stats --json`` prints; ``stats["standing"]`` reads it as that mapping). A store is read
    one tile at a time, each checked, so memory stays flat at any resolution; damaged tiles
    count as not computed."""
    from ..stores.basin_store import BasinStore

    if isinstance(basin, str | os.PathLike) and not Path(basin).is_file():
        return BasinStore.open(basin).stats()
    return as_basin(basin).stats()


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
    from ..charts.basin_render import render_map

    try:
        return render_map(as_basin(basin), out, title=title, dpi=dpi, n_max=n_max,
                          field=field, marks=marks, ax=ax)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None


def show_basin(basin, *, rrd: str | os.PathLike | None = None, spawn: bool = False,
               connect: str | None = None, notebook=False) -> None:
    """A basin (Dataset or store path, finished or partial) in Rerun's viewer, as
    `coin basin show`: n in the paper's colours, each class named, the uncertain, undecided,
    unsettled and non-finite cells over it, cells not computed (or damaged) marked; to the
    .rrd file ``rrd``, a new viewer (``spawn``) and/or a running one (``connect``), or alone
    in the notebook's cell (``notebook``)."""
    from ..recordings.basin_view import show_basin as show

    where = live_destination(rrd, spawn, connect, notebook)
    if where is None:
        raise ParameterError("show_basin() needs a destination: rrd=PATH, spawn=True, "
                             "connect=URL or notebook=True")
    show(as_basin(basin), where)
