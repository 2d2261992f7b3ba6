"""What a Monte Carlo run returns at one value: :class:`Fractions`; and where an estimate along a
parameter crosses a level (:func:`level_crossing`; a continuation's results, along a parameter
or over a grid of two, are :class:`coincli.charts.fractions_over.FractionsOver`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..enums import StopReason
from ..params import Scene
from ..stats import proportion
from .sampling import Sampling
from .tally import INTERVAL_NOTE, Progression, summary, widest


@dataclass
class Fractions:
    """The outcome probabilities of one scene (see the module docstring for the definitions).

    ``standing``, ``lying``: over the counted (certain) labels; ``uncertain``: over all samples;
    ``outcomes``: one row per n; each a dict with ``probability``, ``low``, ``high`` (the 95 %
    Wilson interval), ``count`` and ``of``. ``all_decided`` holds the same over every decided
    sample (its deepest rung settled, converged or not), ``all_labelled`` over every labelled
    one; ``uncertain`` also counts its causes (``chaotic``, ``undecided``). ``stopped`` says
    why the run ended (a :class:`coincli.StopReason`)."""

    samples: int
    counted: int
    standing: dict
    lying: dict
    uncertain: dict
    outcomes: list[dict]
    all_labelled: dict
    status: dict
    verified: bool
    stopped: StopReason
    goal: dict
    achieved: float  # the widest half-width the stop rule looks at
    sampling: dict
    scene: dict
    cost: dict = field(default_factory=dict)
    store: str | None = None
    parameter: str | None = None  # along one parameter: the parameter and this value
    value: float | None = None
    all_decided: dict = field(default_factory=dict)
    at: dict | None = None  # of a continuation (one parameter or a grid): {name: value}

    @property
    def interrupted(self) -> bool:
        return self.stopped is StopReason.INTERRUPTED

    def __repr__(self) -> str:  # one line in a notebook; the numbers: to_dict()
        at = "" if not self.at else \
            ", ".join(f"{name} = {value:g}" for name, value in self.at.items()) + ": "
        return (f"Fractions({at}P(standing) = {percent_text(self.standing)}, "
                f"{self.samples:,} samples, {self.counted:,} counted, uncertain "
                f"{100 * self.uncertain['probability']:.3g} %, stopped: {self.stopped})")

    def probability(self, n: int) -> dict:
        """P(n) over the counted labels (zero count if n never occurred)."""
        for row in self.outcomes:
            if row["n"] == n:
                return row
        return {"n": n, **proportion(0, self.counted)}

    def to_dict(self) -> dict:
        out = {
            "samples": self.samples, "counted": self.counted, "verified": self.verified,
            "standing": self.standing, "lying": self.lying, "uncertain": self.uncertain,
            "outcomes": self.outcomes, "all_decided": self.all_decided,
            "all_labelled": self.all_labelled,
            "status": self.status, "stopped": self.stopped,
            "precision": {**self.goal, "achieved_half_width": self.achieved},
            "interval": INTERVAL_NOTE, "sampling": self.sampling, "parameters": self.scene,
            "cost": self.cost, "store": self.store,
        }
        if self.at:
            out = {"at": dict(self.at), **out}
        if self.parameter is not None:
            out = {"parameter": self.parameter, "value": self.value, **out}
        return out


def percent_text(row: dict) -> str:
    """'0.76 % [0.66, 0.87]': a probability and its 95 % interval, in percent."""
    return (f"{100 * row['probability']:.3g} % [{100 * row['low']:.3g}, "
            f"{100 * row['high']:.3g}]")


def make_result(progression: Progression, sampling: Sampling, scene: Scene,
                stopped: StopReason,
                cost: dict, store: str | None = None, at: dict | None = None) -> Fractions:
    """The result of one value (``at``: its parameters' values, of a continuation)."""
    s = summary(progression.tally, progression.verified)
    return Fractions(samples=s["samples"], counted=s["counted"], standing=s["standing"],
                     lying=s["lying"], uncertain=s["uncertain"], outcomes=s["outcomes"],
                     all_labelled=s["all_labelled"], all_decided=s["all_decided"],
                     status=s["status"],
                     verified=progression.verified, stopped=stopped,
                     goal=progression.goal.to_dict(),
                     achieved=widest(progression.tally, progression.goal.of),
                     sampling=sampling.to_dict(), scene=scene.to_dict(), cost=cost,
                     store=store, at=at or None,
                     parameter=next(iter(at)) if at and len(at) == 1 else None,
                     value=next(iter(at.values())) if at and len(at) == 1 else None)


BASES = {"certain": lambda r: r.standing, "decided": lambda r: r.all_decided["standing"],
         "labelled": lambda r: r.all_labelled["standing"]}


def _rise(x: np.ndarray, f: np.ndarray, level: float, last: bool) -> float:
    """x where f rises through level, linearly between the values around it: the first rise
    (``last``: the rise after which f stays at or above the level); NaN if f does not rise
    through it within x."""
    below = np.flatnonzero(~(f >= level))  # NaN counts as below
    if below.size == 0 or below[-1] == f.size - 1 and last:
        return math.nan
    if last:
        i = below[-1]
    else:
        above = np.flatnonzero(f >= level)
        if above.size == 0 or above[0] == 0:
            return math.nan
        i = above[0] - 1
        if not f[i] < level:  # NaN before the rise
            return math.nan
    return float(x[i] + (level - f[i]) * (x[i + 1] - x[i]) / (f[i + 1] - f[i]))


def level_crossing(x, p, low, high, level: float = 1 / 3) -> tuple[float, float, float]:
    """Where an estimate p(x) that rises with x (x ascending) crosses ``level``, with an
    interval: (at, from, to). ``at``: the first rise of p through the level; ``from``: the
    first rise of the intervals' high end (below it p is below the level, at 95 % each);
    ``to``: the last rise of their low end (beyond it p stays above). Linear interpolation
    between neighbouring values; NaN where the rise is not within x (the level is crossed
    before the first value, or after the last)."""
    x = np.asarray(x, dtype=np.float64)
    return (_rise(x, np.asarray(p, dtype=np.float64), level, False),
            _rise(x, np.asarray(high, dtype=np.float64), level, False),
            _rise(x, np.asarray(low, dtype=np.float64), level, True))


__all__ = ["BASES", "Fractions", "level_crossing", "make_result", "percent_text"]
