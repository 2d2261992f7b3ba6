"""A Monte Carlo run checked before any work: each value's scene, how samples are drawn, when to
stop, and the attributes its store carries; and what a run reports after every batch."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..engines.work import available_memory, memory_text
from ..grid import method_attrs
from ..integrators import check_step
from ..params import ParameterError, Scene, validate
from ..version import __version__
from .continuation import PARAMETERS, continuation_note, parse_over, point_scene
from .sampling import DEFAULT_BATCH, SOBOL_MAX, Sampling, check_box, make_sampling
from .tally import DEFAULT_MAX_SAMPLES, Goal, make_goal

STORE_FORMAT = 3  # of a fractions store (coincli.stores.fractions_store): 2, a chunk a batch;
# 3: certainty 3 = undecided (before, undecided labels were 0, uncertain, like chaotic ones)


MAX_PARAMETERS = 2  # a continuation varies one parameter, or a grid of two
FOUNDATION = ("k", "c", "mu", "slip_velocity")  # the parameters of a scene's foundation

# What a value (a point of a grid) takes from its plan to its result: its scene, the engine's
# spec and progression (about 3 kB), its result and its row of the Dataset (20 to 30 kB,
# measured). A grid of a million points takes about 31 GiB.
POINT_BYTES = 32 * 1024


@dataclass(frozen=True)
class FractionsPlan:
    """A validated Monte Carlo run: the scene of each value (one for a plain run; over a grid of
    two parameters, one a point, counted flat with the first parameter outermost), how samples
    are drawn, when to stop, and the attributes its store carries."""

    scenes: tuple[Scene, ...]
    sampling: Sampling
    goal: Goal
    parameters: tuple[str, ...]  # the parameters varied (none for a plain run)
    axes: tuple[tuple[float, ...], ...]  # the values of each
    note: str | None
    attrs: dict

    @property
    def scene(self) -> Scene:
        return self.scenes[0]

    @property
    def parameter(self) -> str | None:
        """The parameter of a continuation along one (None for a plain run or a grid)."""
        return self.parameters[0] if len(self.parameters) == 1 else None

    @property
    def values(self) -> tuple[float, ...] | None:
        """The values of a continuation along one parameter (None for a plain run or a
        grid)."""
        return self.axes[0] if len(self.parameters) == 1 else None

    @property
    def shape(self) -> tuple[int, ...]:
        """How many values each parameter takes (() for a plain run)."""
        return tuple(len(values) for values in self.axes)

    def at(self, value: int) -> dict[str, float]:
        """The parameters' values at flat index ``value`` ({} for a plain run)."""
        if not self.parameters:
            return {}
        index = np.unravel_index(value, self.shape)
        return {name: values[i] for name, values, i in
                zip(self.parameters, self.axes, index, strict=True)}

    def label(self, value: int) -> str:
        """'thickness = 0.002, c = 0.5': where value ``value`` is ('' for a plain run)."""
        return ", ".join(f"{name} = {v:g}" for name, v in self.at(value).items())


def parse_grid(over) -> list[tuple[str, tuple[float, ...]]]:
    """The (name, values) of each parameter of ``over``: ``'NAME=LO:HI:STEPS'`` (or
    ``'NAME=V1,V2,...'``), ``(name, values)``, a dict ``{name: values}``, or a list of
    these (strings or pairs), the first parameter outermost."""
    if isinstance(over, str):
        items = [over]
    elif isinstance(over, dict):
        items = list(over.items())
    elif isinstance(over, tuple | list) and len(over) == 2 and isinstance(over[0], str) \
            and not isinstance(over[1], str):
        items = [tuple(over)]
    elif isinstance(over, tuple | list):
        items = list(over)
    else:
        raise ParameterError(f"over: give 'NAME=LO:HI:STEPS', (name, values) or "
                             f"{{name: values}}, got {type(over).__name__}",
                             parameters=("over",))
    grid = []
    for item in items:
        if isinstance(item, str):
            name, values = parse_over(item)
        elif isinstance(item, tuple | list) and len(item) == 2 and isinstance(item[0], str):
            name, values = item
        else:
            raise ParameterError(f"over: {item!r} is neither 'NAME=LO:HI:STEPS' nor a "
                                 "(name, values) pair", parameters=("over",))
        if name not in PARAMETERS:
            raise ParameterError(f"cannot vary '{name}'; one of {', '.join(PARAMETERS)}",
                                 parameters=("over",))
        try:
            values = tuple(float(v) for v in np.atleast_1d(np.asarray(values, dtype=float)))
        except (TypeError, ValueError):
            raise ParameterError(f"{name}: its values must be numbers",
                                 parameters=("over",)) from None
        if not values or not all(math.isfinite(v) for v in values):
            raise ParameterError(f"{name}: give finite values to vary it over",
                                 parameters=("over",))
        grid.append((name, values))
    names = [name for name, _ in grid]
    if not names:
        raise ParameterError("over: name a parameter to vary", parameters=("over",))
    if len(set(names)) != len(names):
        raise ParameterError(f"over: {names[0] if names.count(names[0]) > 1 else names[1]} "
                             "is given twice", parameters=("over",))
    if len(names) > MAX_PARAMETERS:
        raise ParameterError(f"over: at most {MAX_PARAMETERS} parameters at once, got "
                             f"{len(names)} ({', '.join(names)})", parameters=("over",))
    return grid


def check_grid_memory(axes) -> None:
    """ParameterError naming ``over`` unless every value of a continuation (every point of a
    grid of two: ``axes``, the values of each parameter) fits in the memory available now,
    POINT_BYTES each: checked before any value's scene is built, where a grid of thousands of
    values a side would end in a MemoryError (as a tile too large for memory is refused,
    :func:`coincli.engines.basin_plan.check_tile_memory`)."""
    points = math.prod(len(values) for values in axes)
    need = points * POINT_BYTES
    available = available_memory()
    if available is None or need <= available:
        return
    what, unit = ((f"a grid of {' x '.join(f'{len(v):,}' for v in axes)} = {points:,} points",
                   "points") if len(axes) > 1 else (f"{points:,} values", "values"))
    most = max(available // POINT_BYTES, 1)
    raise ParameterError(f"over: {what} need {memory_text(need, available)}; give fewer "
                         f"values (at most about {most:,} {unit})", parameters=("over",))


def plan_fractions(scene: Scene, *, y0=None, phi0=None, vx=None, vy=None, vphi=None,
                   samples=None, precision=None, of: str = "all",
                   max_samples=DEFAULT_MAX_SAMPLES, seed: int = 0, sampler: str = "sobol",
                   batch: int = DEFAULT_BATCH, over=None, keep=(), force: bool = False
                   ) -> FractionsPlan:
    """Check everything about a Monte Carlo run before any work: the distributions (see
    :func:`coincli.fractions.parse_dist`), that no sample can start too deep in the foundation,
    the goal, and for a continuation (``over``: see :func:`parse_grid`; two parameters make a
    grid of every pair of their values) every value's scene and step."""
    validate(scene)
    sampling = make_sampling(scene, sampler=sampler, seed=seed, batch=batch, y0=y0, phi0=phi0,
                             vx=vx, vy=vy, vphi=vphi)
    goal = make_goal(samples=samples, precision=precision, of=of, max_samples=max_samples)
    if sampler == "sobol" and goal.batches(sampling.batch) * sampling.batch > SOBOL_MAX:
        raise ParameterError(f"a Sobol sequence has {SOBOL_MAX:,} points; lower max_samples "
                             "or use sampler random", parameters=("max_samples", "sampler"))
    keep = tuple(keep or ())
    for name in keep:
        if name not in ("mass", "inertia"):
            raise ParameterError(f"keep: '{name}' is not mass or inertia")
    grid = [] if over is None else parse_grid(over)
    names = tuple(name for name, _ in grid)
    axes = tuple(values for _, values in grid)
    check_grid_memory(axes)
    if "slip_velocity" in names and "mu" not in names and not scene.foundation.mu:
        raise ParameterError("over slip_velocity: the scene has no friction (mu = 0), where "
                             "a slip velocity changes nothing; give mu > 0, or vary mu too",
                             parameters=("over", "mu"))
    note = continuation_note(scene, names, keep) if grid else None
    scenes = tuple(point_scene(scene, dict(zip(names, point, strict=True)), keep)
                   for point in itertools.product(*axes)) if grid else (scene,)
    for s in scenes:
        check_box(s, sampling)
        method = check_step(s, force=force)
    parameters = scene.to_dict()
    for name in sampling.random_names:
        parameters["initial"][name] = None  # drawn: see sampling
    for name in names:  # varied: see over (the base scene's value is in the note)
        if name == "g":
            parameters["g"] = None
        else:
            section = "foundation" if name in FOUNDATION else "coin"
            parameters[section][name] = None
    if "mu" in names and "slip_velocity" not in names:  # the values with friction have it,
        # though a frictionless base scene records none
        parameters["foundation"]["slip_velocity"] = float(scene.foundation.slip_velocity)
    if len(names) == 1:  # as 0.9.0 wrote it (its stores resume)
        described = {"parameter": names[0], "values": list(axes[0]), "keep": list(keep),
                     "note": note}
    elif names:
        described = {"parameters": list(names), "values": [list(v) for v in axes],
                     "keep": list(keep), "note": note}
    else:
        described = None
    attrs = {"coin_fractions": {"format": STORE_FORMAT, "command": "coin fractions"},
             "version": __version__, "parameters": parameters,
             "sampling": sampling.to_dict(), "method": method_attrs(scene, method),
             "over": described}
    return FractionsPlan(scenes, sampling, goal, names, axes, note, attrs)


@dataclass(frozen=True)
class FractionsProgress:
    """Passed to a Monte Carlo run's ``progress`` callback after every batch."""

    value: int  # index of the value whose batch just finished (0 for a plain run; over a
    # grid, the point counted flat, the first parameter outermost: FractionsPlan.at)
    values: int  # number of values (1 for a plain run; the points of a grid)
    values_done: int  # values whose goal is met
    samples: int  # samples counted for this value so far (the prefix of batches, in order)
    standing: tuple[float, float, float]  # P(standing), low, high over that prefix
    widest: float  # the widest half-width the stop rule looks at (NaN: nothing yet)
    precision: float | None  # the goal's half-width (None for a fixed count)
    expected: int  # samples this value will likely need (a guess, for a progress bar)
    computed: int  # samples computed by this run so far (all values)
    elapsed: float  # s of wall time
    tally: object = None  # the montecarlo.tally.Tally of that prefix: every outcome's count
