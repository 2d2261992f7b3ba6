"""How fractal are a basin's boundaries: the estimators of :mod:`coincli.boundary` applied to a
coin basin, on the whole map and per band of its first swept axis (vy0 by default: the throw's
energy).

On the finished map (the store's labels; uncertain and not-computed cells are not evidence):
basin entropy S_b and boundary basin entropy S_bb in boxes of ``box`` cells with the log-2
criterion (Daza et al. 2016), the ball test for fractal boundaries (Puy et al. 2021), the
uncertainty exponent by box counting (Attractors.jl's estimator, for comparison) and the Wada
merging test (Daza et al. 2018).

With the simulator itself: the uncertainty exponent alpha by the perturbation method (McDonald,
Grebogi, Ott and Yorke 1985). ``points`` initial conditions are drawn uniformly over the map's
region, each is perturbed by eps (relative to each swept axis's range, in a random direction) for
eps over several decades far below the grid spacing, and the point and its two perturbations
are classified with *verified* labels (the store's ladder of settings). Only triples whose three
labels are certain count; the others are reported as the uncertain fraction. The points of each
band give that band's f(eps); their union (drawn uniformly over the whole region) gives the
whole map's. alpha is the slope of log f against log eps, D = 2 - alpha the boundary's
box-counting dimension.

Pure computation: arrays and the store's attributes in, dataclasses out; the API reads stores,
:mod:`coincli.charts.analysis` draws, the CLI prints.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from .boundary import (
    LOG2,
    BasinEntropy,
    FractalTest,
    GridUncertainty,
    UncertainFraction,
    UncertaintyExponent,
    WadaResult,
    basin_entropy,
    basins_fractal_test,
    boundary_by_band,
    fit_uncertainty_exponent,
    local_exponents,
    pool_uncertain_fractions,
    uncertain_fraction,
    uncertainty_exponent_grid,
    wada_merge,
)
from .defaults import IC_NAMES
from .enums import Certainty, Status
from .labeller import Labeller, new_control
from .params import ParameterError, scene_from_dict

DEFAULT_POINTS = 150_000  # about a minute for the default 512 x 512 basin on 2 cores
# eps relative to each axis's range, one value per decade. The default grid spacing is 1/511 ~
# 2e-3; at 1e-3 the uncertain fraction of the highest band nears 0.9 (no longer a power law),
# so the window stops 20 times below the spacing.
DEFAULT_EPS = (1e-9, 1e-4)
DEFAULT_EPS_VALUES = 6
DEFAULT_BOX = 5
DEFAULT_BANDS = 4
DEFAULT_RADIUS = 5.0
DEFAULT_BALLS = 1000
DEFAULT_MAX_DILATION = 6
CHUNK = 1024  # points per task of the classification threads


@dataclass(frozen=True)
class AnalysisOptions:
    """The settings of one analysis (all have defaults; see :func:`analyze_basin`)."""

    box: int = DEFAULT_BOX
    bands: int = DEFAULT_BANDS
    points: int = DEFAULT_POINTS
    eps: tuple[float, ...] = tuple(np.logspace(math.log10(DEFAULT_EPS[0]),
                                               math.log10(DEFAULT_EPS[1]),
                                               DEFAULT_EPS_VALUES).tolist())
    seed: int = 0
    threads: int = 2
    radius: float = DEFAULT_RADIUS
    balls: int = DEFAULT_BALLS
    max_dilation: int = DEFAULT_MAX_DILATION
    direction: str = "random"
    confidence: float = 0.95

    def check(self, shape: tuple[int, int]) -> None:
        """ParameterError (one line) for settings that cannot apply to a map of ``shape``."""
        rows = shape[0] // self.box if self.box >= 1 else 0
        if self.box < 1 or self.box > min(shape):
            raise ParameterError(f"box must be between 1 and {min(shape)} cells (the map is "
                                 f"{shape[0]} x {shape[1]}), got {self.box}", parameters=("box",))
        if not 1 <= self.bands <= rows:
            raise ParameterError(f"bands must be between 1 and {rows} (the rows of boxes of "
                                 f"{self.box} cells), got {self.bands}", parameters=("bands",))
        if self.points < 0:
            raise ParameterError(f"points must be at least 0 (0 skips the perturbation "
                                 f"method), got {self.points}", parameters=("points",))
        eps = np.asarray(self.eps, dtype=float)
        if eps.size < 2 or not np.all(np.isfinite(eps)) or np.any(eps <= 0) or np.any(eps >= 0.1):
            raise ParameterError("eps must be at least 2 values between 0 and 0.1 (relative to "
                                 f"each axis's range), got {list(self.eps)}")
        if self.threads < 1:
            raise ParameterError(f"threads must be at least 1, got {self.threads}",
                                 parameters=("threads",))
        if not 1 <= self.radius or not math.isfinite(self.radius):
            raise ParameterError(f"radius must be at least 1 cell, got {self.radius}",
                                 parameters=("radius",))
        if self.balls < 100:
            raise ParameterError(f"balls must be at least 100, got {self.balls}",
                                 parameters=("balls",))
        if self.max_dilation < 1:
            raise ParameterError(f"max_dilation must be at least 1, got {self.max_dilation}",
                                 parameters=("max_dilation",))
        if not (isinstance(self.confidence, int | float) and 0.0 < self.confidence < 1.0):
            raise ParameterError(f"confidence must be between 0 and 1 (e.g. 0.95), got "
                                 f"{self.confidence!r}")
        d = self.direction
        index = isinstance(d, int | np.integer) and not isinstance(d, bool) and \
            0 <= d < len(shape)
        if not index and d not in ("random", "axis"):
            raise ParameterError(f"direction must be 'random', 'axis' or an axis index "
                                 f"({', '.join(map(str, range(len(shape))))}), got {d!r}")


@dataclass(frozen=True, eq=False)
class RegionAnalysis:
    """The measures of one region: the whole map, or one band of its first axis.

    ``rows`` are the map's cells along the first axis used by the grid measures (whole boxes
    only); ``span`` is the range of the first axis from which the perturbation points were
    drawn (the whole band, edges between cells). Measures that cannot be made (a band too thin
    for the ball test, no points) are None."""

    name: str
    rows: tuple[int, int]
    span: tuple[float, float]
    cells: int
    evidence_cells: int  # cells whose label counts (certain)
    entropy: BasinEntropy
    fractal_test: FractalTest | None
    wada: WadaResult
    grid_exponent: GridUncertainty | None
    perturbation: UncertainFraction | None
    exponent: UncertaintyExponent | None
    fractal_test_error: str | None = None

    @property
    def uncertain_cells(self) -> float:
        """Fraction of the region's cells that are not evidence (uncertain, not computed)."""
        return 1.0 - self.evidence_cells / self.cells if self.cells else math.nan

    @property
    def uncertain_fraction(self) -> float:
        """Fraction of the perturbation triples left out because a label was not certain
        (over every eps), NaN without points: the "left out" column of coin basin analyze
        (the name is that of the JSON key, kept for the stores and scripts that read it)."""
        pert = self.perturbation
        if pert is None or pert.n_points == 0:
            return math.nan
        return float(pert.excluded.sum()) / (pert.n_points * pert.eps.size)

    @property
    def alpha(self) -> float:
        return math.nan if self.exponent is None else self.exponent.alpha

    def to_dict(self, axis_name: str) -> dict:
        e, ft, w, ex = self.entropy, self.fractal_test, self.wada, self.exponent
        out = {
            "name": self.name,
            "range": {axis_name: list(self.span)},
            "rows": list(self.rows),
            "basin_entropy": e.basin_entropy,
            "boundary_basin_entropy": e.boundary_basin_entropy,
            "box": list(e.box),
            "fractal_boundary": e.fractal_boundary,
            "fractal_boundary_rule": "S_bb > log 2 (Daza et al. 2016): sufficient, not "
                                     "necessary",
            "fractal_test": None if ft is None else {
                "fractal": ft.fractal, "verdict": ft.verdict,
                "rule": "ball test of Puy et al. 2021 (Attractors.jl's basins_fractal_test): "
                        "S_bb in random balls outside the smooth band",
                "boundary_basin_entropy": ft.boundary_basin_entropy, "stderr": ft.stderr,
                "smooth_value": ft.smooth_value, "smooth_band": [ft.low, ft.high],
                "radius": ft.radius, "balls": ft.balls, "tries": ft.tries,
                "excluded_balls": ft.excluded_balls, "note": ft.note},
            "uncertainty_exponent": None if ex is None else ex.alpha,
            "uncertainty_exponent_interval": None if ex is None else [ex.alpha_low,
                                                                     ex.alpha_high],
            "boundary_dimension": None if ex is None else ex.boundary_dimension,
            "boundary_dimension_interval": None if ex is None else [2 - ex.alpha_high,
                                                                   2 - ex.alpha_low],
            "uncertain_fraction": self.uncertain_fraction,
            "wada": w.is_wada,
            "wada_test": {"is_wada": w.is_wada, "classes": w.n_classes, "dilation": w.dilation,
                          "hausdorff_distance": w.hausdorff_distance,
                          "max_dilation": w.max_dilation,
                          "failing_fraction": w.failing_fraction, "worst_pair": w.worst_pair,
                          "reason": w.reason},
            "cells": self.cells,
            "evidence_cells": self.evidence_cells,
            "uncertain_cells": self.uncertain_cells,
            "n_classes": e.n_classes,
            "entropy_boxes": {"boxes": e.boxes, "boundary_boxes": e.boundary_boxes,
                              "excluded_boxes": e.excluded_boxes},
        }
        if self.fractal_test_error:
            out["fractal_test_error"] = self.fractal_test_error
        g = self.grid_exponent
        out["uncertainty_exponent_grid"] = None if g is None else {
            "alpha": g.alpha, "interval": [g.exponent.alpha_low, g.exponent.alpha_high],
            "box_sizes": [int(g.eps[0]), int(g.eps[-1])],
            "method": "box counting on the finished map (Attractors.jl's uncertainty_exponent)"}
        p = self.perturbation
        out["perturbation"] = None if p is None else {
            "points": p.n_points, "eps": p.eps, "fraction": p.fraction,
            "uncertain": p.uncertain, "evidence": p.evidence, "excluded": p.excluded,
            "ci_low": p.ci_low, "ci_high": p.ci_high, "confidence": p.confidence,
            "direction": p.direction,
            "local_exponents": local_exponents(p),
            "fit": None if ex is None else {
                "alpha": ex.alpha, "stderr": ex.alpha_stderr, "intercept": ex.intercept,
                "eps_used": ex.eps, "dropped": ex.dropped, "reason": ex.reason}}
        return out


@dataclass(frozen=True, eq=False)
class BasinAnalysis:
    """The result of :func:`analyze_basin` (and ``coincli.analyze``)."""

    whole: RegionAnalysis
    bands: tuple[RegionAnalysis, ...]
    axes: tuple[dict, dict]  # the store's sweep axes (name, lo, hi, n, units, long_name)
    fixed: dict  # the initial values not swept
    options: AnalysisOptions
    verified: bool  # the store's labels were verified on a ladder (evidence = certain)
    trajectories: int  # simulator runs of the perturbation method (rungs not counted)
    seconds: dict = field(default_factory=dict)  # wall seconds per stage, and "total"
    cpu_seconds: dict = field(default_factory=dict)  # process CPU seconds (all threads), same keys
    parameters: dict = field(default_factory=dict)  # the store's physical parameters (its
    # coin and foundation: mu among them with friction)

    @property
    def friction(self) -> float:
        """The store's friction coefficient mu (0: the paper's frictionless model)."""
        return float(self.parameters.get("foundation", {}).get("mu") or 0.0)

    @property
    def band_axis(self) -> dict:
        return self.axes[0]

    def __repr__(self) -> str:  # one line in a notebook; everything: to_dict()
        w = self.whole
        parts = [f"S_b = {w.entropy.basin_entropy:.3g}",
                 f"S_bb = {w.entropy.boundary_basin_entropy:.3g}"]
        if w.exponent is not None and math.isfinite(w.exponent.alpha):
            parts.append(f"alpha = {w.exponent.alpha:.3g} [{w.exponent.alpha_low:.3g}, "
                         f"{w.exponent.alpha_high:.3g}]")
        parts.append(f"Wada: {'yes' if w.wada.is_wada else 'no'}")
        names = " x ".join(a["name"] for a in self.axes)
        return (f"BasinAnalysis({names}, whole map: {', '.join(parts)}; "
                f"{len(self.bands)} band{'s' * (len(self.bands) != 1)} of "
                f"{self.axes[0]['name']})")

    def to_dict(self) -> dict:
        name = self.axes[0]["name"]
        o = self.options
        return {
            **self.whole.to_dict(name),
            "bands": [b.to_dict(name) for b in self.bands],
            "band_axis": name,
            "axes": list(self.axes),
            "fixed": self.fixed,
            "parameters": self.parameters,
            "verified": self.verified,
            "evidence": ("labels certain on the store's ladder of settings" if self.verified
                         else "settled labels of a single pass (the store is not verified)"),
            "settings": {"box": o.box, "bands": o.bands, "points": o.points,
                         "eps": list(o.eps), "eps_relative_to": "each swept axis's range",
                         "grid_spacing_relative": [1.0 / (a["n"] - 1) for a in self.axes],
                         "seed": o.seed, "threads": o.threads, "radius": o.radius,
                         "balls": o.balls, "max_dilation": o.max_dilation,
                         "direction": o.direction, "confidence": o.confidence},
            "trajectories": self.trajectories,
            "seconds": self.seconds,
            "cpu_seconds": self.cpu_seconds,
        }


# -- the classifier the perturbation method calls --------------------------------------------
class VerifiedClassifier:
    """``classify(points) -> (labels, certain)`` for :func:`coincli.boundary.uncertain_fraction`:
    points are values of the two swept initial conditions (M x 2), the other four fixed; each is
    run up the ladder (its Labeller) on ``threads`` threads (the kernel releases the GIL).
    A label counts when it is certain (or, for a single-pass ladder, when the run settled).
    Setting ``stop`` (an Event) or Ctrl-C stops the kernels and raises KeyboardInterrupt."""

    def __init__(self, labeller: Labeller, base_state, axes: Sequence[int], *,
                 threads: int = 2, progress: Callable[[int], None] | None = None, stop=None):
        self.labeller = labeller
        self.base = np.asarray(base_state, dtype=np.float64)
        self.axes = list(axes)
        self.threads = max(1, int(threads))
        self.progress = progress
        self.stop = stop
        self.control = new_control()
        self.runs = 0
        self._pool = None

    def __enter__(self):
        self._pool = ThreadPoolExecutor(max_workers=self.threads,
                                        thread_name_prefix="coin-analyze")
        return self

    def __exit__(self, *exc):
        self.control[0] = 1 if exc[0] is not None else self.control[0]
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._pool = None
        return False

    def states(self, points: np.ndarray) -> np.ndarray:
        st = np.empty((points.shape[0], 6), dtype=np.float64)
        st[:] = self.base
        for k, axis in enumerate(self.axes):
            st[:, axis] = points[:, k]
        return st

    def _run(self, states):
        if self.control[0]:
            return None
        return self.labeller.label(states, self.control)

    def __call__(self, points):
        pts = np.asarray(points, dtype=np.float64)
        states = self.states(pts)
        n = states.shape[0]
        labels = np.empty(n, dtype=np.int64)
        certain = np.zeros(n, dtype=bool)
        bounds = list(range(0, n, CHUNK)) + [n]
        futures = []
        try:
            for a, b in zip(bounds[:-1], bounds[1:], strict=True):
                futures.append((a, b, self._pool.submit(self._run, states[a:b])))
            for a, b, fut in futures:
                out = fut.result()
                if self.stop is not None and self.stop.is_set():
                    raise KeyboardInterrupt("analysis interrupted")
                if out is None or self.control[0]:
                    raise KeyboardInterrupt("analysis interrupted")
                labels[a:b] = out.quarter_turns
                if self.labeller.verified:
                    certain[a:b] = out.certainty == Certainty.CERTAIN
                else:
                    certain[a:b] = out.status == Status.SETTLED
                self.runs += b - a
                if self.progress is not None:
                    self.progress(b - a)
        except BaseException:
            self.control[0] = 1
            for _, _, fut in futures:
                fut.cancel()
            raise
        return labels, certain


# -- the analysis -----------------------------------------------------------------------------
def evidence_mask(quarter_turns, status, certainty, verified: bool) -> np.ndarray:
    """Cells whose label counts: certain on the ladder (verified) or settled (single pass)."""
    del quarter_turns  # the label itself does not decide
    if verified:
        return np.asarray(certainty) == Certainty.CERTAIN
    computed = np.asarray(certainty) != Certainty.NOT_COMPUTED
    return (np.asarray(status) == Status.SETTLED) & computed


def scene_of(attrs: dict):
    """The scene of a store: its parameters with the swept values taken from sweep.fixed."""
    params = {k: (dict(v) if isinstance(v, dict) else v) for k, v in attrs["parameters"].items()}
    for name in attrs["sweep"]["dims"]:
        params["initial"].pop(name, None)  # swept: null in the store, set per point here
    return scene_from_dict(params)


def base_state_of(attrs: dict) -> np.ndarray:
    """The six initial values of a store's cells, the swept ones set to each axis's lo."""
    sweep = attrs["sweep"]
    values = dict(sweep["fixed"])
    for axis in sweep["axes"]:
        values[axis["name"]] = axis["lo"]
    missing = [n for n in IC_NAMES if n not in values]
    if missing:
        raise ParameterError(f"the store's sweep attributes lack the initial value(s) {missing}")
    return np.array([float(values[n]) for n in IC_NAMES], dtype=np.float64)


def band_spans(axis: dict, row_ranges: Sequence[tuple[int, int]]) -> list[tuple[float, float]]:
    """Physical range of each band of rows: edges half-way between cell centres; the first band
    starts at lo and the last ends at hi (rows past the last complete box join it)."""
    lo, hi, n = float(axis["lo"]), float(axis["hi"]), int(axis["n"])
    h = (hi - lo) / (n - 1)
    spans = []
    for i, (a, b) in enumerate(row_ranges):
        start = lo if i == 0 else lo + (a - 0.5) * h
        stop = hi if i == len(row_ranges) - 1 else lo + (b - 0.5) * h
        spans.append((start, stop))
    return spans


def _grid_exponent(lab, valid):
    lo_dim, hi_dim = min(lab.shape), max(lab.shape)
    top = min(hi_dim // 20, lo_dim // 2)
    if top < 3:
        return None
    return uncertainty_exponent_grid(lab, valid=valid, eps=np.arange(2, top + 1))


def _map_measures(lab, valid, opts: AnalysisOptions, seed: int):
    entropy = basin_entropy(lab, box=opts.box, valid=valid)
    ft, ft_error = None, None
    try:
        ft = basins_fractal_test(lab, radius=opts.radius, balls=opts.balls, valid=valid,
                                 rng=seed)
    except ValueError as exc:
        ft_error = str(exc)
    wada = wada_merge(lab, valid=valid, max_dilation=opts.max_dilation)
    return entropy, ft, ft_error, wada, _grid_exponent(lab, valid)


def analyze_basin(quarter_turns, status, certainty, attrs: dict, *,
                  options: AnalysisOptions | None = None,
                  progress: Callable[[str, int, int], None] | None = None,
                  on_band: Callable[[int, tuple[int, int], UncertainFraction], None]
                  | None = None,
                  stop=None) -> BasinAnalysis:
    """Measure the boundaries of a basin map (arrays indexed [first axis, second axis] and the
    store's attributes): see the module docstring. ``progress(stage, done, total)`` is called
    as the work advances, ``on_band(index, rows, f)`` as each band's uncertain fraction f(eps)
    is measured (``rows``: the band's first row and the one past its last, along the first
    axis); ``stop`` (an Event) set, or Ctrl-C, interrupts it (KeyboardInterrupt)."""
    opts = options or AnalysisOptions()
    t_start, cpu_start = time.perf_counter(), time.process_time()
    lab = np.asarray(quarter_turns).astype(np.int64)
    shape = lab.shape
    opts.check(shape)
    verified = len(attrs["method"]["verification"]["rungs"]) > 1
    valid = evidence_mask(lab, status, certainty, verified)
    axes = tuple(dict(a) for a in attrs["sweep"]["axes"])
    seconds: dict[str, float] = {}
    cpu: dict[str, float] = {}

    def report(stage, done, total):
        if progress is not None:
            progress(stage, done, total)

    # -- on the map ---------------------------------------------------------------------------
    t0, c0 = time.perf_counter(), time.process_time()
    report("map", 0, opts.bands + 1)
    rows = [(b.start, b.stop) for b in
            boundary_by_band(lab, axis=0, bands=opts.bands, box=opts.box, valid=valid)]
    whole_map = _map_measures(lab, valid, opts, opts.seed)
    report("map", 1, opts.bands + 1)
    band_maps = []
    for i, (a, b) in enumerate(rows):
        band_maps.append(_map_measures(lab[a:b], valid[a:b], opts, opts.seed + 1 + i))
        report("map", i + 2, opts.bands + 1)
    seconds["map"], cpu["map"] = time.perf_counter() - t0, time.process_time() - c0

    # -- with the simulator -------------------------------------------------------------------
    spans = band_spans(axes[0], rows)
    pert_bands: list[UncertainFraction | None] = [None] * len(rows)
    pert_whole = None
    trajectories = 0
    t0, c0 = time.perf_counter(), time.process_time()
    if opts.points > 0:
        scene = scene_of(attrs)
        labeller = Labeller.of(scene)
        base = base_state_of(attrs)
        indices = [IC_NAMES.index(a["name"]) for a in axes]
        labeller.load(base)
        eps = np.asarray(opts.eps, dtype=float)
        rng = np.random.default_rng(opts.seed)
        ranges = np.array([a["hi"] - a["lo"] for a in axes], dtype=float)
        margin = eps.max() * ranges
        lows = np.array([a["lo"] for a in axes], dtype=float) + margin
        highs = np.array([a["hi"] for a in axes], dtype=float) - margin
        pts = rng.uniform(lows, highs, size=(opts.points, 2))
        edges = np.array([s[0] for s in spans[1:]])
        which = np.searchsorted(edges, pts[:, 0], side="right")
        total = opts.points * (1 + 2 * eps.size)
        done = 0

        def advance(k):
            nonlocal done
            done += k
            report("perturbation", done, total)

        report("perturbation", 0, total)
        with VerifiedClassifier(labeller, base, indices, threads=opts.threads,
                                progress=advance, stop=stop) as classify:
            for i in range(len(rows)):
                mine = pts[which == i]
                if mine.shape[0] == 0:
                    continue
                pert_bands[i] = uncertain_fraction(
                    classify, mine, eps, rng=np.random.default_rng([opts.seed, i]),
                    scale=ranges, direction=opts.direction, confidence=opts.confidence)
                if on_band is not None:
                    on_band(i, rows[i], pert_bands[i])
            trajectories = classify.runs
        measured = [p for p in pert_bands if p is not None]
        pert_whole = pool_uncertain_fractions(measured) if measured else None
    seconds["perturbation"] = time.perf_counter() - t0
    cpu["perturbation"] = time.process_time() - c0

    def fit(p):
        return None if p is None else fit_uncertainty_exponent(p, confidence=opts.confidence)

    def region(name, rws, span, maps, pert):
        entropy, ft, ft_error, wada, grid_exp = maps
        a, b = rws
        return RegionAnalysis(name=name, rows=(a, b), span=span, cells=(b - a) * shape[1],
                              evidence_cells=int(valid[a:b].sum()), entropy=entropy,
                              fractal_test=ft, wada=wada, grid_exponent=grid_exp,
                              perturbation=pert, exponent=fit(pert), fractal_test_error=ft_error)

    whole = region("whole map", (0, shape[0]), (float(axes[0]["lo"]), float(axes[0]["hi"])),
                   whole_map, pert_whole)
    bands = tuple(region(f"band {i + 1}", rows[i], spans[i], band_maps[i], pert_bands[i])
                  for i in range(len(rows)))
    seconds["total"] = time.perf_counter() - t_start
    cpu["total"] = time.process_time() - cpu_start
    fixed = {k: float(v) for k, v in attrs["sweep"]["fixed"].items()}
    return BasinAnalysis(whole=whole, bands=bands, axes=axes, fixed=fixed, options=opts,
                         verified=verified, trajectories=int(trajectories), seconds=seconds,
                         cpu_seconds=cpu, parameters=attrs["parameters"])


def eps_values(lo: float, hi: float, count: int) -> tuple[float, ...]:
    """``count`` log-spaced perturbation sizes from lo to hi (relative to the axes' ranges)."""
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise ParameterError(f"eps {lo:g}:{hi:g}: need 0 < LO < HI", parameters=("eps",))
    if count < 2:
        raise ParameterError(f"eps_values must be at least 2, got {count}",
                             parameters=("eps_values",))
    return tuple(np.logspace(math.log10(lo), math.log10(hi), int(count)).tolist())


__all__ = ["AnalysisOptions", "BasinAnalysis", "DEFAULT_BALLS", "DEFAULT_BANDS", "DEFAULT_BOX",
           "DEFAULT_EPS", "DEFAULT_EPS_VALUES", "DEFAULT_MAX_DILATION", "DEFAULT_POINTS",
           "DEFAULT_RADIUS", "LOG2", "RegionAnalysis", "VerifiedClassifier", "analyze_basin",
           "band_spans", "base_state_of", "eps_values", "evidence_mask", "scene_of"]
