"""A sweep's target in memory (:class:`MemoryMap`): what ``coincli.basin`` without a store
fills, through the same engine as a store (:func:`coincli.engines.basin.run_sweep`)."""

from __future__ import annotations

import math

import numpy as np

from ..engines.basin import Prepared
from ..engines.basin_plan import SweepPlan
from ..grid import TileResult
from ..params import ParameterError
from .basin_schema import FILLS, VARIABLES, root_attrs
from .dataset import Basin


class MemoryMap:
    """The arrays of one sweep in this process: every variable of the schema on the grid, the
    tiles done, each tile's CPU seconds and the run records. No other process shares it (no
    claims), and no Dask worker can write to it."""

    name = None  # no path

    def __init__(self):
        self.arrays: dict[str, np.ndarray] = {}
        self.done = np.zeros((0, 0), np.uint8)
        self.tile_seconds = np.zeros((0, 0))
        self.runs: list[dict] = []
        self.grid = None
        self.attrs: dict = {}

    def exists(self) -> bool:
        return False

    def prepare(self, plan: SweepPlan, overwrite: bool = False) -> Prepared:
        grid = self.grid = plan.grid
        self.attrs = root_attrs(plan.attrs)
        self.arrays = {name: np.full(grid.shape, FILLS[name], dtype=VARIABLES[name][0])
                       for name in plan.spec.array_names}
        self.done = np.zeros(grid.tile_grid, np.uint8)
        self.tile_seconds = np.full(grid.tile_grid, math.nan)
        return Prepared(self.done.astype(bool))

    def claims(self):
        return None  # nobody else writes here

    def has_digest(self, tile) -> bool:
        return bool(self.done[tuple(tile)])

    tile_done = has_digest

    def shared(self):
        raise ParameterError("a sweep on Dask writes its tiles to a store: give store=PATH",
                             parameters=("store",))

    def write_tile(self, result: TileResult, parameters: bytes | None = None) -> None:
        """The tile's arrays into the map (tiles are disjoint: threads never share cells)."""
        s0, s1 = self.grid.tile_slices(result.tile)
        for name, block in result.arrays.items():
            self.arrays[name][s0, s1] = block
        self.done[result.tile] = 1
        self.tile_seconds[result.tile] = result.cpu_seconds

    def record_run(self, run: dict) -> None:
        self.runs.append(run)

    def basin(self) -> Basin:
        """What the map holds, as a store's :meth:`~coincli.stores.basin_store.BasinStore.read`
        gives it."""
        return Basin(attrs=self.attrs, arrays=self.arrays, done=self.done,
                     tile_seconds=self.tile_seconds, runs=self.runs)


__all__ = ["MemoryMap"]
