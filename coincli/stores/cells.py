"""From a cell of a basin back to its throw: which cell is nearest to a point of the map, the
exact initial state and scene the sweep gave that cell (rebuilt from the store's attributes by
the sweep's own code, :meth:`coincli.grid.Grid.tile_states`, so the state is bit-identical),
what the store holds for it, and the throw replayed with the store's parameters and ladder.

A basin's attributes hold everything this needs: ``parameters`` (the scene, the swept initial
conditions null), ``sweep`` (the two axes: lo, hi, n; the fixed initial values) and ``method``
(the settings and the verification ladder)."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass

import numpy as np

from ..defaults import IC_NAMES
from ..enums import Certainty, Engine, Status
from ..grid import Axis, Grid
from ..integrators import NO_LABEL
from ..integrators.ladder import scene_ladder
from ..params import (
    ParameterError,
    Scene,
    scene_from_dict,
    shown,
    state_array,
)
from ..quantities import parse_quantity
from .basin_layout import grid_of
from .basin_store import BasinStore, Tile


def sweep_axes(attrs: dict) -> tuple[Axis, Axis]:
    """The two swept axes of a basin's attributes."""
    return grid_of(attrs).axes


def _value(name: str, value, r: float) -> float:
    """A value of initial condition ``name`` as given (:mod:`coincli.quantities`), in SI units
    for a coin of half diagonal ``r``."""
    return parse_quantity(name, value).resolve(r)


def locate(attrs: dict, cell=None, **values) -> tuple[int, int]:
    """The cell (i, j) of a basin: ``cell`` by index, or the cell whose centre is nearest to
    ``values`` (both swept initial conditions by name, e.g. ``vy=1.2, vphi=3.5``).
    ParameterError for an axis that is not swept, a value outside its range, an index outside
    the grid."""
    axes = sweep_axes(attrs)
    names = [a.name for a in axes]
    given = {k: v for k, v in values.items() if v is not None}
    if cell is not None:
        if given:
            raise ParameterError("give a cell by its index or by its values, not both")
        if isinstance(cell, str):
            parts = cell.split(",")
            if len(parts) != 2:
                raise ParameterError(f"a cell index is I,J, got '{shown(cell)}'")
            try:
                cell = tuple(int(p.strip()) for p in parts)
            except ValueError:
                raise ParameterError(f"a cell index is I,J (whole numbers), got "
                                     f"'{shown(cell)}'") from None
        if not isinstance(cell, tuple | list) or len(cell) != 2 or any(
                isinstance(c, bool) or not isinstance(c, int | np.integer) for c in cell):
            raise ParameterError(f"a cell index is two whole numbers (i, j), got {shown(cell)}")
        for axis, index in zip(axes, cell, strict=True):
            if not 0 <= index < axis.n:
                raise ParameterError(f"cell index {index} along {axis.name} is outside the "
                                     f"grid: 0 to {axis.n - 1}")
        return int(cell[0]), int(cell[1])
    unknown = [k for k in given if k not in names]
    if unknown:
        fixed = [k for k in unknown if k in IC_NAMES]
        why = (f"{', '.join(fixed)} is not swept in this basin (fixed)" if fixed
               else f"unknown initial condition {', '.join(unknown)}")
        raise ParameterError(f"{why}; its swept axes are {' and '.join(names)}")
    missing = [n for n in names if n not in given]
    if missing:
        raise ParameterError(f"give both swept axes ({' and '.join(names)}) or a cell index; "
                             f"missing: {', '.join(missing)}")
    out = []
    r = scene_from_dict(attrs["parameters"]).coin.r
    for axis in axes:
        value = _value(axis.name, given[axis.name], r)
        if not axis.lo <= value <= axis.hi:
            raise ParameterError(f"{axis.name} = {value:g} is outside the swept range "
                                 f"{axis.lo:g} to {axis.hi:g} {axis.units}")
        out.append(int(np.argmin(np.abs(axis.coords - value))))
    return out[0], out[1]


def mirror_source(attrs: dict, cell: tuple[int, int]) -> tuple[int, int] | None:
    """The cell whose throw the sweep computed and mirrored into ``cell`` (n -> -n), if it
    did (:attr:`coincli.grid.Grid.mirror_flips`); None for a cell computed itself."""
    grid = grid_of(attrs)
    flips = grid.mirror_flips
    tile = tuple(int(c) // k for c, k in zip(cell, grid.chunk, strict=True))
    if flips is None or tile <= grid.mirror_tile(tile):  # a work tile: computed
        return None
    return tuple(n - 1 - c if flip else int(c)
                 for c, n, flip in zip(cell, grid.shape, flips, strict=True))


def cell_state(attrs: dict, cell: tuple[int, int]) -> np.ndarray:
    """The initial state (x0, y0, phi0, vx, vy, vphi) of the throw behind ``cell``'s label,
    bit for bit: the sweep's own code (:meth:`coincli.grid.Grid.tile_states`, on one-cell
    tiles) at the cell, or, for a cell the sweep filled as the mirror image of another, that
    cell's state mirrored (its swept odd values negated: linspace's centres are antisymmetric
    only to a few ulps, and the label is the mirror throw's)."""
    grid = grid_of(attrs)
    one = Grid(grid.axes, grid.base_state, (1, 1))
    source = mirror_source(attrs, cell)
    if source is None:
        return one.tile_states(tuple(cell))[0]
    state = one.tile_states(source)[0]
    for axis, flip in zip(grid.axes, grid.mirror_flips, strict=True):
        if flip:
            state[axis.index] = -state[axis.index]
    return state


def cell_scene(attrs: dict, cell: tuple[int, int]) -> Scene:
    """The scene of ``cell``: the basin's parameters with the cell's six initial values."""
    state = cell_state(attrs, cell)
    scene = scene_from_dict(attrs["parameters"]).with_overrides(
        **{name: float(v) for name, v in zip(IC_NAMES, state, strict=True)})
    if not np.array_equal(state_array(scene), state):  # cannot happen: every value is set
        raise AssertionError("the scene's initial state differs from the sweep's")
    return scene


def ladder_matches(attrs: dict, scene: Scene) -> bool:
    """Whether this version climbs the ladder the store records (a store of another version
    may record another one: its replay may then differ)."""
    ours = json.loads(json.dumps(scene_ladder(scene).to_dict()))
    return ours == attrs["method"].get("verification")


@dataclass(frozen=True)
class StoredCell:
    """What a basin holds for one cell (``computed`` False: its tile is not done)."""

    computed: bool
    quarter_turns: int | None
    status: Status
    certainty: Certainty
    rung: int | None  # index of the last rung run (the one a certain label converged at)
    settle_time: float  # s, NaN if never settled
    steps: int | None


def stored_cell(arrays: dict, cell: tuple[int, int]) -> StoredCell:
    """The outcome a basin's arrays (name -> 2-D array, or the tile's block) hold at ``cell``."""
    i, j = cell
    status = Status(int(arrays["status"][i, j]))
    if status == Status.NOT_COMPUTED:
        return StoredCell(False, None, status, Certainty.NOT_COMPUTED, None, math.nan, None)
    n = int(arrays["quarter_turns"][i, j])
    rung = int(arrays["rung"][i, j])
    return StoredCell(True, None if n == NO_LABEL else n, status,
                      Certainty(int(arrays["certainty"][i, j])), None if rung < 0 else rung,
                      float(arrays["settle_time"][i, j]), int(arrays["steps"][i, j]))


def read_stored_cell(path: str | os.PathLike, cell: tuple[int, int]):
    """(attributes, StoredCell) of a store: the cell's tile alone is read, and checked against
    its digest (a damaged tile's cells read as not computed)."""
    store = BasinStore.open(path)
    grid = store.grid
    tile = tuple(int(c) // k for c, k in zip(cell, grid.chunk, strict=True))
    (_, state, data, _), = store.scan(with_data=True, tiles=[tile])
    if state is not Tile.DONE:
        return store.attrs, StoredCell(False, None, Status.NOT_COMPUTED,
                                       Certainty.NOT_COMPUTED, None, math.nan, None)
    s0, s1 = grid.tile_slices(tile)
    return store.attrs, stored_cell(data, (cell[0] - s0.start, cell[1] - s1.start))


def replay(scene: Scene, *, sample_dt: float | None = None, record_events: bool = False):
    """The cell's throw run again as the sweep ran it: the compiled kernels (the sweep's; the
    Python engine agrees only to rounding) up the same ladder; ``force`` because the sweep has
    already accepted its step."""
    from ..throw import simulate

    return simulate(scene, sample_dt=sample_dt, record_events=record_events, force=True,
                    engine=Engine.NUMBA)


__all__ = ["StoredCell", "cell_scene", "cell_state", "ladder_matches", "locate", "mirror_source",
           "read_stored_cell", "replay", "stored_cell", "sweep_axes"]
