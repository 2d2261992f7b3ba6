"""Counts of outcomes, their Wilson intervals, the goal of a run and its stop rule (evaluated on
the prefix of completed batches, in order, so that it is reproducible)."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from ..defaults import DEFAULT_MAX_SAMPLES, DEFAULT_PRECISION
from ..enums import Certainty, Status, StopReason
from ..params import ParameterError
from ..stats import outcome_rows, proportion


@dataclass
class Tally:
    """Counts of a set of samples. ``counted``: the labels probabilities are taken over (certain
    ones; for a single pass, the settled ones); ``labelled``: every sample with a label
    (settled, or unsettled at t_end); ``decided``: every sample whose deepest rung run settled
    (its label final for that run, converged or not); ``certainty``: the samples by
    Certainty (why a label is not certain: uncertain, chaotic, or undecided)."""

    samples: int = 0
    counted: Counter = field(default_factory=Counter)  # n -> count
    labelled: Counter = field(default_factory=Counter)  # n -> count
    status: Counter = field(default_factory=Counter)  # Status value -> count
    decided: Counter = field(default_factory=Counter)  # n -> count
    certainty: Counter = field(default_factory=Counter)  # Certainty value -> count

    @classmethod
    def of(cls, quarter_turns, status, certainty, verified: bool = True) -> Tally:
        q = np.asarray(quarter_turns).astype(np.int64)
        st = np.asarray(status)
        cert = np.asarray(certainty)
        labelled = (st == Status.SETTLED) | (st == Status.UNSETTLED)
        if verified:
            counted = labelled & (cert == Certainty.CERTAIN)
        else:
            counted = st == Status.SETTLED
        def counts(values) -> Counter:
            return Counter({int(k): int(v) for k, v in
                            zip(*np.unique(values, return_counts=True), strict=True)})

        return cls(samples=int(q.size), counted=counts(q[counted]),
                   labelled=counts(q[labelled]), status=counts(st),
                   decided=counts(q[st == Status.SETTLED]), certainty=counts(cert))

    def __add__(self, other: Tally) -> Tally:
        return Tally(self.samples + other.samples, self.counted + other.counted,
                     self.labelled + other.labelled, self.status + other.status,
                     self.decided + other.decided, self.certainty + other.certainty)

    @property
    def n_counted(self) -> int:
        return sum(self.counted.values())

    @property
    def n_labelled(self) -> int:
        return sum(self.labelled.values())

    @property
    def standing(self) -> int:
        return sum(c for n, c in self.counted.items() if n % 2)

    @property
    def standing_labelled(self) -> int:
        return sum(c for n, c in self.labelled.items() if n % 2)

    @property
    def n_decided(self) -> int:
        return sum(self.decided.values())

    @property
    def standing_decided(self) -> int:
        return sum(c for n, c in self.decided.items() if n % 2)

GOALS = ("all", "standing")
CONFIDENCE = 0.95
INTERVAL_NOTE = ("Wilson score interval at 95 % (scipy): exact in its model for independent "
                 "draws; scrambled Sobol points measured to have the same variance here")


def wilson_arrays(k, n, confidence: float = CONFIDENCE) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score intervals of many counts at once, by the operations of scipy's
    ``binomtest(k, n).proportion_ci(method="wilson")`` (so the same floats as
    coincli.stats.wilson); NaN where n = 0."""
    from scipy.special import ndtri

    k = np.asarray(k, dtype=np.float64)
    n = np.asarray(n, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = k / n
        z = ndtri(0.5 + 0.5 * confidence)
        denom = 2 * (n + z ** 2)
        center = (2 * n * p + z ** 2) / denom
        delta = z / denom * np.sqrt(4 * n * p * (1 - p) + z ** 2)
        lo = np.where(k == 0, 0.0, center - delta)
        hi = np.where(k == n, 1.0, center + delta)
    bad = n <= 0
    return np.where(bad, np.nan, lo), np.where(bad, np.nan, hi)


def half_widths(tally: Tally, of: str = "all") -> np.ndarray:
    """The half-widths (high - low) / 2 of the 95 % intervals the stop rule looks at."""
    counted = tally.n_counted
    ks = [tally.standing]
    ns = [counted]
    if of == "all":
        ks += list(tally.counted.values())
        ns += [counted] * len(tally.counted)
        ks.append(tally.samples - counted)  # the uncertain fraction, over all samples
        ns.append(tally.samples)
    lo, hi = wilson_arrays(ks, ns)
    return (hi - lo) / 2


def widest(tally: Tally, of: str = "all") -> float:
    """The largest half-width the stop rule looks at (NaN if there is nothing to divide by)."""
    w = half_widths(tally, of)
    return math.nan if np.isnan(w).any() else float(w.max())


def precise(tally: Tally, precision: float, of: str = "all") -> bool:
    w = widest(tally, of)
    return not math.isnan(w) and w <= precision


Z95 = 1.959963984540054  # the normal quantile of a two-sided 95 % interval


def samples_needed(tally: Tally, precision: float, of: str = "all") -> int:
    """The samples at which every interval the stop rule looks at (``of``) would be
    ``precision`` wide (half-width), by the normal approximation at ``tally``'s estimates (the
    progress bar's total, and the pilot's estimate of a run). A proportion seen none (or all)
    of is taken as one half of a sample in ``n``, not 0: no count says it is exactly 0."""
    n = max(tally.n_counted, 1)
    floor = 0.5 / n

    def var(count: int, total: int) -> float:
        p = min(max(count / max(total, 1), floor), 1 - floor)
        return p * (1 - p)

    spread = [var(tally.standing, n)]
    if of == "all":
        spread += [var(c, n) for c in tally.counted.values()]
        spread.append(var(tally.samples - tally.n_counted, tally.samples))
    share = tally.n_counted / tally.samples if tally.samples else 1.0
    return int(math.ceil(max(spread) * (Z95 / precision) ** 2 / max(share, 1e-9)))


def summary(tally: Tally, verified: bool = True) -> dict:
    """Everything a result reports, as plain values: probabilities over the counted labels with
    their 95 % intervals, the uncertain fraction over all samples with its causes (chaotic:
    decided at every rung compared but no two agree; undecided: a rung not settled within its
    horizon or budget), and the same probabilities over all decided samples (each throw's
    deepest rung, settled: an estimate that keeps the chaotic throws, each with the label its
    finest run gave) and over all labelled samples."""
    counted = tally.n_counted
    standing = tally.standing
    labelled = tally.n_labelled
    standing_all = tally.standing_labelled
    decided = tally.n_decided
    standing_decided = tally.standing_decided
    return {
        "samples": tally.samples,
        "counted": counted,
        "verified": verified,
        "standing": proportion(standing, counted),
        "lying": proportion(counted - standing, counted),
        "uncertain": {**proportion(tally.samples - counted, tally.samples),
                      "chaotic": int(tally.certainty.get(int(Certainty.UNCERTAIN), 0)),
                      "undecided": int(tally.certainty.get(int(Certainty.UNDECIDED), 0))},
        "outcomes": outcome_rows(tally.counted),
        "all_decided": {
            "decided": decided,
            "standing": proportion(standing_decided, decided),
            "lying": proportion(decided - standing_decided, decided),
            "outcomes": outcome_rows(tally.decided),
        },
        "all_labelled": {
            "labelled": labelled,
            "standing": proportion(standing_all, labelled),
            "lying": proportion(labelled - standing_all, labelled),
            "outcomes": outcome_rows(tally.labelled),
        },
        "status": {Status(s).label: int(c) for s, c in sorted(tally.status.items())},
    }


# -- the stop rule ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Goal:
    """When a run is done: a fixed number of ``samples``, or the first batch at which every
    interval looked at (``of``) has half-width <= ``precision``, within ``max_samples``."""

    samples: int | None = None
    precision: float | None = None
    of: str = "all"
    max_samples: int = DEFAULT_MAX_SAMPLES

    def batches(self, batch: int) -> int:
        """The most batches this goal can need."""
        if self.samples is not None:
            return -(-self.samples // batch)
        return -(-self.max_samples // batch)

    def count(self, index: int, batch: int) -> int:
        """Samples of batch ``index`` this goal uses (the last of a fixed count may be part)."""
        if self.samples is not None:
            return max(0, min(batch, self.samples - index * batch))
        return batch

    def to_dict(self) -> dict:
        return {"samples": self.samples, "precision": self.precision, "of": self.of,
                "max_samples": self.max_samples}


def make_goal(samples=None, precision=None, of: str = "all",
              max_samples=DEFAULT_MAX_SAMPLES) -> Goal:
    def whole(option: str, value) -> int:
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
            raise ParameterError(f"{option} must be a whole number of at least 1, got "
                                 f"{value!r}", parameters=(option,))
        return int(value)

    if of not in GOALS:
        raise ParameterError(f"of must be {' or '.join(GOALS)}, got '{of}'", parameters=("of",))
    max_samples = whole("max_samples", max_samples)
    if samples is not None:
        if precision is not None:
            raise ParameterError("give samples (a fixed count) or precision (stop when "
                                 "the intervals are that narrow), not both",
                                 parameters=("samples", "precision"))
        return Goal(samples=whole("samples", samples), of=of, max_samples=max_samples)
    if precision is None:
        precision = DEFAULT_PRECISION
    if isinstance(precision, bool) or not isinstance(precision, int | float) or \
            not math.isfinite(precision) or not 0 < precision < 0.5:
        raise ParameterError(f"precision must be a probability between 0 and 0.5 (the "
                             f"half-width of a 95 % interval), got {precision!r}",
                             parameters=("precision",))
    return Goal(precision=float(precision), of=of, max_samples=max_samples)


def parse_precision(text) -> float | None:
    """``0.001``, ``1e-3`` or ``0.1%`` (percentage points) -> 0.001."""
    if text is None or isinstance(text, int | float):
        return text
    t = str(text).strip()
    scale = 1.0
    if t.endswith("%"):
        t, scale = t[:-1].strip(), 0.01
    try:
        return float(t) * scale
    except ValueError:
        raise ParameterError(f"precision: '{text}' is not a number (0.001, or 0.1% in "
                             "percentage points)", parameters=("precision",)) from None


def parse_count(option: str, text) -> int | None:
    """``4600000``, ``4.6e6``, ``4.6M``, ``16k`` -> a whole number."""
    if text is None or isinstance(text, int):
        return text
    t = str(text).strip().lower().replace("_", "").replace(",", "")
    scale = {"k": 10 ** 3, "m": 10 ** 6, "g": 10 ** 9}.get(t[-1:], 1)
    if scale != 1:
        t = t[:-1]
    try:
        value = float(t) * scale
    except ValueError:
        raise ParameterError(f"{option}: '{text}' is not a whole number",
                             parameters=(option,)) from None
    if not value.is_integer() or value < 1:
        raise ParameterError(f"{option} must be a whole number of at least 1, got '{text}'",
                             parameters=(option,))
    return int(value)


class Progression:
    """The stop rule of one value: batches come in any order; the prefix of consecutive
    complete batches from batch 0 advances, and the goal is tested on each prefix in turn.
    What it decides depends only on the batches' contents, never on their order of arrival."""

    def __init__(self, goal: Goal, batch: int, verified: bool = True):
        self.goal = goal
        self.batch = batch
        self.verified = verified
        self.limit = goal.batches(batch)
        self.tallies: dict[int, Tally] = {}
        self.prefix = 0  # batches 0 .. prefix-1 are complete and counted
        self.tally = Tally()
        self.done = False
        self.reason: StopReason | None = None
        self.issued: set[int] = set()  # batches handed out, not back yet
        self._advance()

    def peek(self) -> int | None:
        """The lowest batch not yet done or handed out, if the run may still need it."""
        index = self.prefix
        while index < self.limit and (index in self.tallies or index in self.issued):
            index += 1
        if self.done or index >= self.limit:
            return None
        return index

    def next_batch(self) -> int | None:
        """:meth:`peek`, and mark that batch as handed out."""
        index = self.peek()
        if index is not None:
            self.issued.add(index)
        return index

    def add(self, index: int, tally: Tally) -> None:
        self.issued.discard(index)
        self.tallies[index] = tally
        self._advance()

    def _advance(self) -> None:
        if self.done:
            return
        while self.prefix in self.tallies and self.prefix < self.limit:
            self.tally = self.tally + self.tallies[self.prefix]
            self.prefix += 1
            if self.goal.precision is not None and precise(self.tally, self.goal.precision,
                                                           self.goal.of):
                self.done, self.reason = True, StopReason.PRECISION
                return
        if self.prefix >= self.limit:
            self.done = True
            self.reason = StopReason.SAMPLES if self.goal.samples is not None else \
                StopReason.BUDGET

    @property
    def samples(self) -> int:
        return self.tally.samples
