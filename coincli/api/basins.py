"""The public functions of basin maps: sweeping one (into a store or in memory), reading,
exporting, checking, counting, drawing and showing it, and going from one of its cells back
to its throw.

Everything that takes a basin takes a Dataset from :func:`basin` or :func:`open_basin`, or the
path of a store (or of a NetCDF export)."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..defaults import IC_NAMES, MAX_SECONDS
from ..engines.basin import SweepProgress, SweepReport, SweepStart, check_progress, run_sweep
from ..engines.basin_plan import SweepPlan, plan_sweep
from ..engines.executors import executor_for
from ..engines.work import check_max_seconds
from ..grid import DEFAULT_CHUNK, DEFAULT_RES
from ..params import ParameterError, Scene
from ..stats import BasinStats
from .recording import both, live_destination, warn_if_failed


def sweep(plan: SweepPlan, store: str | os.PathLike, *, overwrite: bool = False,
          threads: int | None = None, workers: int | None = None, scheduler: str | None = None,
          progress: Callable[[SweepProgress], None] | None = None, stop=None,
          max_seconds: float | None = MAX_SECONDS,
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
    the sweep is first estimated (:func:`estimate_sweep`, a pilot of at most a second) and,
    over ``max_seconds`` (12 hours unless given; None: no limit, and no estimate unless
    ``on_start`` asks for it), refused with :class:`SweepTooLong` (a
    :class:`coincli.WorkTooLong`, as a Monte Carlo run is refused) before anything is created.
    A store with other parameters is refused (ParameterError naming them) unless
    ``overwrite``. OSErrors (a read-only or full disk) are raised as they come; a store or
    output that cannot be written is found before any work."""
    from ..stores.basin_store import BasinStore

    check_progress(progress)
    check_max_seconds(max_seconds)
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
          notebook=False, max_seconds: float | None = MAX_SECONDS, **overrides):
    """The basin map of two initial conditions as an xarray Dataset.

    ``overrides`` change the scene for this map, by the flat names of
    :meth:`Scene.with_overrides` (``mu=0.3``: with friction at the corners; ``k=5000``,
    ``rtol=1e-8``), as :func:`simulate` takes them.

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
    tile for a resume. A sweep estimated at over ``max_seconds`` (12 hours unless given) is
    refused with :class:`SweepTooLong` before any work; ``max_seconds=None`` starts it anyway.

    ``rrd`` (an .rrd file), ``spawn`` (a new viewer) and ``connect`` (a running viewer's URL,
    ``rerun+http://host:port/proxy``) stream the map to Rerun as it fills in, as
    `coin basin STORE --rrd FILE` does; in a notebook, ``notebook`` (alone): a viewer of
    :func:`viewer` shown in an earlier cell, which fills in live, or True, a viewer in this
    cell that shows the map once the cell has run. The recording reads the tiles back from the
    store, so it needs ``store``. A recording that fails (a full disk, a viewer gone) does not
    fail the sweep: it is said in a RuntimeWarning."""
    from ..throw import with_keywords

    scene = with_keywords(scene, overrides, "basin")
    check_progress(progress)
    check_max_seconds(max_seconds)
    plan = plan_sweep(scene, res=res, chunk=chunk, force=force, mirror=mirror, x0=x0, y0=y0,
                      phi0=phi0, vx=vx, vy=vy, vphi=vphi)
    where = live_destination(rrd, spawn, connect, notebook)
    if store is None:
        if where is not None:
            raise ParameterError("a live recording of a sweep reads its tiles from the store: "
                                 "give store=PATH")
        return _basin_in_memory(plan, executor_for(threads, workers, scheduler), progress,
                                stop, max_seconds)
    from .recording import sweep_recorder

    recorder = sweep_recorder(plan, store, where)
    if recorder is None:
        report = sweep(plan, store, overwrite=overwrite, threads=threads, workers=workers,
                       scheduler=scheduler, progress=progress, stop=stop,
                       max_seconds=max_seconds)
    else:
        with recorder:
            report = sweep(plan, store, overwrite=overwrite, threads=threads, workers=workers,
                           scheduler=scheduler, progress=both(progress, recorder.progress),
                           stop=stop, max_seconds=max_seconds)
        warn_if_failed(recorder)
    if report.interrupted:
        raise KeyboardInterrupt(f"sweep interrupted: {report.tiles_done} of "
                                f"{report.tiles_total} tiles are in {report.path}")
    return open_basin(store)


def _basin_in_memory(plan: SweepPlan, executor, progress, stop, max_seconds):
    from ..stores.dataset import to_dataset
    from ..stores.memory import MemoryMap

    if executor.dask:
        raise ParameterError("a sweep on Dask writes its tiles to a store: give store=PATH",
                             parameters=("store",))
    target = MemoryMap()
    report = run_sweep(plan, target, executor, progress=progress, stop=stop,
                       max_seconds=max_seconds)
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


def basin_scene(basin) -> Scene:
    """The Scene a basin (Dataset, store path or NetCDF export) was swept with: its
    parameters (friction's too: a basin swept before friction reads as mu = 0), the
    initial state the scene's, not a cell's (:func:`cell_scene` gives a cell's)."""
    from ..params import scene_from_dict

    return scene_from_dict(basin_attrs(basin)["parameters"])


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


@dataclass(frozen=True)
class CellRecord:
    """One cell of a basin (:func:`inspect_cell`): where it is, the throw behind it and what
    the basin holds for it (``stored``: ``computed``, ``quarter_turns``, ``status``,
    ``certainty``, ``rung``, ``settle_time``, ``steps``)."""

    cell: tuple[int, int]  # index along the first and the second swept axis
    dims: tuple[str, str]  # the swept axes
    scene: Scene  # the basin's parameters with the cell's initial state, as the sweep gave it
    stored: object  # a coincli.stores.cells.StoredCell
    rung_setting: str | None  # the setting of the rung the stored label was decided at
    ladder_matches: bool  # this version climbs the ladder the basin records (else a replay
    # may differ: a basin of another version)

    def __repr__(self) -> str:  # one line in a notebook; everything: to_dict()
        s, at = self.stored, ", ".join(f"{d} = {self.initial[d]:.6g}" for d in self.dims)
        held = (f"n = {s.quarter_turns} ({s.certainty.label}, {s.status.label})" if s.computed
                else "not computed")
        return f"CellRecord({self.cell[0]}, {self.cell[1]}: {at}; stored {held})"

    @property
    def initial(self) -> dict[str, float]:
        """The cell's six initial values by name."""
        s = self.scene
        i = s.initial
        return dict(zip(IC_NAMES, map(float, (i.x0, s.y0, i.phi0, i.vx, i.vy, i.vphi)),
                        strict=True))

    def to_dict(self) -> dict:
        """Plain values (what `coin basin inspect --json` prints under cell, values, stored)."""
        s, initial = self.stored, self.initial
        return {"cell": list(self.cell), "dims": list(self.dims),
                "values": {d: initial[d] for d in self.dims}, "initial": initial,
                "stored": {"computed": s.computed, "quarter_turns": s.quarter_turns,
                           "status": s.status.label, "certainty": s.certainty.label,
                           "rung": s.rung, "rung_setting": self.rung_setting,
                           "settle_time": None if math.isnan(s.settle_time)
                           else s.settle_time, "steps": s.steps},
                "ladder_matches": self.ladder_matches, "parameters": self.scene.to_dict()}


def inspect_cell(basin, *, cell=None, **values) -> CellRecord:
    """One cell of a basin (a store path, or a Dataset): the cell nearest to ``values`` of both
    swept axes (``vy=1.2, vphi=3.5``; ``phi0="pi/2"``) or ``cell=(i, j)`` (or ``"I,J"``), its
    scene (as :func:`cell_scene`) and what the basin holds for it: a :class:`CellRecord`. Of
    a store only the cell's tile is read, checked against its digest (a damaged tile's cells
    read as not computed). :func:`replay_cell` runs its throw again."""
    from ..integrators.ladder import scene_ladder
    from ..stores.basin_store import BasinStore
    from ..stores.cells import cell_scene as scene_of
    from ..stores.cells import ladder_matches, locate, read_stored_cell, stored_cell

    on_disk = isinstance(basin, str | os.PathLike) and not Path(basin).is_file()
    attrs = BasinStore.open(basin).attrs if on_disk else as_basin(basin).attrs
    index = locate(attrs, cell=cell, **{k: v for k, v in values.items() if v is not None})
    if on_disk:
        attrs, stored = read_stored_cell(basin, index)
    else:
        stored = stored_cell(as_basin(basin).arrays, index)
    scene = scene_of(attrs, index)
    ladder = scene_ladder(scene)
    return CellRecord(index, tuple(attrs["sweep"]["dims"]), scene, stored,
                      None if stored.rung is None else ladder.rung_text(stored.rung),
                      ladder_matches(attrs, scene))


def replay_cell(cell: CellRecord | Scene, *, sample_dt: float | None = None,
                record_events: bool = False):
    """The throw of a cell (a :class:`CellRecord` of :func:`inspect_cell`, or its scene) run
    again as the sweep ran it: the compiled kernels up the same ladder, its step accepted (a
    :class:`coincli.Trajectory`; ``sample_dt`` and ``record_events`` as for
    :func:`coincli.simulate`). Its label is the stored one unless the basin is damaged or of
    another version."""
    from ..recordings.trajectory import Trajectory
    from ..stores import cells

    scene = cell.scene if isinstance(cell, CellRecord) else cell
    return Trajectory.of(cells.replay(scene, sample_dt=sample_dt, record_events=record_events))


def open_store(store: str | os.PathLike):
    """A basin store opened for reading, for a front end that reports on it
    (:class:`coincli.stores.basin_store.BasinStore`): ``attrs``, ``read()`` (its map, every
    tile checked: a Basin), ``stats()``, and the damage of its metadata (``problems``: copies
    of its parameters changed or lost; ``damaged_metadata()``: files that differ from its
    parameters; ``view.proof``: how the parameters it is read with are known). ParameterError
    if ``store`` is no basin store."""
    from ..stores.basin_store import BasinStore

    return BasinStore.open(store)


def export_stats(stats: BasinStats, path: str | os.PathLike) -> Path:
    """Write the outcome table of :func:`basin_stats` to the CSV file ``path`` (what `coin
    basin stats --csv` writes): a row per n with its pose, direction, cells, fraction and 95 %
    interval, and over the certain cells too for a verified sweep. The file is complete or
    absent; returns its path."""
    import csv

    from ..files import atomic_output

    stats = dict(stats)  # a BasinStats, or its to_dict()
    certain = {r["n"]: r for r in stats.get("outcomes_certain", [])}
    with atomic_output(path) as tmp, open(tmp, "w", newline="") as fh:
        writer = csv.writer(fh)
        header = ["n", "pose", "direction", "cells", "fraction", "low", "high"]
        if stats["verified"]:
            header += ["certain_cells", "fraction_of_certain", "certain_low", "certain_high"]
        writer.writerow(header)
        for row in stats["outcomes"]:
            line = [row["n"], row["pose"], row["direction"], row["count"], row["fraction"],
                    row["low"], row["high"]]
            if stats["verified"]:
                r = certain.get(row["n"])
                line += ([r["count"], r["fraction"], r["low"], r["high"]] if r
                         else [0, 0.0, "", ""])
            writer.writerow(line)
    return Path(path)


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
