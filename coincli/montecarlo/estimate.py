"""How much a Monte Carlo run will cost before it starts: a pilot of a few hundred samples of
the run's own first batch, at a few of its values (along one parameter the first, the middle and
the last; over a grid its corners and its centre), timed and counted. From the pilot's
labels, the normal approximation at its estimates gives the samples the stop rule will need
(a precision goal), and whether the sample budget suffices; from its CPU time, how long the
samples left take."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..params import state_array
from .batch import BatchTask, compute_batch, make_fraction_spec
from .plan import FractionsPlan
from .sampling import Draws, initial_states
from .tally import Tally, samples_needed

PILOT_SAMPLES = 512  # samples a piloted value computes: the first of its first batch


@dataclass(frozen=True)
class FractionsEstimate:
    """What a run will likely cost, from a pilot (``samples`` and ``seconds`` exclude what a
    store holds already; a store that holds the whole run needs no pilot: ``pilot_samples``
    0)."""

    samples: int  # samples still to compute, over every value
    needed: int | None  # the most samples any value's stop rule likely needs (precision goals)
    budget: int  # the most samples a value may take (--samples, or --max-samples)
    cpu_per_sample: float  # CPU s a sample, every rung of the ladder counted
    seconds: float  # wall time on ``workers`` (CPU time if workers is None)
    workers: int | None  # threads or Dask workers assumed; None: a cluster of unknown size
    pilot_samples: int  # samples the pilot computed
    held: int = 0  # samples a store holds already (every value)

    @property
    def budget_suffices(self) -> bool:
        return self.needed is None or self.needed <= self.budget


def pilot_values(shape: tuple[int, ...]) -> list[int]:
    """The values a pilot runs (flat indices): the corners of the grid (along one parameter,
    its ends) and its centre; 0 for a plain run."""
    if not shape:
        return [0]
    points = {tuple(p) for p in itertools.product(*[(0, n - 1) for n in shape])}
    points.add(tuple(n // 2 for n in shape))
    return sorted(int(np.ravel_multi_index(p, shape)) for p in points)


def estimate_fractions(plan: FractionsPlan, workers: int | None,
                       held: list[int] | None = None) -> FractionsEstimate:
    """Estimate a planned run: ``workers`` threads or Dask workers (None: CPU time, for a
    cluster of unknown size); ``held``: the samples a store holds already, per value."""
    goal, sampling = plan.goal, plan.sampling
    budget = goal.samples or goal.batches(sampling.batch) * sampling.batch
    n_values = len(plan.scenes)
    if held and all(h >= budget for h in held):  # the store holds the whole run: no pilot
        return FractionsEstimate(0, None, budget, math.nan, 0.0, workers, 0, sum(held))
    piloted = pilot_values(plan.shape)
    count = min(PILOT_SAMPLES, sampling.batch, budget)
    points = Draws(sampling).batch(0)[:count]
    cpu, needs = 0.0, []
    for v in piloted:
        spec = make_fraction_spec(plan.scenes[v])
        spec.load(np.asarray(state_array(plan.scenes[v])))  # the kernels, outside the clock
        task = BatchTask(v, 0, count, initial_states(plan.scenes[v], sampling, points))
        result = compute_batch(spec, task)
        cpu += result.cpu_seconds
        if goal.precision is not None:
            lab = result.labels
            tally = Tally.of(lab["quarter_turns"], lab["status"], lab["certainty"],
                             spec.verified)
            needs.append(samples_needed(tally, goal.precision, goal.of))
    per_sample = cpu / (count * len(piloted))
    needed = max(needs) if needs else None
    per_value = min(budget, needed) if needed is not None else budget
    held = held or [0] * n_values
    samples = sum(max(0, per_value - h) for h in held)
    seconds = per_sample * samples / (workers or 1)
    return FractionsEstimate(samples, needed, budget, per_sample, seconds, workers,
                             count * len(piloted), sum(held))


__all__ = ["FractionsEstimate", "PILOT_SAMPLES", "estimate_fractions", "pilot_values"]
