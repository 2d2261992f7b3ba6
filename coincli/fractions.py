"""Outcome probabilities by Monte Carlo: P(n), P(standing), P(lying) for throws whose five
initial conditions (y0, phi0, vx, vy, vphi) are drawn from distributions, with 95 % intervals.

Calling this module is the public API's :func:`coincli.api.fractions`::

    import coincli
    result = coincli.fractions(coincli.load_preset("paper"), phi0="0:2pi", precision=0.001)
    result.standing        # {"probability": ..., "low": ..., "high": ..., "count": ..., "of": ...}

This module holds the pure computation (no files, no threads, no terminal): the distributions
and their parsing (:func:`parse_dist`), the draws (:class:`Draws`: scrambled Sobol points or a
seeded generator), the initial states of a batch (:func:`initial_states`), one batch's labels
(:func:`compute_batch`), the counts (:class:`Tally`), the stop rule (:class:`Progression`), the
scenes of a continuation (:func:`scene_at`) and the summaries. :mod:`coincli.api` runs batches
on threads or Dask and :mod:`coincli.io.fractions_store` keeps them in a Zarr store.

Reproducibility
---------------
Sample i depends only on (seed, i, the distributions): Sobol points are generated batch by
batch from one scrambled sequence (``fast_forward`` to the batch's first index), random ones
from ``numpy.random.default_rng([seed, batch])``. The same points serve every value of a
continuation (common random numbers). Batches finish out of order on threads, so the stop rule
is evaluated on the prefix of completed batches *in order*: the same command stops after the
same number of samples however many threads ran it and however often it was resumed.

Probabilities and intervals
---------------------------
Probabilities are taken over the *certain* labels (verified: two successive rungs of the ladder
of settings agree, :mod:`coincli.integrators.ladder`); the *uncertain* fraction (no two rungs
agreed, or no label at all) is reported beside them, over all samples, and so are the
probabilities over *all labelled* samples. Each interval is Wilson's score interval at 95 %
(:func:`coincli.stats.proportion`, scipy's). For independent draws (``sampler="random"``) the
binomial interval is exact in its model; for scrambled Sobol points the estimate's error is in
practice smaller than for independent draws, so the same interval is conservative.

``precision`` is the half-width, (high - low) / 2, of a 95 % interval: a run stops at the first
batch at which that half-width is at most ``precision`` for every probability it is asked about
(``of="all"``: every outcome n, standing, lying and the uncertain fraction; ``of="standing"``:
P(standing) only), or when the sample budget is spent.
"""

from __future__ import annotations

import importlib
import math
import re
import sys
import time
import types
import warnings
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from .enums import Certainty, Status
from .integrators.batch import verified_labels
from .integrators.ladder import Ladder, ladder_of
from .params import (
    ModelParams,
    ParameterError,
    RunSettings,
    Scene,
    check_start,
    model_params,
    run_settings,
    validate,
)
from .stats import outcome_rows, proportion

# The five initial conditions drawn (x0 stays the scene's: the model is translation invariant).
IC5 = ("y0", "phi0", "vx", "vy", "vphi")
UNITS = {"y0": "m", "phi0": "rad", "vx": "m/s", "vy": "m/s", "vphi": "rad/s"}
DEFAULT_DISTRIBUTIONS = {"vy": "0.05:2", "vphi": "-20:20"}  # as coin basin's default axes
SAMPLERS = ("sobol", "random")
GOALS = ("all", "standing")
DEFAULT_BATCH = 8192  # 2^13: Sobol points keep their balance in powers of two
DEFAULT_PRECISION = 0.002  # +- 0.2 percentage points
DEFAULT_MAX_SAMPLES = 1 << 24
SOBOL_MAX = 1 << 30  # scipy's Sobol engine has 30 bits
PARAMETERS = ("thickness", "diameter", "k", "c", "mass", "inertia", "g")
PARAMETER_UNITS = {"thickness": "m", "diameter": "m", "k": "N/m", "c": "N s/m", "mass": "kg",
                   "inertia": "kg m^2", "g": "m/s^2"}
CONFIDENCE = 0.95
INTERVAL_NOTE = ("Wilson score interval at 95 % (scipy): exact in its model for independent "
                 "draws, conservative in practice for scrambled Sobol points")


# -- distributions ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Dist:
    """The distribution of one initial condition.

    ``fixed``: ``a`` always; ``uniform``: on [a, b); ``normal``: mean a, standard deviation b,
    truncated to [lo, hi] (infinite ends: not truncated). ``per_r``: the numbers are multiples of
    the coin's half diagonal r (y0 only), resolved for each scene by :meth:`scaled`."""

    kind: str
    a: float
    b: float = math.nan
    lo: float = -math.inf
    hi: float = math.inf
    per_r: bool = False

    @property
    def random(self) -> bool:
        return self.kind != "fixed"

    def scaled(self, r: float) -> Dist:
        """The distribution in metres for a coin of half diagonal ``r`` (itself if not per r)."""
        if not self.per_r:
            return self
        return Dist(self.kind, self.a * r, self.b * r, self.lo * r, self.hi * r, False)

    def support(self) -> tuple[float, float]:
        if self.kind == "fixed":
            return self.a, self.a
        if self.kind == "uniform":
            return self.a, self.b
        return self.lo, self.hi

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Values at the quantiles ``u`` (in [0, 1)); inverse CDF, so that low-discrepancy
        points stay low-discrepancy."""
        if self.per_r:
            raise ValueError("resolve r first (Dist.scaled)")
        if self.kind == "fixed":
            return np.full(len(u), self.a)
        if self.kind == "uniform":
            return self.a + u * (self.b - self.a)
        from scipy.special import ndtr, ndtri

        u = np.clip(u, 2.0 ** -53, 1.0 - 2.0 ** -53)  # ndtri(0) is -inf
        mean, sd = self.a, self.b
        if math.isinf(self.lo) and math.isinf(self.hi):
            return mean + sd * ndtri(u)
        # truncated: map u into [Phi(lo), Phi(hi)]; on the upper side mirror, so that a far
        # tail keeps its digits (Phi near 1 has none)
        za, zb = (self.lo - mean) / sd, (self.hi - mean) / sd
        if za > 0:
            pa, pb = ndtr(-zb), ndtr(-za)
            x = mean - sd * ndtri(pb - u * (pb - pa))
        else:
            pa, pb = ndtr(za), ndtr(zb)
            x = mean + sd * ndtri(pa + u * (pb - pa))
        return np.clip(x, self.lo, self.hi)

    def to_dict(self) -> dict:
        unit = "r" if self.per_r else None
        if self.kind == "fixed":
            out = {"kind": "fixed", "value": self.a}
        elif self.kind == "uniform":
            out = {"kind": "uniform", "low": self.a, "high": self.b}
        else:
            out = {"kind": "normal", "mean": self.a, "sd": self.b,
                   "truncate": [None if math.isinf(self.lo) else self.lo,
                                None if math.isinf(self.hi) else self.hi]}
        if unit:
            out["unit"] = "r (half diagonal of the coin)"
        return out

    def text(self, unit: str = "") -> str:
        """``0.05:2 m/s``, ``1r:5r``, ``normal(0, 0.3) m/s``, ``0.01 m``."""
        def num(x: float) -> str:
            return f"{x:g}r" if self.per_r else f"{x:g}"

        suffix = "" if self.per_r or not unit else f" {unit}"
        if self.kind == "fixed":
            return num(self.a) + suffix
        if self.kind == "uniform":
            return f"{num(self.a)}:{num(self.b)}{suffix}"
        trunc = "" if math.isinf(self.lo) and math.isinf(self.hi) else \
            f", {num(self.lo)}, {num(self.hi)}"
        return f"normal({num(self.a)}, {num(self.b)}{trunc}){suffix}"


_NUMBER = re.compile(
    r"^(?P<sign>[+-]?)\s*(?P<num>(\d+\.?\d*|\.\d+)(e[+-]?\d+)?)?\s*\*?\s*(?P<unit>pi|r)?"
    r"\s*(/\s*(?P<div>(\d+\.?\d*|\.\d+)(e[+-]?\d+)?))?$", re.IGNORECASE)


def _number(name: str, text: str) -> tuple[float, bool]:
    """``'2pi'`` -> (6.28..., False), ``'5r'`` -> (5.0, True) (a multiple of r), ``'-0.5'``,
    ``'pi/2'``, ``'inf'``."""
    t = text.strip().lower()
    if t in ("inf", "+inf", "-inf"):
        return (-math.inf if t.startswith("-") else math.inf), False
    m = _NUMBER.match(t)
    if not t or m is None or (m.group("num") is None and m.group("unit") is None):
        raise ParameterError(f"--{name}: '{text}' is not a number (like 0.5, 2pi, pi/2"
                             f"{', 5r' if name == 'y0' else ''})")
    value = float(m.group("num")) if m.group("num") else 1.0
    unit = m.group("unit")
    if unit == "pi":
        value *= math.pi
    if m.group("div"):
        value /= float(m.group("div"))
    if m.group("sign") == "-":
        value = -value
    if unit == "r" and name != "y0":
        raise ParameterError(f"--{name}: '{text}': multiples of r are for y0 only")
    if not math.isfinite(value):
        raise ParameterError(f"--{name}: '{text}' is not finite")
    return value, unit == "r"


def _one_unit(name: str, parsed: list[tuple[float, bool]], text: str) -> bool:
    flags = {per_r for value, per_r in parsed if math.isfinite(value)}
    if len(flags) > 1:
        raise ParameterError(f"--{name} {text}: give every number in multiples of r (e.g. "
                             "r:5r) or every number in metres, not a mix")
    return flags == {True}


def parse_dist(name: str, value) -> Dist:
    """A distribution from an option or keyword value.

    - a number, or text like ``0.01``, ``2pi``, ``r`` (y0: a multiple of r): that value, fixed;
    - ``LO:HI`` or a pair ``(lo, hi)``: uniform on [LO, HI);
    - ``normal(MEAN,SD)``, truncated ``normal(MEAN,SD,LO,HI)``;
    - ``uniform(LO,HI)`` and ``fixed(V)`` say the same as the short forms;
    - a :class:`Dist` as it is.
    Numbers may carry ``pi`` (``0:2pi``, ``-pi/2``) and, for y0, ``r`` (``r:5r``)."""
    if name not in IC5:
        raise ParameterError(f"unknown initial condition '{name}'; drawn: {', '.join(IC5)}")
    if isinstance(value, Dist):
        return _checked(name, value, str(value))
    if isinstance(value, bool):
        raise ParameterError(f"--{name}: {value!r} is not a number or a distribution")
    if isinstance(value, int | float):
        if not math.isfinite(value):
            raise ParameterError(f"--{name} must be finite, got {value}")
        return Dist("fixed", float(value))
    if isinstance(value, tuple | list):
        if len(value) != 2:
            raise ParameterError(f"--{name}: a range is (LO, HI), got {value!r}")
        return parse_dist(name, ":".join(str(v) for v in value))
    if not isinstance(value, str):
        raise ParameterError(f"--{name}: {value!r} is not a number or a distribution")
    text = value.strip()
    call = re.fullmatch(r"(?P<fn>[a-z]+)\s*\((?P<args>.*)\)", text, re.IGNORECASE)
    if call:
        fn = call.group("fn").lower()
        args = [a for a in call.group("args").split(",")]
        parsed = [_number(name, a) for a in args]
        per_r = _one_unit(name, parsed, text)
        nums = [v for v, _ in parsed]
        if fn in ("normal", "gauss", "gaussian") and len(nums) in (2, 4):
            lo, hi = (nums[2], nums[3]) if len(nums) == 4 else (-math.inf, math.inf)
            return _checked(name, Dist("normal", nums[0], nums[1], lo, hi, per_r), text)
        if fn == "uniform" and len(nums) == 2:
            return _checked(name, Dist("uniform", nums[0], nums[1], per_r=per_r), text)
        if fn == "fixed" and len(nums) == 1:
            return _checked(name, Dist("fixed", nums[0], per_r=per_r), text)
        raise ParameterError(f"--{name}: '{text}' is not a distribution: use a value, LO:HI "
                             "(uniform), normal(MEAN,SD) or normal(MEAN,SD,LO,HI) (truncated)")
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 2 or not parts[0].strip() or not parts[1].strip():
            raise ParameterError(f"--{name}: '{text}' is not a LO:HI range")
        parsed = [_number(name, p) for p in parts]
        per_r = _one_unit(name, parsed, text)
        return _checked(name, Dist("uniform", parsed[0][0], parsed[1][0], per_r=per_r), text)
    number, per_r = _number(name, text)
    return _checked(name, Dist("fixed", number, per_r=per_r), text)


def _checked(name: str, d: Dist, text: str) -> Dist:
    if d.kind not in ("fixed", "uniform", "normal"):
        raise ParameterError(f"--{name}: unknown distribution kind '{d.kind}'")
    if not math.isfinite(d.a) or (d.kind != "fixed" and not math.isfinite(d.b)):
        raise ParameterError(f"--{name} {text}: numbers must be finite")
    if d.kind == "uniform" and not d.a < d.b:
        raise ParameterError(f"--{name} {text}: empty range (LO must be below HI)")
    if d.kind == "normal":
        if not d.b > 0:
            raise ParameterError(f"--{name} {text}: the standard deviation must be positive")
        if not d.lo < d.hi:
            raise ParameterError(f"--{name} {text}: empty truncation (LO must be below HI)")
    return d


@dataclass(frozen=True)
class Sampling:
    """How the samples are drawn: a distribution for each of the five initial conditions, the
    sampler, its seed and the batch size (the unit of work, of storing and of the stop rule)."""

    dists: tuple[tuple[str, Dist], ...]  # in IC5 order
    sampler: str = "sobol"
    seed: int = 0
    batch: int = DEFAULT_BATCH

    @property
    def by_name(self) -> dict[str, Dist]:
        return dict(self.dists)

    @property
    def random_names(self) -> tuple[str, ...]:
        """The drawn dimensions, in IC5 order (one Sobol coordinate each)."""
        return tuple(name for name, d in self.dists if d.random)

    def to_dict(self) -> dict:
        return {"sampler": self.sampler, "seed": self.seed, "batch": self.batch,
                "dims": list(self.random_names),
                "distributions": {name: d.to_dict() for name, d in self.dists},
                "sample_i": "depends only on (seed, i, distributions): Sobol points "
                            "fast-forwarded to each batch, or default_rng([seed, batch])"}

    def describe(self, scene: Scene | None = None) -> str:
        """``y0 1r:5r (0.01005:0.05025 m), phi0 -3.14159:3.14159 rad, ...`` (multiples of r
        also in metres if a scene is given)."""
        parts = []
        for name, d in self.dists:
            text = f"{name} {d.text(UNITS[name])}"
            if scene is not None and d.per_r:
                text += f" ({d.scaled(scene.coin.r).text(UNITS[name])})"
            parts.append(text)
        return ", ".join(parts)


def make_sampling(scene: Scene, *, sampler: str = "sobol", seed: int = 0,
                  batch: int = DEFAULT_BATCH, **options) -> Sampling:
    """The sampling of ``options`` (name -> distribution, see :func:`parse_dist`); an initial
    condition not given keeps the scene's value, except vy and vphi, which are drawn uniform
    over coin basin's default ranges, and y0, which is the scene's y0 (r unless the preset
    says otherwise, as a multiple of r so that it follows the coin in a continuation)."""
    unknown = set(options) - set(IC5)
    if unknown:
        raise ParameterError(f"unknown initial condition(s) {sorted(unknown)}; drawn: "
                             f"{', '.join(IC5)}")
    if sampler not in SAMPLERS:
        raise ParameterError(f"--sampler must be one of {', '.join(SAMPLERS)}, got "
                             f"'{sampler}'")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ParameterError(f"--seed must be a whole number >= 0, got {seed!r}")
    if isinstance(batch, bool) or not isinstance(batch, int | np.integer) or \
            not 1 <= batch <= 1 << 20:
        raise ParameterError(f"--batch must be a whole number from 1 to {1 << 20}, got "
                             f"{batch!r}")
    dists = []
    for name in IC5:
        value = options.get(name)
        if value is None:
            if name in DEFAULT_DISTRIBUTIONS:
                value = DEFAULT_DISTRIBUTIONS[name]
            elif name == "y0":
                value = Dist("fixed", 1.0, per_r=True) if scene.initial.y0 is None \
                    else float(scene.initial.y0)
            else:
                value = float(getattr(scene.initial, name))
        dists.append((name, parse_dist(name, value)))
    return Sampling(tuple(dists), sampler, int(seed), int(batch))


def max_reach(scene: Scene, phi_lo: float, phi_hi: float) -> tuple[float, float]:
    """(deepest reach below the centroid r_d |sin phi| + r_t |cos phi|, the angle reaching it)
    over phi in [phi_lo, phi_hi]: r where a diagonal can be vertical, else at an end."""
    r_d, r_t = scene.coin.r_d, scene.coin.r_t

    def reach(phi: float) -> float:
        return r_d * abs(math.sin(phi)) + r_t * abs(math.cos(phi))

    if not (math.isfinite(phi_lo) and math.isfinite(phi_hi)) or phi_hi - phi_lo >= math.pi:
        return scene.coin.r, scene.coin.phi_cr
    peak = scene.coin.phi_cr  # reach = r at +-phi_cr + k pi
    for base in (peak, math.pi - peak):
        k = math.ceil((phi_lo - base) / math.pi)
        if base + k * math.pi <= phi_hi:
            return scene.coin.r, base + k * math.pi
    return max((reach(phi_lo), phi_lo), (reach(phi_hi), phi_hi))


def check_box(scene: Scene, sampling: Sampling) -> None:
    """Refuse (one line) a sampling that can start a corner deeper in the foundation than the
    scene allows (coincli.params.check_start), judged on the distributions' supports: the
    lowest y0 with the angle reaching furthest down."""
    dists = {name: d.scaled(scene.coin.r) for name, d in sampling.dists}
    y_lo, _ = dists["y0"].support()
    if not math.isfinite(y_lo):
        raise ParameterError("--y0: an untruncated normal reaches every height, into the "
                             "foundation; truncate it, e.g. normal(3r,0.5r,r,5r)")
    phi_lo, phi_hi = dists["phi0"].support()
    _, phi = max_reach(scene, phi_lo, phi_hi)
    try:
        check_start(scene, y_lo, phi)
    except ParameterError as exc:
        raise ParameterError(f"the lowest start drawn is refused: {exc}; raise y0's lower end "
                             "(y0 from r up starts every pose above the foundation)") from None


def initial_states(scene: Scene, sampling: Sampling, u: np.ndarray) -> np.ndarray:
    """The initial states (N x 6: x, y, phi, vx, vy, vphi) at the points ``u`` (N x D in
    [0, 1), one column per drawn dimension) for ``scene`` (r of its coin)."""
    n = u.shape[0]
    states = np.empty((n, 6), dtype=np.float64)
    states[:, 0] = scene.initial.x0
    column = 0
    for index, (_name, d) in enumerate(sampling.dists, start=1):
        d = d.scaled(scene.coin.r)
        if d.random:
            states[:, index] = d.ppf(u[:, column])
            column += 1
        else:
            states[:, index] = d.a
    return states


class Draws:
    """The points in [0, 1)^D of each batch, reproducible from the seed: batch b holds samples
    b * batch ... (b + 1) * batch - 1. Sobol points come from one scrambled sequence, kept at
    its position between consecutive batches (fast-forwarded when a batch is skipped); recent
    batches are cached, since a continuation draws the same points for every value."""

    def __init__(self, sampling: Sampling, cache: int = 32):
        self.sampling = sampling
        self.dims = len(sampling.random_names)
        self._engine = None
        self._position = 0
        self._cache: dict[int, np.ndarray] = {}
        self._cache_size = cache

    def batch(self, index: int) -> np.ndarray:
        if index in self._cache:
            return self._cache[index]
        b = self.sampling.batch
        if self.dims == 0:
            points = np.empty((b, 0))
        elif self.sampling.sampler == "random":
            points = np.random.default_rng([self.sampling.seed, index]).random((b, self.dims))
        else:
            points = self._sobol(index * b, b)
        self._cache[index] = points
        while len(self._cache) > self._cache_size:
            del self._cache[min(self._cache)]
        return points

    def _sobol(self, start: int, count: int) -> np.ndarray:
        from scipy.stats import qmc

        if start + count > SOBOL_MAX:
            raise ParameterError(f"a Sobol sequence has {SOBOL_MAX:,} points; use "
                                 "--sampler random for more samples")
        if self._engine is None or start < self._position:
            try:
                self._engine = qmc.Sobol(self.dims, scramble=True, rng=self.sampling.seed)
            except TypeError:  # scipy < 1.15 names it seed (the same generator from an int)
                self._engine = qmc.Sobol(self.dims, scramble=True, seed=self.sampling.seed)
            self._position = 0
        if start > self._position:
            self._engine.fast_forward(start - self._position)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "balance properties ... power of 2": by batch
            points = self._engine.random(count)
        self._position = start + count
        return points


# -- one batch ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class FractionSpec:
    """What a batch of one scene needs, as plain picklable values (shipped to Dask workers)."""

    params: ModelParams
    settings: RunSettings
    ladder: Ladder


def make_fraction_spec(scene: Scene) -> FractionSpec:
    return FractionSpec(model_params(scene), run_settings(scene.integration),
                        ladder_of(scene.integration))


@dataclass(frozen=True)
class BatchTask:
    """One unit of work: ``count`` samples of batch ``batch`` for value ``value`` (0 for a
    plain run), from these initial states."""

    value: int
    batch: int
    count: int
    states: np.ndarray


@dataclass
class BatchResult:
    value: int
    batch: int
    count: int
    states: np.ndarray  # count x 6
    labels: dict  # name -> array of count (quarter_turns, status, settle_time, steps, ...)
    cpu_seconds: float


LABEL_NAMES = ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung")


def compute_batch(spec: FractionSpec, task: BatchTask, control=None) -> BatchResult:
    """Run every sample of a batch up the verification ladder (compiled; releases the GIL)."""
    cpu0 = time.thread_time()
    states = np.ascontiguousarray(task.states[:task.count], dtype=np.float64)
    out = verified_labels(spec.params, spec.settings, spec.ladder, states, control)
    labels = {name: getattr(out, name) for name in LABEL_NAMES}
    return BatchResult(task.value, task.batch, task.count, states, labels,
                       time.thread_time() - cpu0)


# -- counts -------------------------------------------------------------------------------------
@dataclass
class Tally:
    """Counts of a set of samples. ``counted``: the labels probabilities are taken over (certain
    ones; for a single pass, the settled ones); ``labelled``: every sample with a label
    (settled, or unsettled at t_end)."""

    samples: int = 0
    counted: Counter = field(default_factory=Counter)  # n -> count
    labelled: Counter = field(default_factory=Counter)  # n -> count
    status: Counter = field(default_factory=Counter)  # Status value -> count

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
        t = cls(samples=int(q.size))
        t.counted.update(dict(zip(*np.unique(q[counted], return_counts=True), strict=True)))
        t.labelled.update(dict(zip(*np.unique(q[labelled], return_counts=True), strict=True)))
        t.status.update(dict(zip(*np.unique(st, return_counts=True), strict=True)))
        t.counted = Counter({int(k): int(v) for k, v in t.counted.items()})
        t.labelled = Counter({int(k): int(v) for k, v in t.labelled.items()})
        t.status = Counter({int(k): int(v) for k, v in t.status.items()})
        return t

    def __add__(self, other: Tally) -> Tally:
        return Tally(self.samples + other.samples, self.counted + other.counted,
                     self.labelled + other.labelled, self.status + other.status)

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


def samples_needed(tally: Tally, precision: float, of: str = "all") -> int:
    """A guess of the samples the stop rule will need (normal approximation at the current
    estimates; for the progress bar only)."""
    z = 1.959963984540054
    counted = max(tally.n_counted, 1)
    props = [tally.standing / counted]
    if of == "all":
        props += [c / counted for c in tally.counted.values()]
        props.append((tally.samples - tally.n_counted) / max(tally.samples, 1))
    share = tally.n_counted / tally.samples if tally.samples else 1.0
    need = max(p * (1 - p) for p in props) * (z / precision) ** 2
    return int(math.ceil(need / max(share, 1e-9)))


def summary(tally: Tally, verified: bool = True) -> dict:
    """Everything a result reports, as plain values: probabilities over the counted labels with
    their 95 % intervals, the uncertain fraction over all samples, and the same over all
    labelled samples."""
    counted = tally.n_counted
    standing = tally.standing
    labelled = tally.n_labelled
    standing_all = tally.standing_labelled
    return {
        "samples": tally.samples,
        "counted": counted,
        "verified": verified,
        "standing": proportion(standing, counted),
        "lying": proportion(counted - standing, counted),
        "uncertain": proportion(tally.samples - counted, tally.samples),
        "outcomes": outcome_rows(tally.counted),
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
                                 f"{value!r}")
        return int(value)

    if of not in GOALS:
        raise ParameterError(f"--of must be one of {', '.join(GOALS)}, got '{of}'")
    max_samples = whole("--max-samples", max_samples)
    if samples is not None:
        if precision is not None:
            raise ParameterError("give --samples (a fixed count) or --precision (stop when "
                                 "the intervals are that narrow), not both")
        return Goal(samples=whole("--samples", samples), of=of, max_samples=max_samples)
    if precision is None:
        precision = DEFAULT_PRECISION
    if isinstance(precision, bool) or not isinstance(precision, int | float) or \
            not math.isfinite(precision) or not 0 < precision < 0.5:
        raise ParameterError(f"--precision must be a probability between 0 and 0.5 (the "
                             f"half-width of a 95 % interval), got {precision!r}")
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
        raise ParameterError(f"--precision: '{text}' is not a number (0.001, or 0.1% in "
                             "percentage points)") from None


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
        raise ParameterError(f"{option}: '{text}' is not a whole number") from None
    if not value.is_integer() or value < 1:
        raise ParameterError(f"{option} must be a whole number of at least 1, got '{text}'")
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
        self.reason: str | None = None
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
                self.done, self.reason = True, "precision"
                return
        if self.prefix >= self.limit:
            self.done = True
            self.reason = "samples" if self.goal.samples is not None else "budget"

    @property
    def samples(self) -> int:
        return self.tally.samples


# -- continuation -------------------------------------------------------------------------------
def parse_over(text: str) -> tuple[str, np.ndarray]:
    """``thickness=0.001:0.02:20`` -> ('thickness', linspace(0.001, 0.02, 20))."""
    m = re.fullmatch(r"\s*([a-z_]+)\s*=\s*([^:]+):([^:]+):([^:]+)\s*", str(text), re.IGNORECASE)
    if m is None:
        raise ParameterError(f"--over '{text}' is not NAME=LO:HI:STEPS (e.g. "
                             "thickness=0.001:0.02:20)")
    name = m.group(1).lower()
    if name not in PARAMETERS:
        raise ParameterError(f"--over {name}: not a physical parameter; one of "
                             f"{', '.join(PARAMETERS)}")
    try:
        lo, hi = float(m.group(2)), float(m.group(3))
        steps = float(m.group(4))
    except ValueError:
        raise ParameterError(f"--over '{text}': LO, HI and STEPS must be numbers") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
        raise ParameterError(f"--over '{text}': LO must be below HI")
    if not steps.is_integer() or not 2 <= steps <= 10_000:
        raise ParameterError(f"--over '{text}': STEPS must be a whole number from 2 to 10000")
    return name, np.linspace(lo, hi, int(steps))


def disc_density(scene: Scene) -> float:
    """kg/m^3 of the scene's coin as a solid disc of its diameter and thickness."""
    c = scene.coin
    return c.mass / (math.pi * c.r_d ** 2 * c.thickness)


def disc_inertia(mass: float, diameter: float, thickness: float) -> float:
    """A uniform solid disc turning about a diameter: m (3 (d/2)^2 + t^2) / 12."""
    return mass * (3 * (diameter / 2) ** 2 + thickness ** 2) / 12


def lamina_inertia(mass: float, diameter: float, thickness: float) -> float:
    """A rectangle lamina d x t turning in its plane: m (d^2 + t^2) / 12 (the square coin)."""
    return mass * (diameter ** 2 + thickness ** 2) / 12


def scene_at(scene: Scene, parameter: str, value: float, keep: tuple[str, ...] = ()) -> Scene:
    """The scene with ``parameter`` set to ``value``. For thickness and diameter, the mass and
    the inertia follow a uniform solid disc of the base coin's density (m = rho pi (d/2)^2 t,
    I = m (3 (d/2)^2 + t^2) / 12), except those named in ``keep``, which keep the scene's."""
    if parameter not in PARAMETERS:
        raise ParameterError(f"cannot vary '{parameter}'; one of {', '.join(PARAMETERS)}")
    new = scene.with_overrides(**{parameter: float(value)})
    if parameter in ("thickness", "diameter"):
        c = new.coin
        mass = c.mass if "mass" in keep else \
            disc_density(scene) * math.pi * c.r_d ** 2 * c.thickness
        inertia = c.inertia if "inertia" in keep else \
            disc_inertia(mass, c.diameter, c.thickness)
        new = new.with_overrides(mass=mass, inertia=inertia)
    return validate(new)


def continuation_note(scene: Scene, parameter: str, keep: tuple[str, ...] = ()) -> str | None:
    """What a user must know about the scenes of a continuation in thickness or diameter."""
    if parameter not in ("thickness", "diameter"):
        return None
    follow = [name for name in ("mass", "inertia") if name not in keep]
    if not follow:
        return "mass and inertia are held at the scene's values at every " + parameter
    c = scene.coin
    disc_i = disc_inertia(c.mass, c.diameter, c.thickness)
    text = (f"{' and '.join(follow)} follow{'s' if len(follow) == 1 else ''} a uniform solid "
            f"disc of the base coin's density ({disc_density(scene):.5g} kg/m^3): "
            "m = rho pi (d/2)^2 t, I = m (3 (d/2)^2 + t^2) / 12")
    if "inertia" in follow and abs(disc_i - c.inertia) > 1e-3 * c.inertia:
        paper = " printed in the paper" if abs(c.inertia - 7.06e-8) < 1e-12 else ""
        text += (f"; at the base coin (d = {c.diameter:g} m, t = {c.thickness:g} m) the "
                 f"disc's I is {disc_i:.3g} kg m^2, not the scene's {c.inertia:.3g}{paper}: "
                 "the curve does not pass through the base scene")
    if keep:
        text += f"; {' and '.join(keep)} held at the scene's value"
    return text


def pender_uhrin(ratio) -> np.ndarray:
    """P(standing) of a planar die with sides d and t = ratio d after Pender and Uhrin
    (arXiv:1407.6307): P(edge) / P(face) = (sqrt(d^2 + t^2) - d) / (sqrt(d^2 + t^2) - t)
    * arctan(t / d) / arctan(d / t), i.e. the ratio of the energy barriers times the ratio of
    the angular widths of the wells (a die with random orientation rolling through many
    revolutions on a bouncy or grippy surface). 1/2 for a square, 3.7e-4 for t/d = 0.1."""
    x = np.asarray(ratio, dtype=np.float64)
    hyp = np.hypot(1.0, x)
    odds = (hyp - 1.0) / (hyp - x) * np.arctan(x) / np.arctan(1.0 / x)
    return odds / (1.0 + odds)


# -- results ------------------------------------------------------------------------------------
@dataclass
class Fractions:
    """The outcome probabilities of one scene (see the module docstring for the definitions).

    ``standing``, ``lying``: over the counted (certain) labels; ``uncertain``: over all samples;
    ``outcomes``: one row per n; each a dict with ``probability``, ``low``, ``high`` (the 95 %
    Wilson interval), ``count`` and ``of``. ``all_labelled`` holds the same over every labelled
    sample. ``stopped`` says why the run ended: ``precision``, ``samples``, ``budget`` or
    ``interrupted``."""

    samples: int
    counted: int
    standing: dict
    lying: dict
    uncertain: dict
    outcomes: list[dict]
    all_labelled: dict
    status: dict
    verified: bool
    stopped: str
    goal: dict
    achieved: float  # the widest half-width the stop rule looks at
    sampling: dict
    scene: dict
    cost: dict = field(default_factory=dict)
    store: str | None = None
    parameter: str | None = None  # of a continuation: the parameter and this value
    value: float | None = None

    @property
    def interrupted(self) -> bool:
        return self.stopped == "interrupted"

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
            "outcomes": self.outcomes, "all_labelled": self.all_labelled,
            "status": self.status, "stopped": self.stopped,
            "precision": {**self.goal, "achieved_half_width": self.achieved},
            "interval": INTERVAL_NOTE, "sampling": self.sampling, "parameters": self.scene,
            "cost": self.cost, "store": self.store,
        }
        if self.parameter is not None:
            out = {"parameter": self.parameter, "value": self.value, **out}
        return out


def make_result(progression: Progression, sampling: Sampling, scene: Scene, stopped: str,
                cost: dict, store: str | None = None, parameter: str | None = None,
                value: float | None = None) -> Fractions:
    s = summary(progression.tally, progression.verified)
    return Fractions(samples=s["samples"], counted=s["counted"], standing=s["standing"],
                     lying=s["lying"], uncertain=s["uncertain"], outcomes=s["outcomes"],
                     all_labelled=s["all_labelled"], status=s["status"],
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

    def to_dict(self) -> dict:
        return {"parameter": self.parameter, "units": PARAMETER_UNITS[self.parameter],
                "values": list(self.values), "note": self.note, "cost": self.cost,
                "store": self.store, "results": [r.to_dict() for r in self.results]}


# -- `coincli.fractions(...)` -------------------------------------------------------------------
class _CallableModule(types.ModuleType):
    """``coincli.fractions(scene, ...)`` is :func:`coincli.api.fractions`: the module is the
    public name of the computation and callable as it (the API is loaded on the first call;
    this module itself depends on nothing above the analysis layer)."""

    def __call__(self, *args, **kwargs):
        return importlib.import_module("coincli.api").fractions(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule


__all__ = ["BatchResult", "BatchTask", "DEFAULT_BATCH", "DEFAULT_MAX_SAMPLES",
           "DEFAULT_PRECISION", "Dist", "Draws", "FractionSpec", "Fractions", "FractionsOver",
           "Goal", "IC5", "PARAMETERS", "Progression", "Sampling", "Tally",
           "check_box", "compute_batch", "continuation_note", "disc_inertia", "half_widths",
           "initial_states", "lamina_inertia", "make_fraction_spec", "make_goal", "make_result",
           "make_sampling", "max_reach", "parse_count", "parse_dist", "parse_over",
           "parse_precision", "pender_uhrin", "precise", "samples_needed",
           "scene_at", "summary", "widest", "wilson_arrays"]
