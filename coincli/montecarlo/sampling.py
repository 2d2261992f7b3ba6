"""The distributions of the five initial conditions, their parsing, the draws (scrambled Sobol
points or a seeded generator) and the initial states of a batch."""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass

import numpy as np

from ..defaults import DEFAULT_BATCH
from ..params import ParameterError, Scene, check_start
from ..quantities import parse_quantity, parse_span

# The five initial conditions drawn (x0 stays the scene's: the model is translation invariant).
IC5 = ("y0", "phi0", "vx", "vy", "vphi")
UNITS = {"y0": "m", "phi0": "rad", "vx": "m/s", "vy": "m/s", "vphi": "rad/s"}
DEFAULT_DISTRIBUTIONS = {"vy": "0.05:2", "vphi": "-20:20"}  # as coin basin's default axes
SAMPLERS = ("sobol", "random")
SOBOL_MAX = 1 << 30  # scipy's Sobol engine has 30 bits
QUANTILE_CLIP = 2.0 ** -53  # the quantiles a normal is drawn at: [2^-53, 1 - 2^-53]
# how many standard deviations from its mean an untruncated normal's draw may be (|ndtri| at
# QUANTILE_CLIP is 8.21): a normal whose draws would overflow a float is refused (_checked)
NORMAL_REACH = 8.3
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

        u = np.clip(u, QUANTILE_CLIP, 1.0 - QUANTILE_CLIP)  # ndtri(0) is -inf
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


def _number(name: str, text: str) -> tuple[float, bool]:
    """An argument of a distribution (:func:`coincli.quantities.parse_quantity`; ``inf`` for
    a truncation without a bound): (value, whether in multiples of r)."""
    q = parse_quantity(name, text, finite=False)
    return q.value, q.per_r


def _one_unit(name: str, parsed: list[tuple[float, bool]], text: str) -> bool:
    flags = {per_r for value, per_r in parsed if math.isfinite(value)}
    if len(flags) > 1:
        raise ParameterError(f"{name} {text}: give every number in multiples of r (e.g. "
                             "r:5r) or every number in metres, not a mix", parameters=(name,))
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
        raise ParameterError(f"{name}: {value!r} is not a number or a distribution",
                             parameters=(name,))
    if isinstance(value, int | float):
        if not math.isfinite(value):
            raise ParameterError(f"{name} must be finite, got {value}", parameters=(name,))
        return Dist("fixed", float(value))
    if isinstance(value, tuple | list):
        if len(value) != 2:
            raise ParameterError(f"{name}: a range is (LO, HI), got {value!r}", parameters=(name,))
        return parse_dist(name, ":".join(str(v) for v in value))
    if not isinstance(value, str):
        raise ParameterError(f"{name}: {value!r} is not a number or a distribution",
                             parameters=(name,))
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
        raise ParameterError(f"{name}: '{text}' is not a distribution: use a value, LO:HI "
                             "(uniform), normal(MEAN,SD) or normal(MEAN,SD,LO,HI) (truncated)",
                             parameters=(name,))
    span = parse_span(name, text)
    if isinstance(span, tuple):
        lo, hi = span
        return _checked(name, Dist("uniform", lo.value, hi.value, per_r=lo.per_r), text)
    return _checked(name, Dist("fixed", span.value, per_r=span.per_r), text)


def _checked(name: str, d: Dist, text: str) -> Dist:
    if d.kind not in ("fixed", "uniform", "normal"):
        raise ParameterError(f"{name}: unknown distribution kind '{d.kind}'", parameters=(name,))
    if not math.isfinite(d.a) or (d.kind != "fixed" and not math.isfinite(d.b)):
        raise ParameterError(f"{name} {text}: numbers must be finite", parameters=(name,))
    if d.kind == "uniform" and not d.a < d.b:
        raise ParameterError(f"{name} {text}: empty range (LO must be below HI)",
                             parameters=(name,))
    if d.kind == "normal":
        if not d.b > 0:
            raise ParameterError(f"{name} {text}: the standard deviation must be positive",
                                 parameters=(name,))
        if not d.lo < d.hi:
            raise ParameterError(f"{name} {text}: empty truncation (LO must be below HI)",
                                 parameters=(name,))
        if not math.isfinite(abs(d.a) + NORMAL_REACH * d.b):
            raise ParameterError(f"{name} {text}: draws of this normal reach past the largest "
                                 f"float, 1.8e308 (|MEAN| + {NORMAL_REACH:g} SD must stay "
                                 "below it); narrow it", parameters=(name,))
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
        """``y0 = 1r:5r (0.01005:0.05025 m), phi0 = -3.14159:3.14159 rad, ...`` (multiples of r
        also in metres if a scene is given)."""
        parts = []
        for name, d in self.dists:
            text = f"{name} = {d.text(UNITS[name])}"
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
        raise ParameterError(f"sampler must be one of {', '.join(SAMPLERS)}, got "
                             f"'{sampler}'", parameters=("sampler",))
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ParameterError(f"seed must be a whole number >= 0, got {seed!r}",
                             parameters=("seed",))
    if isinstance(batch, bool) or not isinstance(batch, int | np.integer) or \
            not 1 <= batch <= 1 << 20:
        raise ParameterError(f"batch must be a whole number from 1 to {1 << 20}, got "
                             f"{batch!r}", parameters=("batch",))
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
        raise ParameterError("y0: an untruncated normal reaches every height, into the "
                             "foundation; truncate it, e.g. normal(3r,0.5r,r,5r)",
                             parameters=("y0",))
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
                                 "sampler random for more samples", parameters=("sampler",))
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
