"""A Monte Carlo run checked before any work: each value's scene, how samples are drawn, when to
stop, and the attributes its store carries; and what a run reports after every batch."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..grid import method_attrs
from ..integrators import check_step
from ..params import ParameterError, Scene, validate
from ..version import __version__
from .continuation import PARAMETERS, continuation_note, parse_over, scene_at
from .sampling import DEFAULT_BATCH, SOBOL_MAX, Sampling, check_box, make_sampling
from .tally import DEFAULT_MAX_SAMPLES, Goal, make_goal

STORE_FORMAT = 3  # of a fractions store (coincli.io.fractions_store): 2, a chunk a batch;
# 3: certainty 3 = undecided (before, undecided labels were 0, uncertain, like chaotic ones)


@dataclass(frozen=True)
class FractionsPlan:
    """A validated Monte Carlo run: the scene of each value (one for a plain run), how samples
    are drawn, when to stop, and the attributes its store carries."""

    scenes: tuple[Scene, ...]
    sampling: Sampling
    goal: Goal
    parameter: str | None
    values: tuple[float, ...] | None
    note: str | None
    attrs: dict

    @property
    def scene(self) -> Scene:
        return self.scenes[0]


def plan_fractions(scene: Scene, *, y0=None, phi0=None, vx=None, vy=None, vphi=None,
                   samples=None, precision=None, of: str = "all",
                   max_samples=DEFAULT_MAX_SAMPLES, seed: int = 0, sampler: str = "sobol",
                   batch: int = DEFAULT_BATCH, over=None, keep=(), force: bool = False
                   ) -> FractionsPlan:
    """Check everything about a Monte Carlo run before any work: the distributions (see
    :func:`coincli.fractions.parse_dist`), that no sample can start too deep in the foundation,
    the goal, and for a continuation (``over``: ``(name, values)`` or ``'NAME=LO:HI:STEPS'``)
    every value's scene and step."""
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
    parameter = values = note = None
    if over is not None:
        parameter, values = parse_over(over) if isinstance(over, str) else over
        values = tuple(float(v) for v in np.atleast_1d(np.asarray(values, dtype=float)))
        if parameter not in PARAMETERS:
            raise ParameterError(f"cannot vary '{parameter}'; one of {', '.join(PARAMETERS)}")
        if not values or not all(math.isfinite(v) for v in values):
            raise ParameterError(f"{parameter}: give finite values to vary it over")
        scenes = tuple(scene_at(scene, parameter, v, keep) for v in values)
        note = continuation_note(scene, parameter, keep)
    else:
        scenes = (scene,)
    for s in scenes:
        check_box(s, sampling)
        method = check_step(s, force=force)
    parameters = scene.to_dict()
    for name in sampling.random_names:
        parameters["initial"][name] = None  # drawn: see sampling
    if parameter is not None:  # varied: see over (the base scene's value is in the note)
        if parameter == "g":
            parameters["g"] = None
        else:
            section = "foundation" if parameter in ("k", "c") else "coin"
            parameters[section][parameter] = None
    attrs = {"coin_fractions": {"format": STORE_FORMAT, "command": "coin fractions"},
             "version": __version__, "parameters": parameters,
             "sampling": sampling.to_dict(), "method": method_attrs(scene, method),
             "over": None if parameter is None else {
                 "parameter": parameter, "values": list(values), "keep": list(keep),
                 "note": note}}
    return FractionsPlan(scenes, sampling, goal, parameter, values, note, attrs)


@dataclass(frozen=True)
class FractionsProgress:
    """Passed to a Monte Carlo run's ``progress`` callback after every batch."""

    value: int  # index of the value whose batch just finished (0 for a plain run)
    values: int  # number of values (1 for a plain run)
    values_done: int  # values whose goal is met
    samples: int  # samples counted for this value so far (the prefix of batches, in order)
    standing: tuple[float, float, float]  # P(standing), low, high over that prefix
    widest: float  # the widest half-width the stop rule looks at (NaN: nothing yet)
    precision: float | None  # the goal's half-width (None for a fixed count)
    expected: int  # samples this value will likely need (a guess, for a progress bar)
    computed: int  # samples computed by this run so far (all values)
    elapsed: float  # s of wall time
    tally: object = None  # the montecarlo.tally.Tally of that prefix: every outcome's count
