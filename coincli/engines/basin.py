"""The one engine of a basin sweep: :func:`run_sweep` computes the tiles of a plan that its target
does not hold yet, on an executor, and says what it did (:class:`SweepReport`). Every way of
sweeping calls it: ``coincli.sweep`` and ``coincli.basin`` with a store or in memory, the
command line, on threads or on Dask, with or without a live view (fed by ``progress``).

A target is where the tiles go: a store (:class:`coincli.stores.basin_store.BasinStore`) or memory
(:class:`coincli.stores.memory.MemoryMap`). It has ``exists()`` (it holds a sweep already),
``prepare(plan, overwrite)`` (create or open it and check what it holds: a
:class:`Prepared`), ``claims()`` (this process's claims on its tiles, or None where no other
process can share it), ``has_digest(tile)`` and ``tile_done(tile)`` (finished by another process
since), ``write_tile(result, parameters)``, ``record_run(record)`` and ``shared()`` (the object a
Dask worker writes through).

A tile's task computes the tile and writes it (and its mirror image) itself, so on Dask no data
travel back to the client, only the tile's cost (:class:`TileDone`); each tile binds the digest
of the parameters it was computed with, whatever the target's metadata say when it is written
(another process may have overwritten a store meanwhile: its tiles then do not verify there, and
are computed again).
"""

from __future__ import annotations

import os
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import NamedTuple

import numpy as np

from ..enums import Status
from ..grid import SweepSpec, compute_tile, with_mirror
from ..integrators.batch import new_control
from .basin_plan import (
    SweepEstimate,
    SweepPlan,
    SweepTooLong,
    check_tile_memory,
    estimate_sweep,
    load_kernels,
)
from .claims import tile_queue
from .executors import Dask, SchedulerLost, Threads, hard_stop
from .work import checked_estimate


@dataclass(frozen=True)
class Prepared:
    """What a target holds when a sweep starts: the tiles done (bool per tile), those found
    damaged (tile -> why: recomputed now), the metadata files rewritten, and the digest of the
    parameters its tiles bind (a store of an earlier version that this one resumes keeps its
    own: :data:`coincli.stores.basin_schema.RESUMES`)."""

    done: np.ndarray
    damaged: dict = field(default_factory=dict)
    repaired: tuple = ()
    parameters: bytes | None = None  # the digest its tiles bind (None: a target in memory)


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
class SweepStart:
    """Passed to a sweep's ``on_start`` callback once the target is open, before any work."""

    path: str | None  # the store's; None in memory
    tiles_total: int
    tiles_done: int  # complete and verified
    damaged: tuple  # tiles whose data failed their check: recomputed now
    repaired: tuple  # metadata files rewritten
    cells_todo: int
    estimate: SweepEstimate | None


@dataclass(frozen=True)
class SweepReport:
    """What one run of a sweep did."""

    path: str | None  # the store's; None in memory
    tiles_total: int
    tiles_done: int  # complete tiles in the target now (as far as this run saw)
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

    def to_dict(self) -> dict:
        return {"path": self.path, "tiles_total": self.tiles_total,
                "tiles_done": self.tiles_done, "tiles_before": self.tiles_before,
                "cells": self.cells, "wall_seconds": self.wall_seconds, "mode": self.mode,
                "workers": self.workers, "interrupted": self.interrupted,
                "complete": self.complete, "tiles_computed": self.tiles_computed,
                "tiles_elsewhere": self.tiles_elsewhere,
                "damaged": [list(t) for t in self.damaged],
                "estimate": None if self.estimate is None else self.estimate.to_dict(),
                "kernel_seconds": self.kernel_seconds, "store_seconds": self.store_seconds,
                "mirrored_cells": self.mirrored_cells}


class TileDone(NamedTuple):
    """What a tile's task reports back: no data, only what it cost and whether it was
    written."""

    tile: tuple[int, int]
    cells: int  # cells written (0 if interrupted), its mirror tile's included
    cpu_seconds: float
    written: bool  # False: stopped through its control flag, nothing written
    compute_seconds: float = 0.0  # wall time in the kernels
    write_seconds: float = 0.0  # wall time writing the tile(s) and cost record(s)
    tiles: int = 1  # tiles written: 2 when the tile's mirror image was written too


def run_tile_task(target, spec: SweepSpec, parameters: bytes, tile: tuple[int, int],
                  control: np.ndarray | None = None) -> TileDone:
    """Compute one tile and write it to ``target``, and its mirror tile if the sweep has one
    (:meth:`coincli.grid.Grid.task_tiles`), binding the digest ``parameters`` of the parameters
    it was computed with. ``control[0]`` set (from another thread) stops the computation; a
    tile so stopped is not written at all."""
    control = new_control() if control is None else control
    result = compute_tile(spec, tuple(tile), control)
    if control[0] or (result.arrays["status"] == Status.INTERRUPTED).any():
        return TileDone(tuple(tile), 0, result.cpu_seconds, False, result.wall_seconds)
    start = time.perf_counter()
    results = with_mirror(result, spec.grid)
    for each in results:
        target.write_tile(each, parameters)
    return TileDone(tuple(tile), sum(r.cells for r in results), result.cpu_seconds, True,
                    result.wall_seconds, time.perf_counter() - start, len(results))


def run_record(started: float, wall: float, tiles: int, cells: int, mode: str, workers: int,
               interrupted: bool, kernel_seconds: float = 0.0,
               store_seconds: float = 0.0) -> dict:
    """One run's record: when, how long, what it computed, and where the time went (the tiles'
    wall time in the kernels and in writing, summed over threads)."""
    return {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(started)),
            "wall_seconds": round(wall, 3), "tiles": tiles, "cells": cells, "mode": mode,
            "workers": workers, "interrupted": interrupted, "host": socket.gethostname(),
            "pid": os.getpid(), "kernel_seconds": round(kernel_seconds, 3),
            "store_seconds": round(store_seconds, 3)}


def check_progress(progress) -> None:
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be a function (or None), got {type(progress).__name__}")


def _estimate(plan: SweepPlan, executor: Threads | Dask, cells: int | None,
              max_seconds: float | None) -> SweepEstimate:
    if executor.dask:
        where = {"workers": executor.local_workers, "scheduler": executor.scheduler}
    else:
        where = {"threads": executor.threads}
    return checked_estimate(lambda: estimate_sweep(plan, **where, cells=cells), max_seconds,
                            SweepTooLong)


def run_sweep(plan: SweepPlan, target, executor: Threads | Dask, *, overwrite: bool = False,
              progress: Callable[[SweepProgress], None] | None = None, stop=None,
              max_seconds: float | None = None,
              on_start: Callable[[SweepStart], None] | None = None) -> SweepReport:
    """Compute the tiles of ``plan`` that ``target`` does not hold yet (creating it if
    needed) on ``executor``; see :func:`coincli.sweep` for what each option does.

    Tiles already in the target are checked first: a damaged one is recomputed like a missing
    one. Several processes may run the same sweep on one store at once: each claims a tile
    before computing it, and returns only once every tile is done, whoever computed it.
    ``stop`` (anything with ``is_set()``) finishes the tiles in flight and returns;
    KeyboardInterrupt stops the tiles in flight at once, unwritten, and returns too
    (``interrupted``). With ``max_seconds`` or ``on_start`` the sweep is first estimated and,
    over ``max_seconds``, refused with SweepTooLong before anything is created. A lost Dask
    scheduler raises SchedulerLost once the run is recorded (the target keeps its tiles)."""
    check_progress(progress)
    started = time.time()
    grid, spec = plan.grid, plan.spec
    # the tiles computed at once on this machine (a cluster's workers: each its own)
    check_tile_memory(grid, 1 if executor.dask and executor.scheduler else
                      max(1, executor.workers))
    want_estimate = max_seconds is not None or on_start is not None
    fresh = overwrite or not target.exists()
    estimate = _estimate(plan, executor, None, max_seconds) if fresh and want_estimate else None
    prepared = target.prepare(plan, overwrite)
    todo = [t for t in spec.work_order()
            if not all(prepared.done[u] for u in grid.task_tiles(t))]
    total = len(grid.tiles())
    before = total - sum(len(grid.task_tiles(t)) for t in todo)
    cells_todo = sum(grid.tile_cells(u) for t in todo for u in grid.task_tiles(t))
    if not fresh and want_estimate and todo:
        estimate = _estimate(plan, executor, sum(grid.tile_cells(t) for t in todo),
                             max_seconds)
    damaged = tuple(sorted(prepared.damaged))
    path = getattr(target, "name", None)
    if on_start is not None:
        on_start(SweepStart(path, total, before, damaged, tuple(prepared.repaired),
                            cells_todo, estimate if todo else None))
    if not todo:
        return SweepReport(path, total, total, total, 0, 0.0, executor.mode, executor.workers,
                           False, damaged=damaged, estimate=estimate)

    def finished(tile) -> bool:  # written since the target was prepared, here or elsewhere
        return target.tile_done(tile) if tile in prepared.damaged else target.has_digest(tile)

    def is_done(task) -> bool:  # by another process, since the target was prepared
        return all(finished(u) for u in grid.task_tiles(task))

    claims = target.claims()
    queue = tile_queue(todo, claims, is_done=is_done if claims is not None else None)
    task = partial(run_tile_task, target.shared() if executor.dask else target, spec,
                   prepared.parameters)
    if not executor.dask:
        load_kernels(spec)
    runner = executor.run(task, queue, stop, name=lambda t: f"basin-tile-{t[0]}-{t[1]}")
    try:
        work = _collect(runner, grid, queue, before, total, cells_todo, progress)
    finally:
        if claims is not None:
            claims.close()
    interrupted = work.interrupted or not queue.finished or (stop is not None and stop.is_set())
    elsewhere = sum(len(grid.task_tiles(t)) for t in queue.done_elsewhere)
    # interrupted: what the target holds, also the tiles a task cut off wrote before it was
    # (a tile's mirror image, written after it) and those other processes finished
    n_done = total if not interrupted else before + sum(
        finished(u) for t in todo for u in grid.task_tiles(t))
    interrupted = interrupted and n_done < total  # a stop that came after the last tile
    try:
        target.record_run(run_record(started, work.wall, work.computed, work.cells,
                                     executor.mode, executor.workers, interrupted,
                                     kernel_seconds=work.kernel_seconds,
                                     store_seconds=work.store_seconds))
    except OSError:
        pass  # a cost record lost is no reason to fail a sweep
    if work.lost is not None:
        raise work.lost
    return SweepReport(path, total, n_done, before, work.cells, work.wall, executor.mode,
                       executor.workers, interrupted, work.computed, elsewhere, damaged,
                       estimate, work.kernel_seconds, work.store_seconds, work.mirrored)


@dataclass
class _Work:
    """What one run's tiles did, as they came in."""

    computed: int = 0  # tiles written (mirror images included)
    cells: int = 0
    mirrored: int = 0  # of ``cells``, those written as mirror images
    kernel_seconds: float = 0.0
    store_seconds: float = 0.0
    wall: float = 0.0
    interrupted: bool = False  # by KeyboardInterrupt: the tiles in flight stopped unwritten
    lost: SchedulerLost | None = None


def _collect(runner, grid, queue, before: int, total: int, cells_todo: int,
             progress) -> _Work:
    """Take each finished tile of ``runner``, count it and report the progress; a
    KeyboardInterrupt stops the tiles in flight at once, a lost Dask scheduler is kept to be
    raised once the run is recorded (the target keeps its tiles)."""
    work = _Work()
    wall0 = time.perf_counter()
    try:
        for done in runner:
            work.kernel_seconds += done.compute_seconds
            work.store_seconds += done.write_seconds
            if done.written:
                work.computed += done.tiles
                work.cells += done.cells
                work.mirrored += done.cells - grid.tile_cells(done.tile)
            if progress is not None:
                elsewhere = sum(len(grid.task_tiles(t)) for t in queue.done_elsewhere)
                progress(SweepProgress(before + work.computed + elsewhere, total, work.cells,
                                       cells_todo, time.perf_counter() - wall0,
                                       grid.task_tiles(done.tile) if done.written else ()))
    except KeyboardInterrupt:
        work.interrupted = True
        hard_stop(runner)  # the tiles in flight stop now, unwritten
    except SchedulerLost as exc:
        work.lost = exc
    work.wall = time.perf_counter() - wall0
    return work


__all__ = ["Prepared", "SweepProgress", "SweepReport", "SweepStart", "TileDone",
           "check_progress", "run_record", "run_sweep", "run_tile_task"]

