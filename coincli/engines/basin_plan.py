"""A basin sweep planned before any work (:class:`SweepPlan`): the scene, the grid and what every
tile needs, checked once, with the attributes its store or Dataset will carry; and how long it
should take (:func:`estimate_sweep`, from a pilot of a few dozen cells timed on this machine)."""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

import numpy as np

from ..enums import Status
from ..grid import (
    DEFAULT_CHUNK,
    DEFAULT_RES,
    Grid,
    SweepSpec,
    make_grid,
    make_spec,
    method_attrs,
    parse_pair,
    split_options,
)
from ..integrators import check_step
from ..integrators.batch import new_control
from ..integrators.ladder import describe_scene
from ..params import ParameterError, Scene, check_start, require_scene, validate
from ..values import format_duration
from ..version import __version__
from .executors import usable_cores
from .work import WorkTooLong, available_memory, memory_text


@dataclass(frozen=True)
class SweepPlan:
    """A validated sweep: the scene (fixed initial values applied), its method, the grid and
    what every tile needs, and the attributes the store or Dataset will carry."""

    scene: Scene
    spec: SweepSpec
    attrs: dict  # what the sweep is (:func:`sweep_attrs`): what its store's parameters digest binds

    @property
    def grid(self) -> Grid:
        return self.spec.grid

    def to_dict(self) -> dict:
        """The plan as plain values: the attributes its store will carry."""
        return dict(self.attrs)

    def __repr__(self) -> str:  # one line in a notebook; everything: .attrs
        g = self.grid
        axes = " x ".join(f"{a.name} {a.lo:g}:{a.hi:g} ({a.n})" for a in g.axes)
        tiles = math.prod(g.tile_grid)
        return (f"SweepPlan({axes}, {tiles} tile{'s' * (tiles != 1)}, {g.work_cells:,} of "
                f"{g.n_cells:,} cells computed, {describe_scene(self.scene)})")


def plan_sweep(scene: Scene, *, res=DEFAULT_RES, chunk=DEFAULT_CHUNK, force: bool = False,
               mirror: bool = True, **initial) -> SweepPlan:
    """Check everything about a sweep before any work: the ranges (two initial conditions
    swept, ``name=(lo, hi)`` or ``'LO:HI'``, e.g. ``phi0='-pi:pi'``, ``y0='r:5r'``; vy and vphi
    sweep their defaults unless given), the other initial values, the resolution, the tiles,
    the method and its step. ``mirror``: where the sweep is its own mirror image, compute one
    tile of each mirror pair (:attr:`coincli.grid.Grid.mirror_flips`; the plan's ``attrs``
    say which axes)."""
    scene = require_scene(scene)
    ranges, fixed = split_options(initial, scene.coin.r)
    scene = validate(scene.with_overrides(**fixed))
    grid = make_grid(scene, ranges, parse_pair("res", res, 2), parse_pair("chunk", chunk, 1),
                     use_mirror=mirror)
    for axis in grid.axes:  # every swept value must make a valid scene too
        for value in (axis.lo, axis.hi):
            validate(scene.with_overrides(**{axis.name: value}))
    _check_starts(scene, grid)
    check_tile_memory(grid)
    method = check_step(scene, force=force)
    spec = make_spec(scene, grid)
    return SweepPlan(scene, spec, sweep_attrs(scene, method, spec))


def sweep_attrs(scene: Scene, method, spec: SweepSpec) -> dict:
    """Everything needed to reproduce a basin: every parameter (the swept ones null, see
    ``sweep``), the grid, the method with its settings and verification ladder, the version."""
    grid = spec.grid
    parameters = scene.to_dict()
    for name in grid.dims:
        parameters["initial"][name] = None  # swept: see sweep.axes
    return {"version": __version__, "parameters": parameters, "sweep": grid.to_dict(),
            "method": method_attrs(scene, method)}


# The memory a tile's work takes, per cell: its initial states (6 float64), its labels (17
# bytes a cell over the six arrays) and their mirror image, and an array being encoded for
# writing (an int64 and its bytes). A tile of 512 x 512 cells takes 26 MB.
TILE_BYTES_PER_CELL = 48 + 17 + 17 + 16


def check_tile_memory(grid: Grid, at_once: int = 1) -> None:
    """ParameterError naming ``chunk`` unless ``at_once`` tiles of ``grid`` (one a thread or a
    worker of this machine) fit in the memory available now: checked before anything is
    allocated, where a tile too large would end in numpy's MemoryError."""
    available = available_memory()
    cells = math.prod(grid.chunk)
    need = at_once * cells * TILE_BYTES_PER_CELL
    if available is None or need <= available:
        return
    side = int(math.isqrt(max(available // (at_once * TILE_BYTES_PER_CELL), 1)))
    side = side // 64 * 64 or side
    tiles = (f"{at_once} tiles at once (one a thread or worker) of {cells:,} cells each need"
             if at_once > 1 else f"a tile of {cells:,} cells needs")
    raise ParameterError(f"chunk {'x'.join(map(str, grid.chunk))}: {tiles} "
                         f"{memory_text(need, available)}; give a smaller chunk (at most "
                         f"{side})", parameters=("chunk",))


def _check_starts(scene: Scene, grid: Grid) -> None:
    """No cell may start deeper in the foundation than the scene allows: the deepest pose has
    the lowest y0 and the angle that reaches furthest down (checked over every phi0 cell)."""
    coords = {axis.name: axis.coords for axis in grid.axes}
    y0 = float(np.min(coords["y0"])) if "y0" in coords else scene.y0
    phis = coords.get("phi0", np.array([scene.initial.phi0]))
    reach = scene.coin.r_d * np.abs(np.sin(phis)) + scene.coin.r_t * np.abs(np.cos(phis))
    check_start(scene, y0, float(phis[int(np.argmax(reach))]))


def load_kernels(spec: SweepSpec) -> None:
    """Load the compiled kernels before a clock starts (and before the threads race to)."""
    spec.labeller.load(np.asarray(spec.grid.base_state, dtype=np.float64))


# -- how long it should take ----------------------------------------------------------------------
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

    def to_dict(self) -> dict:
        return {"seconds": self.seconds, "cells": self.cells,
                "cpu_per_cell": self.cpu_per_cell, "workers": self.workers,
                "pilot_cells": self.pilot_cells, "at_least": self.at_least}


class SweepTooLong(WorkTooLong):
    """A sweep whose estimate (a :class:`SweepEstimate`) is over the limit it was given
    (``max_seconds``): the sweep's kind of :class:`coincli.engines.work.WorkTooLong`."""

    what = "this sweep"


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
    grid, spec = plan.grid, plan.spec
    cells = grid.work_cells if cells is None else int(cells)
    cores = usable_cores()
    n = None if scheduler is not None else min(workers or threads or cores, cores)
    load_kernels(spec)
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
            out = spec.labeller.label(state[None, :], control)
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


__all__ = ["PILOT_CELLS", "PILOT_SECONDS", "SweepEstimate", "SweepPlan", "SweepTooLong",
           "TILE_BYTES_PER_CELL", "available_memory", "check_tile_memory", "estimate_sweep",
           "format_duration", "load_kernels", "pilot_cells", "plan_sweep"]
