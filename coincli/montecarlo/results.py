"""What a Monte Carlo run returns: :class:`Fractions` and, along a parameter,
:class:`FractionsOver`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..enums import StopReason
from ..params import Scene
from ..stats import proportion
from .continuation import PARAMETER_UNITS
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
    parameter: str | None = None  # of a continuation: the parameter and this value
    value: float | None = None
    all_decided: dict = field(default_factory=dict)

    @property
    def interrupted(self) -> bool:
        return self.stopped is StopReason.INTERRUPTED

    def __repr__(self) -> str:  # one line in a notebook; the numbers: to_dict()
        at = "" if self.parameter is None else f"{self.parameter} = {self.value:g}: "
        return (f"Fractions({at}P(standing) = {_pct(self.standing)}, "
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
        if self.parameter is not None:
            out = {"parameter": self.parameter, "value": self.value, **out}
        return out


def _pct(row: dict) -> str:
    """'0.76 % [0.66, 0.87]': a probability and its 95 % interval, in percent."""
    return (f"{100 * row['probability']:.3g} % [{100 * row['low']:.3g}, "
            f"{100 * row['high']:.3g}]")


def make_result(progression: Progression, sampling: Sampling, scene: Scene,
                stopped: StopReason,
                cost: dict, store: str | None = None, parameter: str | None = None,
                value: float | None = None) -> Fractions:
    s = summary(progression.tally, progression.verified)
    return Fractions(samples=s["samples"], counted=s["counted"], standing=s["standing"],
                     lying=s["lying"], uncertain=s["uncertain"], outcomes=s["outcomes"],
                     all_labelled=s["all_labelled"], all_decided=s["all_decided"],
                     status=s["status"],
                     verified=progression.verified, stopped=stopped,
                     goal=progression.goal.to_dict(),
                     achieved=widest(progression.tally, progression.goal.of),
                     sampling=sampling.to_dict(), scene=scene.to_dict(), cost=cost,
                     store=store, parameter=parameter, value=value)


@dataclass
class FractionsOver:
    """A continuation: the outcome probabilities at each value of one physical parameter, the
    same sample points at every value."""

    parameter: str
    values: list[float]
    results: list[Fractions]
    note: str | None
    cost: dict = field(default_factory=dict)
    store: str | None = None

    @property
    def standing(self) -> np.ndarray:
        """(values, 3): P(standing), low, high at each value."""
        return np.array([[r.standing["probability"], r.standing["low"], r.standing["high"]]
                         for r in self.results])

    @property
    def interrupted(self) -> bool:
        return any(r.interrupted for r in self.results)

    def __repr__(self) -> str:
        unit = PARAMETER_UNITS[self.parameter]
        rows = "; ".join(f"{v:g}: {_pct(r.standing)}" for v, r in
                         zip(self.values, self.results, strict=True))
        if len(rows) > 300:
            rows = rows[:300].rsplit(";", 1)[0] + "; ..."
        return (f"FractionsOver({self.parameter} ({unit}), {len(self.values)} values, "
                f"P(standing) {rows})")

    def to_dict(self) -> dict:
        return {"parameter": self.parameter, "units": PARAMETER_UNITS[self.parameter],
                "values": list(self.values), "note": self.note, "cost": self.cost,
                "store": self.store, "results": [r.to_dict() for r in self.results]}
