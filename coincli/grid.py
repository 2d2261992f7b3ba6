"""Basin sweeps as pure computation: the grid of initial conditions, its tiles, and one tile's
outcomes. No files, no terminal: :mod:`coincli.io.store` writes what :func:`compute_tile`
returns, :mod:`coincli.distributed` runs tiles on threads or a Dask cluster.

The grid
--------
Exactly two of the six initial conditions are swept, each over ``n`` cell centres
``numpy.linspace(lo, hi, n)`` (both ends included: the first cell is centred on ``lo``, the last on
``hi``); the other four are fixed. Axis order is the order of the state vector
(x0, y0, phi0, vx, vy, vphi), so the default sweep is indexed ``[i_vy, i_vphi]``.

A tile is a block of ``chunk`` cells (the last row and column of tiles may be smaller), the unit
of work, of writing and of resuming. Each cell's outcome depends only on its own initial
condition (the kernels are deterministic and run one trajectory at a time), so a grid computed in
any tiling, order, thread count or cluster gives bit-identical arrays.

Mirror symmetry
---------------
The model is symmetric under the mirror x -> -x: a throw from (x0, y0, -phi0, -vx, vy, -vphi)
is the mirror image of the throw from (x0, y0, phi0, vx, vy, vphi), and ends -n quarter turns
from where that one ends n (x0 does not matter: the foundation is the same everywhere). When a
sweep maps onto itself under it (phi0, vx and vphi zero where fixed, every swept one of them
over a range symmetric about zero, in whole tiles), each pair of mirror tiles is computed once:
the other tile of the pair gets the same cells reversed along those axes, with n negated
(:attr:`Grid.mirror_flips`, :meth:`TileResult.mirrored`). That halves the default basin. The
mirror cell's centre is the exact negative of the cell's to within a few ulps (linspace is not
exactly antisymmetric), far below anything a verified label resolves; on the default 512 x 512
basin computed in full, every cell's verified label, certainty and rung equals its mirror's.
``use_mirror=False`` (``coin basin --no-mirror``) computes every tile.

Verification
------------
Every cell climbs the ladder of its integration's settings (:mod:`coincli.integrators.ladder`)
until two successive rungs agree; the tile holds, besides the label, its certainty and the rung
at which it converged. A single pass is a ladder of one rung.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .defaults import AXIS_INFO, DEFAULT_CHUNK, DEFAULT_RANGES, DEFAULT_RES, IC_NAMES
from .integrators import MethodInfo
from .integrators.batch import NO_LABEL
from .integrators.ladder import scene_ladder
from .integrators.registry import step_budget
from .jit import NUMBA
from .labeller import Labeller
from .models import horizon_text, model_of
from .params import (
    ParameterError,
    Scene,
    parse_whole,
    shown,
    state_array,
)
from .quantities import parse_span, resolve_span

MAX_CELLS_PER_AXIS = 1 << 16
MIRROR_ODD = ("phi0", "vx", "vphi")  # the initial conditions the mirror negates (see above)


# -- parsing ------------------------------------------------------------------------------------
def format_range(lo: float, hi: float) -> str:
    return f"{lo:g}:{hi:g}"


def parse_range(name: str, value, r: float | None = None) -> float | tuple[float, float]:
    """``'0:2'`` or ``(0, 2)`` -> (0.0, 2.0), a swept axis; ``'1.5'`` or ``1.5`` -> 1.5, a fixed
    value (:mod:`coincli.quantities`: ``'-pi:pi'``, ``'r:5r'``, ...); multiples of r in metres
    for a coin of half diagonal ``r``."""
    span = parse_span(name, value)
    ends = span if isinstance(span, tuple) else (span,)
    if r is None and any(end.per_r for end in ends):
        raise ParameterError(f"{name}: multiples of r need a coin: give the value in metres",
                             parameters=(name,))
    return resolve_span(span, math.nan if r is None else r)


def parse_pair(option: str, text, minimum: int = 1) -> tuple[int, int]:
    """``'512'`` or ``512`` -> (512, 512), ``'512x256'`` or ``(512, 256)`` -> (512, 256)."""
    if isinstance(text, tuple | list):
        text = "x".join(map(str, text))
    text = str(text)
    parts = text.lower().split("x")
    try:
        values = [parse_whole(part) for part in parts]
    except ParameterError:
        raise ParameterError(f"{option}: '{shown(text)}' is not N or NxM (whole numbers in "
                             "ASCII digits)", parameters=(option,)) from None
    if len(values) == 1:
        values *= 2
    if len(values) != 2:
        raise ParameterError(f"{option}: '{shown(text)}' is not N or NxM",
                             parameters=(option,))
    for v in values:
        if v < minimum:
            raise ParameterError(f"{option} must be at least {minimum}, got '{shown(text)}'",
                                 parameters=(option,))
        if v > MAX_CELLS_PER_AXIS:
            raise ParameterError(f"{option} must be at most {MAX_CELLS_PER_AXIS}, got "
                                 f"'{shown(text)}'", parameters=(option,))
    return values[0], values[1]


# -- grid ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Axis:
    name: str  # one of IC_NAMES
    lo: float
    hi: float
    n: int

    @property
    def index(self) -> int:
        return IC_NAMES.index(self.name)

    @property
    def coords(self) -> np.ndarray:
        """Cell centres: linspace(lo, hi, n), both ends included."""
        return np.linspace(self.lo, self.hi, self.n)

    @property
    def spacing(self) -> float:
        return (self.hi - self.lo) / (self.n - 1)

    @property
    def label(self) -> str:
        return AXIS_INFO[self.name][0]

    @property
    def units(self) -> str:
        return AXIS_INFO[self.name][1]

    @property
    def long_name(self) -> str:
        return AXIS_INFO[self.name][2]

    def to_dict(self) -> dict:
        return {"name": self.name, "lo": self.lo, "hi": self.hi, "n": self.n,
                "units": self.units, "long_name": self.long_name}


@dataclass(frozen=True)
class Grid:
    axes: tuple[Axis, Axis]
    base_state: tuple[float, ...]  # the six initial values; the swept ones are overwritten
    chunk: tuple[int, int]
    use_mirror: bool = True  # compute one tile of each mirror pair, if the sweep has them

    @property
    def shape(self) -> tuple[int, int]:
        return self.axes[0].n, self.axes[1].n

    @property
    def dims(self) -> tuple[str, str]:
        return self.axes[0].name, self.axes[1].name

    @property
    def n_cells(self) -> int:
        return self.shape[0] * self.shape[1]

    @cached_property
    def tile_grid(self) -> tuple[int, int]:
        """Number of tiles along each axis."""
        return tuple(-(-n // c) for n, c in zip(self.shape, self.chunk, strict=True))

    def states(self) -> np.ndarray:
        """Initial states of every cell, row-major over (first axis, second axis), N x 6."""
        whole = Grid(self.axes, self.base_state, self.shape)
        return whole.tile_states((0, 0))

    def tiles(self) -> list[tuple[int, int]]:
        t0, t1 = self.tile_grid
        return [(i, j) for i in range(t0) for j in range(t1)]

    @cached_property  # asked once per tile: a million times for a sweep of 65536 x 65536
    def mirror_flips(self) -> tuple[bool, bool] | None:
        """Which axes the mirror reverses, if this sweep maps onto itself under it in whole
        tiles (module docstring) and ``use_mirror``; None otherwise."""
        if not self.use_mirror:
            return None
        fixed = self.fixed()
        if any(fixed.get(name, 0.0) != 0.0 for name in MIRROR_ODD):
            return None
        flips = tuple(axis.name in MIRROR_ODD for axis in self.axes)
        for axis, chunk, flip in zip(self.axes, self.chunk, flips, strict=True):
            if flip and (axis.lo != -axis.hi or axis.n % chunk != 0):
                return None
        return flips if any(flips) else None

    @property
    def mirror_dims(self) -> list[str]:
        """The swept initial conditions the mirror reverses (none without a mirror)."""
        flips = self.mirror_flips or (False, False)
        return [d for d, flip in zip(self.dims, flips, strict=True) if flip]

    def mirror_tile(self, tile: tuple[int, int]) -> tuple[int, int]:
        """The tile holding the mirror images of ``tile``'s cells (itself without a mirror)."""
        flips = self.mirror_flips
        if flips is None:
            return tuple(tile)
        return tuple(n - 1 - t if flip else t
                     for t, n, flip in zip(tile, self.tile_grid, flips, strict=True))

    def work_tiles(self) -> list[tuple[int, int]]:
        """The tiles a sweep computes: every tile, or one of each mirror pair."""
        if self.mirror_flips is None:
            return self.tiles()
        return [t for t in self.tiles() if t <= self.mirror_tile(t)]

    @property
    def work_cells(self) -> int:
        """The cells a sweep computes: all, or those of :meth:`work_tiles` (half, and the
        other half of any tile that is its own mirror image)."""
        flips = self.mirror_flips
        if flips is None:
            return self.n_cells
        # a tile is its own mirror image if it is the middle one along every reversed axis
        axes = list(zip(self.shape, self.chunk, flips, self.tile_grid, strict=True))
        own = (0 if any(flip and tiles % 2 == 0 for _, _, flip, tiles in axes) else
               math.prod(chunk if flip else n for n, chunk, flip, _ in axes))
        return (self.n_cells + own) // 2

    def task_tiles(self, tile: tuple[int, int]) -> tuple[tuple[int, int], ...]:
        """The tiles computing work tile ``tile`` fills: itself, and its mirror if another."""
        other = self.mirror_tile(tile)
        return (tuple(tile),) if other == tuple(tile) else (tuple(tile), other)

    def tile_slices(self, tile: tuple[int, int]) -> tuple[slice, slice]:
        return tuple(slice(t * c, min((t + 1) * c, n))
                     for t, c, n in zip(tile, self.chunk, self.shape, strict=True))

    def tile_cells(self, tile: tuple[int, int]) -> int:
        s0, s1 = self.tile_slices(tile)
        return (s0.stop - s0.start) * (s1.stop - s1.start)

    def tile_states(self, tile: tuple[int, int]) -> np.ndarray:
        """Initial states of a tile's cells, row-major (C order over the tile), N x 6."""
        s0, s1 = self.tile_slices(tile)
        c0 = self.axes[0].coords[s0]
        c1 = self.axes[1].coords[s1]
        states = np.empty((c0.size * c1.size, 6), dtype=np.float64)
        states[:] = np.asarray(self.base_state, dtype=np.float64)
        states[:, self.axes[0].index] = np.repeat(c0, c1.size)
        states[:, self.axes[1].index] = np.tile(c1, c0.size)
        return states

    def fixed(self) -> dict[str, float]:
        swept = set(self.dims)
        return {name: float(v) for name, v in zip(IC_NAMES, self.base_state, strict=True)
                if name not in swept}

    def to_dict(self) -> dict:
        return {"dims": list(self.dims), "axes": [a.to_dict() for a in self.axes],
                "fixed": self.fixed(), "chunk": list(self.chunk),
                "cell_centres": "numpy.linspace(lo, hi, n): both ends included",
                "mirror": self.mirror_dims or None}


def split_options(options: dict, r: float) -> tuple[dict[str, tuple[float, float]],
                                                   dict[str, float]]:
    """Initial-condition options (name -> 'LO:HI' | (lo, hi) | value | None) -> (swept ranges,
    fixed values), in SI units for a coin of half diagonal ``r``. vy and vphi sweep their
    default ranges unless given."""
    unknown = set(options) - set(IC_NAMES)
    if unknown:
        raise ParameterError(f"unknown initial condition(s) {sorted(unknown)}; "
                             f"sweepable: {', '.join(IC_NAMES)}")
    ranges: dict[str, tuple[float, float]] = {}
    fixed: dict[str, float] = {}
    for name in IC_NAMES:
        text = options.get(name)
        if text is None:
            if name in DEFAULT_RANGES:
                ranges[name] = DEFAULT_RANGES[name]
            continue
        value = parse_range(name, text, r)
        if isinstance(value, tuple):
            ranges[name] = value
        else:
            fixed[name] = value
    return ranges, fixed


def make_grid(scene: Scene, ranges: dict[str, tuple[float, float]], res: tuple[int, int],
              chunk: tuple[int, int], use_mirror: bool = True) -> Grid:
    """The grid over the two swept ``ranges`` (name -> (lo, hi)), other values from ``scene``."""
    names = [name for name in IC_NAMES if name in ranges]
    unknown = set(ranges) - set(IC_NAMES)
    if unknown:
        raise ParameterError(f"cannot sweep {sorted(unknown)}; sweepable: {', '.join(IC_NAMES)}")
    if len(names) != 2:
        listed = ", ".join(names) or "none"
        raise ParameterError(
            f"exactly two initial conditions must be swept (LO:HI), got {len(names)} ({listed}); "
            "vy and vphi sweep by default: fix one with a plain value (e.g. vy=1.0) to sweep "
            "another", parameters=("vy", "vphi"))
    for n in res:
        if n < 2:
            raise ParameterError(f"res must give at least 2 cells per axis, got {n}",
                                 parameters=("res",))
    axes = tuple(Axis(name, float(ranges[name][0]), float(ranges[name][1]), int(n))
                 for name, n in zip(names, res, strict=True))
    chunk = tuple(min(int(c), n) for c, n in zip(chunk, res, strict=True))
    return Grid(axes=axes, base_state=tuple(float(v) for v in state_array(scene)), chunk=chunk,
                use_mirror=use_mirror)


# -- what a sweep computes ----------------------------------------------------------------------
@dataclass(frozen=True)
class SweepSpec:
    """Everything a tile needs, as plain picklable values (shipped to Dask workers)."""

    grid: Grid
    labeller: Labeller

    array_names = ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung")

    def work_order(self) -> list[tuple[int, int]]:
        """The work tiles, those with the most energy at their middle cell first. A throw's cost
        grows with its energy (more bounces before it settles), and the tile that finishes last
        leaves the other threads idle: started last, the cheapest tiles shorten that tail
        (0.2 s of the default basin's 3.4, by its measured tile costs). The order changes no
        result."""
        grid = self.grid
        energy_at = self.labeller.python.total_energy  # a few calls: not worth numba's loading
        # the middle cell's coordinate of each row (and column) of tiles, computed once
        middles = []
        for axis, chunk, n_tiles in zip(grid.axes, grid.chunk, grid.tile_grid, strict=True):
            starts = np.arange(n_tiles) * chunk
            middles.append(axis.coords[(starts + np.minimum(starts + chunk, axis.n) - 1) // 2])

        def energy(tile) -> float:
            state = list(grid.base_state)
            for axis, along, t in zip(grid.axes, middles, tile, strict=True):
                state[axis.index] = float(along[t])
            return energy_at(self.labeller.params, state)

        return sorted(grid.work_tiles(), key=energy, reverse=True)


def make_spec(scene: Scene, grid: Grid) -> SweepSpec:
    return SweepSpec(grid=grid, labeller=Labeller.of(scene))


def method_attrs(scene: Scene, method: MethodInfo, backend: str = NUMBA.name) -> dict:
    """How a store's labels were computed: the method, its settings and its verification
    ladder, the model and the backend (what the parameters digest binds)."""
    integ = scene.integration
    return {"name": method.name, "kernel_id": int(method.method), "order": method.order,
            "adaptive": method.adaptive, "symplectic": method.symplectic,
            "dt": integ.dt, "rtol": integ.rtol, "t_end": integ.t_end,
            "horizon": horizon_text(scene),
            "stop_on_settle": integ.stop_on_settle, "max_steps": step_budget(integ),
            "verification": scene_ladder(scene).to_dict(),
            "model": model_of(scene).name,
            "backend": backend}


@dataclass
class TileResult:
    tile: tuple[int, int]
    arrays: dict[str, np.ndarray]  # name -> 2-D block of the tile
    cpu_seconds: float
    wall_seconds: float
    mirror_of: tuple[int, int] | None = None  # the tile computed, if this is its mirror image

    @property
    def cells(self) -> int:
        return int(self.arrays["quarter_turns"].size)

    def mirrored(self, grid: Grid) -> TileResult:
        """The result of the mirror tile: the cells reversed along the mirrored axes, n
        negated (cells without a label keep NO_LABEL), everything else as it is."""
        flips = grid.mirror_flips
        order = tuple(slice(None, None, -1) if flip else slice(None) for flip in flips)
        arrays = {name: np.ascontiguousarray(block[order])
                  for name, block in self.arrays.items()}
        turns = arrays["quarter_turns"]
        labelled = turns != NO_LABEL
        turns[labelled] = -turns[labelled]
        return TileResult(grid.mirror_tile(self.tile), arrays, 0.0, 0.0, mirror_of=self.tile)


def with_mirror(result: TileResult, grid: Grid) -> list[TileResult]:
    """The tiles a computed tile fills: itself, and its mirror image if the sweep has one."""
    if len(grid.task_tiles(result.tile)) == 2:
        return [result, result.mirrored(grid)]
    return [result]


def compute_tile(spec: SweepSpec, tile: tuple[int, int], control=None) -> TileResult:
    """Run every cell of one tile up its ladder; the GIL is released meanwhile. ``control``
    set stops it (its cells then have status INTERRUPTED)."""
    wall0, cpu0 = time.perf_counter(), time.thread_time()
    states = spec.grid.tile_states(tile)
    s0, s1 = spec.grid.tile_slices(tile)
    shape = (s0.stop - s0.start, s1.stop - s1.start)
    out = spec.labeller.label(states, control)
    arrays = {name: getattr(out, name).reshape(shape) for name in spec.array_names}
    return TileResult(tile=tuple(tile), arrays=arrays, cpu_seconds=time.thread_time() - cpu0,
                      wall_seconds=time.perf_counter() - wall0)


__all__ = ["AXIS_INFO", "Axis", "DEFAULT_CHUNK", "DEFAULT_RANGES", "DEFAULT_RES", "Grid",
           "IC_NAMES", "MIRROR_ODD", "SweepSpec", "TileResult", "compute_tile", "format_range",
           "make_grid", "make_spec", "method_attrs", "parse_pair", "parse_range", "split_options",
           "with_mirror"]
