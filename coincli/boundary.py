"""Pure estimators of basin-boundary complexity, on label arrays (numpy; scipy imported lazily).

Every function takes plain arrays (or, for the perturbation method, a classifier callable) and
returns a frozen dataclass; nothing here prints, writes files or knows about the coin model, so the
estimators apply to the basins of any map or flow.

Labels are integer arrays, one outcome class per value (any integers, negative ones included: a
"diverged" or "unsettled" class is an outcome like any other). The optional boolean ``valid`` mask
(same shape) marks the cells whose label is trustworthy; a cell with ``valid=False`` never counts
as evidence. How each estimator excludes such cells, and where it reports how many it excluded, is
said in its docstring.

Estimators
----------
``basin_entropy``
    Basin entropy S_b and boundary basin entropy S_bb of Daza, Wagemakers, Georgeot,
    Guery-Odelin and Sanjuan, "Basin entropy: a new tool to analyze uncertainty in dynamical
    systems", Sci. Rep. 6, 31416 (2016), with the conventions of Attractors.jl's
    ``basin_entropy`` (natural log, non-overlapping boxes, incomplete edge boxes ignored).
``boundary_by_band``
    The same, per band of rows along one axis.
``basins_fractal_test``
    The ball test for fractal boundaries of Puy, Daza, Wagemakers and Sanjuan, "A test for fractal
    boundaries based on the basin entropy", Commun. Nonlinear Sci. Numer. Simul. 95, 105588
    (2021), as Attractors.jl's ``basins_fractal_test``: it also detects fractal boundaries with
    S_bb <= log 2, which the log-2 criterion of ``basin_entropy`` (sufficient only) misses.
``uncertain_fraction`` / ``fit_uncertainty_exponent`` / ``pool_uncertain_fractions``
    The uncertainty exponent alpha by the perturbation method of McDonald, Grebogi, Ott and Yorke,
    "Fractal basin boundaries", Physica D 17, 125 (1985) (and Grebogi, McDonald, Ott and Yorke,
    "Final state sensitivity: an obstruction to predictability", Phys. Lett. A 99, 415 (1983)):
    f(eps) ~ eps**alpha, with f the fraction of points whose outcome changes under a perturbation
    of size eps; the boundary's box-counting dimension is D = dim - alpha.
``uncertainty_exponent_grid``
    alpha from a finished map alone, by box counting as Attractors.jl's
    ``uncertainty_exponent(basins)``.
``wada_merge``
    The merging method of Daza, Wagemakers and Sanjuan, "Ascertaining when a basin is Wada: the
    merging method", Sci. Rep. 8, 9954 (2018), with the conventions of Attractors.jl's
    ``test_wada_merge``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from itertools import combinations

import numpy as np

LOG2 = math.log(2.0)

__all__ = [
    "BandEntropy",
    "BasinEntropy",
    "FractalTest",
    "GridUncertainty",
    "UncertainFraction",
    "UncertaintyExponent",
    "WadaResult",
    "basin_entropy",
    "basins_fractal_test",
    "boundary_by_band",
    "fit_uncertainty_exponent",
    "local_exponents",
    "pool_uncertain_fractions",
    "smooth_ball_sbb",
    "uncertain_fraction",
    "uncertainty_exponent_grid",
    "wada_merge",
]


# --------------------------------------------------------------------------------------------
# input checks and box tiling
# --------------------------------------------------------------------------------------------

def _labels_and_valid(labels, valid) -> tuple[np.ndarray, np.ndarray | None]:
    lab = np.asarray(labels)
    if lab.ndim == 0:
        raise ValueError("labels must be an array with at least one axis, got a scalar")
    if lab.size == 0:
        raise ValueError("labels is empty")
    if lab.dtype == bool:
        lab = lab.astype(np.int8)
    if not np.issubdtype(lab.dtype, np.integer):
        raise TypeError(f"labels must be an integer array, got dtype {lab.dtype}; mark untrusted "
                        "cells with the boolean `valid` mask instead of NaN")
    if valid is None:
        return lab, None
    val = np.asarray(valid)
    if val.dtype != bool:
        raise TypeError(f"valid must be a boolean array, got dtype {val.dtype}")
    if val.shape != lab.shape:
        raise ValueError(f"valid has shape {val.shape}, labels has shape {lab.shape}")
    return lab, (None if val.all() else val)


def _box_sizes(box, shape: tuple[int, ...]) -> tuple[int, ...]:
    if np.ndim(box) == 0:
        sizes = (int(box),) * len(shape)
    else:
        sizes = tuple(int(b) for b in box)
        if len(sizes) != len(shape):
            raise ValueError(f"box has {len(sizes)} sizes but the map has {len(shape)} axes")
    if any(b < 1 for b in sizes):
        raise ValueError(f"box sizes must be >= 1 cell, got {sizes}")
    for axis, (b, n) in enumerate(zip(sizes, shape, strict=True)):
        if b > n:
            raise ValueError(f"box of {b} cells is larger than the map along axis {axis} "
                             f"({n} cells; map shape {shape}): no complete box fits")
    return sizes


def _blocks(a: np.ndarray, sizes: tuple[int, ...]) -> np.ndarray:
    """Complete non-overlapping boxes of `a` as rows: shape (n_boxes, cells_per_box).

    Boxes start at index 0 along every axis; the cells past the last complete box (fewer than
    `size` of them per axis) are dropped, as Attractors.jl does."""
    counts = [n // b for n, b in zip(a.shape, sizes, strict=True)]
    crop = a[tuple(slice(0, c * b) for c, b in zip(counts, sizes, strict=True))]
    split = []
    for c, b in zip(counts, sizes, strict=True):
        split += [c, b]
    nd = a.ndim
    order = list(range(0, 2 * nd, 2)) + list(range(1, 2 * nd, 2))
    return crop.reshape(split).transpose(order).reshape(int(np.prod(counts)), int(np.prod(sizes)))


def _classes(lab: np.ndarray, val: np.ndarray | None) -> np.ndarray:
    return np.unique(lab if val is None else lab[val])


# --------------------------------------------------------------------------------------------
# basin entropy
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class BasinEntropy:
    """Basin entropy of a map (Daza et al., Sci. Rep. 6, 31416, 2016).

    Attributes
    ----------
    basin_entropy
        S_b: the mean Gibbs entropy (natural log) over all evidence boxes;
        0 <= S_b <= log(n_classes).
    boundary_basin_entropy
        S_bb: the mean over boundary boxes (boxes with more than one outcome); NaN when there is no
        boundary box (then ``reason`` says so).
    box
        Box size in cells along each axis.
    boxes
        Evidence boxes: complete boxes in which every cell is valid.
    boundary_boxes
        Evidence boxes holding more than one outcome class.
    excluded_boxes
        Complete boxes skipped because they contain at least one invalid cell.
    excluded_cells
        Invalid cells (anywhere in the map, edge strips included).
    edge_cells
        Cells outside every complete box (the incomplete boxes at the far edges, ignored).
    n_classes
        Distinct labels among the valid cells of the whole map.
    max_entropy
        log(n_classes), the largest possible S_b (0 for a single class).
    fractal_boundary
        True when S_bb > log 2: the "log-2 criterion" of Daza et al. It is *sufficient* for a
        fractal boundary, not necessary: S_bb <= log 2 does not mean the boundary is smooth (the
        map of Grebogi et al. has a fractal boundary with S_bb ~ 0.60 at boxes of 6 on 300 x 300).
    reason
        Why a value is NaN, else None.
    """

    basin_entropy: float
    boundary_basin_entropy: float
    box: tuple[int, ...]
    boxes: int
    boundary_boxes: int
    excluded_boxes: int
    excluded_cells: int
    edge_cells: int
    n_classes: int
    max_entropy: float
    fractal_boundary: bool
    reason: str | None = None

    @property
    def log2_criterion(self) -> float:
        """log 2, the threshold that S_bb must exceed for ``fractal_boundary``."""
        return LOG2


def _box_entropies(lab: np.ndarray, val: np.ndarray | None, sizes: tuple[int, ...]):
    """Per evidence box: Gibbs entropy and number of classes; plus the excluded-box count."""
    _, inv = np.unique(lab, return_inverse=True)
    inv = inv.reshape(lab.shape)
    k = int(inv.max()) + 1
    blocks = _blocks(inv, sizes)
    n_complete = blocks.shape[0]
    if val is not None:
        ok = _blocks(val, sizes).all(axis=1)
        blocks = blocks[ok]
    nb, cells = blocks.shape
    if nb == 0:
        return np.zeros(0), np.zeros(0, dtype=np.int64), n_complete
    flat = (np.arange(nb, dtype=np.int64)[:, None] * k + blocks).ravel()
    counts = np.bincount(flat, minlength=nb * k).reshape(nb, k)
    p = counts / cells
    with np.errstate(divide="ignore", invalid="ignore"):
        plogp = np.where(counts > 0, p * np.log(np.where(counts > 0, p, 1.0)), 0.0)
    entropy = -plogp.sum(axis=1)
    entropy[entropy < 0] = 0.0  # -0.0 and rounding for single-class boxes
    return entropy, (counts > 0).sum(axis=1), n_complete - nb


def basin_entropy(labels, *, box=5, valid=None) -> BasinEntropy:
    """Basin entropy S_b and boundary basin entropy S_bb of a label map.

    Daza, Wagemakers, Georgeot, Guery-Odelin and Sanjuan, "Basin entropy: a new tool to analyze
    uncertainty in dynamical systems", Sci. Rep. 6, 31416 (2016). The map is tiled into
    non-overlapping boxes of ``box`` cells along every axis (an int, or one size per axis); in box
    i the Gibbs entropy is S_i = -sum_j p_ij log p_ij (natural log) over the outcome classes j
    present, p_ij being the fraction of the box's cells with label j. S_b is the mean of S_i over
    the boxes, S_bb the mean over the boundary boxes (those holding more than one class).

    Conventions follow Attractors.jl's ``basin_entropy(basins, eps)``: boxes start at the first
    cell of every axis and the incomplete boxes at the far edges are ignored (``edge_cells``
    reports how many cells that drops); S_bb is NaN when no box lies on a boundary (Attractors.jl
    returns 0/0 there too).

    Invalid cells (``valid=False``): every complete box containing one is skipped altogether and
    counted in ``excluded_boxes``; S_b and S_bb are means over the remaining boxes. The classes are
    counted over valid cells only.

    ``fractal_boundary`` is the log-2 criterion S_bb > log 2, which is sufficient for a fractal
    boundary but not necessary.

    Raises ValueError when the box is larger than the map along some axis (no complete box).
    """
    lab, val = _labels_and_valid(labels, valid)
    sizes = _box_sizes(box, lab.shape)
    classes = _classes(lab, val)
    n_classes = int(classes.size)
    entropy, n_in_box, excluded = _box_entropies(lab, val, sizes)
    nb = int(entropy.size)
    boundary = n_in_box > 1
    nbb = int(boundary.sum())
    covered = int(np.prod([(n // b) * b for n, b in zip(lab.shape, sizes, strict=True)]))
    reason = None
    if nb == 0:
        sb = sbb = math.nan
        reason = "no evidence box: every complete box contains an invalid cell"
    else:
        total = float(entropy.sum())
        sb = total / nb
        if nbb == 0:
            sbb = math.nan
            reason = ("no boundary box: a single outcome class in every box" if n_classes > 1
                      else "a single outcome class: no boundary")
        else:
            sbb = total / nbb
    return BasinEntropy(
        basin_entropy=sb,
        boundary_basin_entropy=sbb,
        box=sizes,
        boxes=nb,
        boundary_boxes=nbb,
        excluded_boxes=int(excluded),
        excluded_cells=0 if val is None else int((~val).sum()),
        edge_cells=int(lab.size - covered),
        n_classes=n_classes,
        max_entropy=math.log(n_classes) if n_classes > 0 else math.nan,
        fractal_boundary=bool(nbb > 0 and sbb > LOG2),
        reason=reason,
    )


@dataclass(frozen=True)
class BandEntropy:
    """Basin entropy of one band of the map: cells ``start:stop`` along ``axis``."""

    index: int
    axis: int
    start: int
    stop: int
    entropy: BasinEntropy

    @property
    def basin_entropy(self) -> float:
        return self.entropy.basin_entropy

    @property
    def boundary_basin_entropy(self) -> float:
        return self.entropy.boundary_basin_entropy

    @property
    def fractal_boundary(self) -> bool:
        return self.entropy.fractal_boundary


def boundary_by_band(labels, *, axis=0, bands=4, box=5, valid=None) -> list[BandEntropy]:
    """S_b, S_bb and the log-2 test per band of the map along ``axis``.

    ``bands`` is either a number of bands or a sequence of ``(start, stop)`` cell ranges along
    ``axis``. A number of bands splits the complete box rows (``shape[axis] // box`` of them) as
    evenly as possible, so that each band is a whole number of boxes thick and no box straddles two
    bands; the last ``shape[axis] % box`` cells are ignored, as in ``basin_entropy``. Explicit
    ranges are used as given (each is tiled from its own start). Each band is passed to
    ``basin_entropy`` with the same ``box`` and ``valid`` conventions.
    """
    lab, val = _labels_and_valid(labels, valid)
    axis = int(axis)
    if not -lab.ndim <= axis < lab.ndim:
        raise ValueError(f"axis {axis} out of range for a map with {lab.ndim} axes")
    axis %= lab.ndim
    sizes = _box_sizes(box, lab.shape)
    n = lab.shape[axis]
    if np.ndim(bands) == 0:
        nbands = int(bands)
        rows = n // sizes[axis]
        if not 1 <= nbands <= rows:
            raise ValueError(f"bands must be between 1 and {rows} (the complete boxes along "
                             f"axis {axis}), got {nbands}")
        edges = np.linspace(0, rows, nbands + 1).round().astype(int) * sizes[axis]
        ranges = list(zip(edges[:-1].tolist(), edges[1:].tolist(), strict=True))
    else:
        ranges = [(int(a), int(b)) for a, b in bands]
        for a, b in ranges:
            if not 0 <= a < b <= n:
                raise ValueError(f"band ({a}, {b}) is not a non-empty range inside 0..{n}")
    out = []
    for i, (a, b) in enumerate(ranges):
        sl = [slice(None)] * lab.ndim
        sl[axis] = slice(a, b)
        sub_val = None if val is None else val[tuple(sl)]
        out.append(BandEntropy(index=i, axis=axis, start=a, stop=b,
                               entropy=basin_entropy(lab[tuple(sl)], box=sizes, valid=sub_val)))
    return out


# --------------------------------------------------------------------------------------------
# fractal test: boundary basin entropy in random balls (Puy et al. 2021)
# --------------------------------------------------------------------------------------------

# S_bb of a smooth boundary seen through a ball, for a space of 1 to 5 dimensions (Puy et al.
# 2021; the table of Attractors.jl's basins_fractal_test). Beyond 5: 0.898 d**-0.4995.
SMOOTH_BALL_SBB = (0.499999, 0.4395093, 0.39609176, 0.36319428, 0.33722572)


def smooth_ball_sbb(dim: int) -> float:
    """Boundary basin entropy of a smooth boundary sampled with balls in ``dim`` dimensions."""
    if dim < 1:
        raise ValueError(f"dim must be >= 1, got {dim}")
    return SMOOTH_BALL_SBB[dim - 1] if dim <= len(SMOOTH_BALL_SBB) else 0.898 * dim ** -0.4995


@dataclass(frozen=True)
class FractalTest:
    """Outcome of the ball test for fractal boundaries (Puy, Daza, Wagemakers and Sanjuan,
    Commun. Nonlinear Sci. Numer. Simul. 95, 105588, 2021).

    Attributes
    ----------
    verdict
        "fractal", "smooth", or "undetermined" (no boundary ball found, or fewer than 2).
    fractal
        ``verdict == "fractal"``.
    boundary_basin_entropy
        The mean Gibbs entropy (natural log) over the boundary balls (balls holding more than
        one class): the ball estimate of S_bb.
    stderr
        Standard error of that mean: std (ddof 1) / sqrt(balls).
    smooth_value
        S_bb of a smooth boundary in this dimension (``SMOOTH_BALL_SBB``).
    bias
        Upper allowance for the discretisation of a ball of ``radius`` cells, 0.224 radius**-1.006.
    low, high
        The smooth band: the verdict is "smooth" when smooth_value - stderr <= S_bb <=
        smooth_value + stderr + bias, "fractal" outside it.
    radius
        Ball radius in cells (Euclidean, cell centres within the radius count).
    balls
        Boundary balls used.
    requested
        Boundary balls asked for.
    tries
        Balls drawn, boundary or not.
    excluded_balls
        Balls skipped because an invalid cell lies inside them.
    note
        A caution (the grid is coarse for this radius, fewer boundary balls than requested), or
        None.
    """

    verdict: str
    fractal: bool
    boundary_basin_entropy: float
    stderr: float
    smooth_value: float
    bias: float
    low: float
    high: float
    radius: float
    balls: int
    requested: int
    tries: int
    excluded_balls: int
    note: str | None = None


def _ball_offsets(radius: float, dim: int) -> np.ndarray:
    """Integer offsets from floor(centre) that can lie within `radius` of the centre."""
    r = int(math.ceil(radius))
    ax = np.arange(-r, r + 2)
    return np.stack(np.meshgrid(*([ax] * dim), indexing="ij"), axis=-1).reshape(-1, dim)


def basins_fractal_test(labels, *, radius=5.0, balls=1000, valid=None, rng=0,
                        max_tries=None, batch=4096) -> FractalTest:
    """Decide whether a basin boundary is fractal at the scale of ``radius`` cells.

    Puy, Daza, Wagemakers and Sanjuan, "A test for fractal boundaries based on the basin
    entropy", Commun. Nonlinear Sci. Numer. Simul. 95, 105588 (2021), as Attractors.jl's
    ``basins_fractal_test(basins; ε, Ntotal)``: balls of ``radius`` cells are dropped at random
    until ``balls`` of them hold more than one class; their mean Gibbs entropy S_bb is compared
    with that of a smooth boundary (0.4395 in 2-D): the boundary is called smooth when
    S_0 - sigma <= S_bb <= S_0 + sigma + delta (sigma the standard error of the mean, delta =
    0.224 radius**-1.006 the discretisation bias of a pixel ball), fractal otherwise. Unlike the
    log-2 criterion of ``basin_entropy`` (sufficient only), it detects fractal boundaries whose
    S_bb is below log 2, e.g. the map of Grebogi et al. (S_bb ~ 0.60 in boxes of 6). The verdict
    is at the scale of the ball: a coarse grid or a large radius can see structure in a smooth
    boundary, and the test is statistical (its smooth band is one standard error wide below).

    Differences from Attractors.jl (choices, same test): ball centres are uniform over the
    positions where the whole ball lies inside the map (Attractors.jl lets balls hang over two
    edges), and the mean is over the boundary balls only (Attractors.jl's includes one spurious
    zero); ``rng`` makes it reproducible.

    Invalid cells (``valid=False``): a ball containing one is skipped (``excluded_balls``).
    At most ``max_tries`` balls are drawn (default 200 * balls); with fewer than ``balls``
    boundary balls the verdict uses those found (``note`` says so), with fewer than 2 it is
    "undetermined". Raises ValueError when the map is not wider than 2 * radius + 1 cells along
    some axis, or for balls < 100 (too few for the statistics, as in Attractors.jl).
    """
    lab, val = _labels_and_valid(labels, valid)
    radius = float(radius)
    if not math.isfinite(radius) or radius < 1:
        raise ValueError(f"radius must be >= 1 cell, got {radius}")
    balls = int(balls)
    if balls < 100:
        raise ValueError(f"balls must be at least 100 for the statistics, got {balls}")
    dim = lab.ndim
    shape = np.array(lab.shape)
    if np.any(shape - 1 <= 2 * radius):
        raise ValueError(f"map {lab.shape} too small for balls of radius {radius} cells "
                         "(each axis needs more than 2 * radius + 1 cells)")
    rng = np.random.default_rng(rng)
    max_tries = 200 * balls if max_tries is None else int(max_tries)
    s0 = smooth_ball_sbb(dim)
    bias = 0.224 * radius ** -1.006
    if _classes(lab, val).size < 2:
        return FractalTest(verdict="undetermined", fractal=False,
                           boundary_basin_entropy=math.nan, stderr=math.nan, smooth_value=s0,
                           bias=bias, low=math.nan, high=math.nan, radius=radius, balls=0,
                           requested=balls, tries=0, excluded_balls=0,
                           note="a single outcome class: no boundary")
    _, inv = np.unique(lab, return_inverse=True)
    inv = inv.reshape(lab.shape)
    k = int(inv.max()) + 1
    offsets = _ball_offsets(radius, dim)
    found: list[np.ndarray] = []
    n_found = tries = excluded = 0
    while n_found < balls and tries < max_tries:
        nb = min(int(batch), max_tries - tries)
        tries += nb
        centre = rng.uniform(radius, shape - 1 - radius, size=(nb, dim))
        cells = np.floor(centre).astype(np.int64)[:, None, :] + offsets[None, :, :]
        inside = ((cells - centre[:, None, :]) ** 2).sum(axis=2) <= radius * radius
        idx = tuple(np.clip(cells[..., d], 0, shape[d] - 1) for d in range(dim))
        if val is not None:
            bad = (inside & ~val[idx]).any(axis=1)
            excluded += int(bad.sum())
            inside &= ~bad[:, None]
        cls = inv[idx]
        flat = (np.arange(nb)[:, None] * k + cls)[inside]
        counts = np.bincount(flat, minlength=nb * k).reshape(nb, k)
        total = counts.sum(axis=1, keepdims=True)
        with np.errstate(divide="ignore", invalid="ignore"):
            p = counts / np.maximum(total, 1)
            ent = -np.where(counts > 0, p * np.log(np.where(counts > 0, p, 1.0)), 0.0).sum(axis=1)
        boundary = (counts > 0).sum(axis=1) > 1
        found.append(ent[boundary])
        n_found += int(boundary.sum())
    ent = np.concatenate(found)[:balls] if found else np.zeros(0)
    notes = []
    if float(shape.min()) / radius < 50:
        notes.append(f"coarse grid for this radius: min(shape) / radius = "
                     f"{float(shape.min()) / radius:.3g} < 50 (Attractors.jl warns)")
    if ent.size < balls:
        notes.append(f"{ent.size} boundary balls found in {tries} tries, {balls} requested")
    if ent.size < 2:
        return FractalTest(verdict="undetermined", fractal=False, boundary_basin_entropy=(
            float(ent.mean()) if ent.size else math.nan), stderr=math.nan, smooth_value=s0,
            bias=bias, low=math.nan, high=math.nan, radius=radius, balls=int(ent.size),
            requested=balls, tries=tries, excluded_balls=excluded,
            note="; ".join(notes + ["too few boundary balls for a verdict"]))
    sbb = float(ent.mean())
    se = float(ent.std(ddof=1) / math.sqrt(ent.size))
    low, high = s0 - se, s0 + se + bias
    verdict = "smooth" if low <= sbb <= high else "fractal"
    return FractalTest(verdict=verdict, fractal=verdict == "fractal", boundary_basin_entropy=sbb,
                       stderr=se, smooth_value=s0, bias=bias, low=low, high=high, radius=radius,
                       balls=int(ent.size), requested=balls, tries=tries,
                       excluded_balls=excluded, note="; ".join(notes) or None)


# --------------------------------------------------------------------------------------------
# power-law fit shared by both uncertainty-exponent estimators
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class UncertaintyExponent:
    """Uncertainty exponent alpha of a basin boundary, f(eps) ~ eps**alpha.

    Attributes
    ----------
    alpha
        The exponent: the slope of log f against log eps (for ``fit == "count"``, dim plus the
        slope of log N); NaN when it cannot be fitted (``reason``).
    alpha_low, alpha_high
        Two-sided ``confidence`` interval for alpha from the regression's standard error and the
        t distribution with (points - 2) degrees of freedom; NaN with only two points.
    alpha_stderr
        Standard error of alpha.
    confidence
        Level of the interval (0.95 by default).
    intercept
        Intercept c of the fitted line (natural logs). For ``fit == "fraction"``:
        log f = alpha log eps + c. For ``fit == "count"`` (the grid estimator, as Attractors.jl):
        log N = (alpha - dim) log eps + c, N being the number of uncertain boxes. For
        ``fit == "fraction-gap"`` (grid estimator with gap correction): log f = alpha log eps + c
        with eps the effective box size (cells - 1).
    boundary_dimension
        dim - alpha: the box-counting dimension of the boundary.
    dim
        Dimension of the space the labels live in (2 for a map of a 2-D plane).
    eps, values, weights
        The data actually fitted (after dropping points without uncertain evidence): eps (the
        effective size cells - 1 for "fraction-gap"), f(eps) or N(eps), and the least-squares
        weights of the log values (all 1 when unweighted).
    fit
        "fraction", "count" or "fraction-gap" (see ``intercept``).
    dropped
        How many eps values were dropped (no uncertain point/box, or no evidence).
    reason
        Why alpha or its interval is NaN, else None.
    """

    alpha: float
    alpha_low: float
    alpha_high: float
    alpha_stderr: float
    confidence: float
    intercept: float
    boundary_dimension: float
    dim: int
    eps: np.ndarray
    values: np.ndarray
    weights: np.ndarray
    fit: str
    dropped: int
    reason: str | None = None


def _nan_exponent(dim, fit, confidence, reason, dropped, eps=(), values=(), weights=()):
    return UncertaintyExponent(
        alpha=math.nan, alpha_low=math.nan, alpha_high=math.nan, alpha_stderr=math.nan,
        confidence=confidence, intercept=math.nan, boundary_dimension=math.nan, dim=dim,
        eps=np.asarray(eps, dtype=float), values=np.asarray(values, dtype=float),
        weights=np.asarray(weights, dtype=float), fit=fit, dropped=dropped, reason=reason)


def _loglog_fit(eps, values, weights, *, dim, fit, confidence, dropped, absolute_weights,
                slope_to_alpha):
    """Weighted least squares of log(values) on log(eps); t-interval on the slope."""
    from scipy import stats

    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    x = np.log(eps)
    y = np.log(values)
    m = x.size
    if m < 2:
        return _nan_exponent(dim, fit, confidence,
                             f"{m} usable eps value(s): a line needs at least 2", dropped,
                             eps, values, weights)
    if np.ptp(x) == 0:
        return _nan_exponent(dim, fit, confidence, "all usable eps values are equal", dropped,
                             eps, values, weights)
    w = np.asarray(weights, dtype=float)
    sw = np.sqrt(w)
    design = np.column_stack([x, np.ones_like(x)])
    coef, *_ = np.linalg.lstsq(design * sw[:, None], y * sw, rcond=None)
    slope, intercept = float(coef[0]), float(coef[1])
    alpha = slope_to_alpha(slope)
    reason = None
    if m > 2:
        resid = y - design @ coef
        dof = m - 2
        s2 = float(np.sum(w * resid**2) / dof)
        if absolute_weights:
            s2 = max(s2, 1.0)  # binomial scatter at least; more if the points scatter more
        cov = s2 * np.linalg.inv(design.T @ (design * w[:, None]))
        se = math.sqrt(max(cov[0, 0], 0.0))
        half = float(stats.t.ppf(0.5 + confidence / 2, dof)) * se
        lo, hi = alpha - half, alpha + half
    else:
        se = lo = hi = math.nan
        reason = "only 2 usable eps values: alpha is exact through them, no interval"
    return UncertaintyExponent(
        alpha=alpha, alpha_low=lo, alpha_high=hi, alpha_stderr=se, confidence=confidence,
        intercept=intercept, boundary_dimension=dim - alpha, dim=dim,
        eps=np.asarray(eps, dtype=float), values=np.asarray(values, dtype=float), weights=w,
        fit=fit, dropped=dropped, reason=reason)


# --------------------------------------------------------------------------------------------
# uncertainty exponent: perturbation method
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class UncertainFraction:
    """Fraction f(eps) of eps-uncertain points (perturbation method of McDonald et al. 1985).

    Attributes
    ----------
    eps
        Perturbation sizes (relative to ``scale`` along each axis).
    fraction
        f(eps) = uncertain / evidence (NaN where there is no evidence).
    uncertain
        Evidence points whose three labels (x, x + e, x - e) are not all equal.
    evidence
        Points whose three classifications were all certain.
    excluded
        Points left out because at least one of the three classifications was not certain.
    ci_low, ci_high
        Wilson score interval for f at ``confidence`` (scipy.stats.binomtest), NaN without evidence.
    n_points
        Base points tried per eps.
    dim
        Dimension of the points (columns of ``points``).
    scale
        Per-axis scale: the perturbation along axis d has length eps * scale[d] for a unit step.
    direction
        "random", "axis" or the index of the one axis perturbed (see ``uncertain_fraction``).
    confidence
        Level of the Wilson intervals.
    """

    eps: np.ndarray
    fraction: np.ndarray
    uncertain: np.ndarray
    evidence: np.ndarray
    excluded: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    n_points: int
    dim: int
    scale: np.ndarray
    direction: str | int
    confidence: float


def _classify(classify, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    out = classify(pts)
    if isinstance(out, tuple):
        if len(out) != 2:
            raise ValueError("classify must return labels or (labels, certain), got a tuple of "
                             f"{len(out)}")
        lab, cert = out
        cert = np.asarray(cert)
        if cert.dtype != bool:
            raise TypeError(f"classify's certain mask must be boolean, got dtype {cert.dtype}")
    else:
        lab, cert = out, None
    lab = np.asarray(lab)
    if lab.shape != (pts.shape[0],):
        raise ValueError(f"classify returned labels of shape {lab.shape} for {pts.shape[0]} points")
    if not (np.issubdtype(lab.dtype, np.integer) or lab.dtype == bool):
        raise TypeError(f"classify must return integer labels, got dtype {lab.dtype}")
    if cert is None:
        cert = np.ones(lab.shape, dtype=bool)
    elif cert.shape != lab.shape:
        raise ValueError(f"classify returned a certain mask of shape {cert.shape} for "
                         f"{lab.shape[0]} labels")
    return lab, cert


def _steps(rng, n: int, dim: int, direction) -> np.ndarray:
    """Unit perturbation directions, shape (n, dim), in scaled coordinates."""
    if direction == "random":
        u = rng.standard_normal((n, dim))
        norm = np.linalg.norm(u, axis=1, keepdims=True)
        norm[norm == 0] = 1.0
        return u / norm
    u = np.zeros((n, dim))
    if direction == "axis":
        u[np.arange(n), rng.integers(0, dim, size=n)] = 1.0
    else:
        u[:, direction] = 1.0
    return u


def uncertain_fraction(classify: Callable, points, eps, *, rng, scale=None, direction="random",
                       confidence=0.95) -> UncertainFraction:
    """Fraction of eps-uncertain points, for the uncertainty exponent (perturbation method).

    McDonald, Grebogi, Ott and Yorke, "Fractal basin boundaries", Physica D 17, 125 (1985);
    Grebogi, McDonald, Ott and Yorke, Phys. Lett. A 99, 415 (1983). A point x is eps-uncertain
    when x, x + e and x - e (|e| = eps) do not all reach the same outcome; for a boundary of
    box-counting dimension D_b in a dim-dimensional space the uncertain fraction scales as
    f(eps) ~ eps**alpha with alpha = dim - D_b. Unlike a grid method, eps can be far below any grid
    spacing, since the classifier is called at the perturbed points themselves.

    Parameters
    ----------
    classify
        ``classify(pts) -> labels`` or ``-> (labels, certain)``: pts is an (M, dim) float array,
        labels an (M,) integer array, certain an (M,) boolean array (True where the label is
        trustworthy; all True when not returned). Called once for the base points (once per eps
        if ``points`` is 3-D) and once per eps for the 2 * N perturbed points stacked as
        [x + e; x - e].
    points
        Base points, (N, dim): the same points are perturbed for every eps (their labels are
        computed once; the f(eps) are then positively correlated, which the regression interval of
        ``fit_uncertainty_exponent`` ignores). Or (len(eps), N, dim): fresh points per eps, which
        makes the f(eps) independent. Draw them uniformly over the region studied; they should lie
        at least eps * scale inside it if ``classify`` is not defined outside.
    eps
        Perturbation sizes, > 0, relative to ``scale``.
    rng
        numpy Generator (or a seed for ``numpy.random.default_rng``) for the directions.
    scale
        Length of a unit step along each axis (scalar or (dim,)), e.g. each axis's range, so that
        eps is relative to it. Default 1.
    direction
        "random" (default): e = eps * scale * u with u uniform on the unit sphere, a fresh u per
        point and eps. "axis": along one coordinate axis drawn at random per point (the
        one-coordinate perturbation of McDonald et al., on every axis in turn). An int k: always
        along axis k. All give the same exponent for a boundary that is not aligned with the axes.
    confidence
        Level of the Wilson intervals.

    Evidence: a point counts only when all three of its classifications are certain; the others
    are reported in ``excluded`` and are neither uncertain nor certain.
    """
    rng = np.random.default_rng(rng)
    eps = np.atleast_1d(np.asarray(eps, dtype=float))
    if eps.ndim != 1 or eps.size == 0:
        raise ValueError("eps must be a non-empty 1-D sequence")
    if not np.all(np.isfinite(eps)) or np.any(eps <= 0):
        raise ValueError(f"eps must be finite and > 0, got {eps}")
    pts = np.asarray(points, dtype=float)
    if pts.ndim == 2:
        per_eps = False
        n, dim = pts.shape
    elif pts.ndim == 3:
        if pts.shape[0] != eps.size:
            raise ValueError(f"points has {pts.shape[0]} sets for {eps.size} eps values")
        per_eps = True
        n, dim = pts.shape[1:]
    else:
        raise ValueError(f"points must be (N, dim) or (len(eps), N, dim), got shape {pts.shape}")
    if n == 0 or dim == 0:
        raise ValueError(f"points has no points or no coordinates: shape {pts.shape}")
    sc = np.broadcast_to(np.asarray(1.0 if scale is None else scale, dtype=float), (dim,)).copy()
    if not np.all(np.isfinite(sc)) or np.any(sc <= 0):
        raise ValueError(f"scale must be finite and > 0, got {sc}")
    if isinstance(direction, str):
        if direction not in ("random", "axis"):
            raise ValueError(f"direction must be 'random', 'axis' or an axis index, got "
                             f"{direction!r}")
    else:
        direction = int(direction)
        if not 0 <= direction < dim:
            raise ValueError(f"direction axis {direction} out of range for {dim}-D points")

    k_unc = np.zeros(eps.size, dtype=np.int64)
    n_ev = np.zeros(eps.size, dtype=np.int64)
    if not per_eps:
        lab0, cert0 = _classify(classify, pts)
    for i, e in enumerate(eps):
        x = pts[i] if per_eps else pts
        if per_eps:
            lab0, cert0 = _classify(classify, x)
        step = _steps(rng, n, dim, direction) * (e * sc)
        lab, cert = _classify(classify, np.concatenate([x + step, x - step]))
        lp, lm = lab[:n], lab[n:]
        ev = cert0 & cert[:n] & cert[n:]
        unc = (lp != lab0) | (lm != lab0)
        k_unc[i] = int(np.count_nonzero(unc & ev))
        n_ev[i] = int(np.count_nonzero(ev))

    frac, lo, hi = _wilson(k_unc, n_ev, confidence)
    return UncertainFraction(
        eps=eps, fraction=frac, uncertain=k_unc, evidence=n_ev, excluded=n - n_ev, ci_low=lo,
        ci_high=hi, n_points=int(n), dim=int(dim), scale=sc, direction=direction,
        confidence=float(confidence))


def _wilson(uncertain: np.ndarray, evidence: np.ndarray, confidence: float):
    """Fractions k / n and their Wilson score intervals (NaN where n = 0)."""
    from scipy import stats

    frac = np.full(uncertain.size, math.nan)
    lo = np.full(uncertain.size, math.nan)
    hi = np.full(uncertain.size, math.nan)
    for i in range(uncertain.size):
        if evidence[i] > 0:
            frac[i] = uncertain[i] / evidence[i]
            ci = stats.binomtest(int(uncertain[i]), int(evidence[i])).proportion_ci(
                confidence_level=confidence, method="wilson")
            lo[i], hi[i] = ci.low, ci.high
    return frac, lo, hi


def pool_uncertain_fractions(parts) -> UncertainFraction:
    """One ``UncertainFraction`` from several measured on disjoint sets of base points with the
    same eps, dimension, scale and direction (e.g. one per band of a map): the counts are summed
    and the fractions and Wilson intervals recomputed. If each part's points were drawn
    uniformly over its region with a number of points proportional to the region's size, the
    pooled f(eps) is that of points drawn uniformly over the union."""
    parts = list(parts)
    if not parts:
        raise ValueError("nothing to pool")
    first = parts[0]
    for p in parts[1:]:
        if (p.eps.shape != first.eps.shape or not np.allclose(p.eps, first.eps)
                or p.dim != first.dim or not np.allclose(p.scale, first.scale)
                or p.direction != first.direction or p.confidence != first.confidence):
            raise ValueError("pooled fractions need the same eps, dim, scale, direction and "
                             "confidence")
    k = np.sum([p.uncertain for p in parts], axis=0).astype(np.int64)
    n = np.sum([p.evidence for p in parts], axis=0).astype(np.int64)
    ex = np.sum([p.excluded for p in parts], axis=0).astype(np.int64)
    frac, lo, hi = _wilson(k, n, first.confidence)
    return UncertainFraction(
        eps=first.eps.copy(), fraction=frac, uncertain=k, evidence=n, excluded=ex, ci_low=lo,
        ci_high=hi, n_points=int(sum(p.n_points for p in parts)), dim=first.dim,
        scale=first.scale.copy(), direction=first.direction, confidence=first.confidence)


def _curve(eps, fraction, who: str) -> tuple[np.ndarray, np.ndarray]:
    """eps and f(eps) as two 1-D float arrays of one length, or the error that says why not."""
    if fraction is None:
        raise TypeError(f"{who} needs the fractions (or an UncertainFraction)")
    e = np.atleast_1d(np.asarray(eps, dtype=float))
    f = np.atleast_1d(np.asarray(fraction, dtype=float))
    if e.shape != f.shape or e.ndim != 1:
        raise ValueError(f"eps {e.shape} and fraction {f.shape} must be 1-D of the same length")
    return e, f


def fit_uncertainty_exponent(eps, fraction=None, *, uncertain=None, evidence=None, dim=2,
                             confidence=0.95) -> UncertaintyExponent:
    """Fit log f = alpha log eps + c; the boundary dimension is dim - alpha.

    ``eps`` may be an ``UncertainFraction`` (then ``fraction``, ``uncertain``, ``evidence`` and
    ``dim`` are taken from it), or arrays: eps, f(eps) and optionally the counts ``uncertain``
    (k) and ``evidence`` (n) behind each f.

    Points with no uncertain point (k = 0 or f = 0: log f undefined) or no evidence are dropped
    (``dropped`` counts them); they are not treated as upper bounds.

    Weights: with the counts, weighted least squares with weight k / (1 - f) on log f, the inverse
    of the binomial variance of log f (delta method: var(log f) ~ (1 - f) / k); the residual
    scale is then max(1, chi^2 / dof), i.e. the interval is widened when the points scatter more
    than binomial noise (curvature, correlated f's). Without counts, ordinary least squares with the
    usual residual variance. The ``confidence`` interval on alpha is alpha +- t_{dof} * se with
    dof = points - 2 (none with only two points). With the same base points for every eps (see
    ``uncertain_fraction``) the f's are correlated and this interval is somewhat optimistic.

    Never raises for degenerate data: fewer than two usable eps values (a single outcome class,
    nothing uncertain) give alpha = NaN with ``reason`` set.
    """
    if isinstance(eps, UncertainFraction):
        res = eps
        eps, fraction = res.eps, res.fraction
        uncertain, evidence, dim = res.uncertain, res.evidence, res.dim
    e, f = _curve(eps, fraction, "fit_uncertainty_exponent")
    ok = np.isfinite(e) & (e > 0) & np.isfinite(f) & (f > 0)
    weighted = uncertain is not None and evidence is not None
    if weighted:
        k = np.asarray(uncertain, dtype=float)
        n = np.asarray(evidence, dtype=float)
        if k.shape != e.shape or n.shape != e.shape:
            raise ValueError("uncertain and evidence must have the length of eps")
        ok &= (k > 0) & (n > 0)
    elif (uncertain is None) != (evidence is None):
        raise TypeError("give both uncertain and evidence counts, or neither")
    dropped = int((~ok).sum())
    if weighted:
        kk, nn, ff = k[ok], n[ok], f[ok]
        w = kk / np.maximum(1.0 - ff, 1.0 / nn)
    else:
        w = np.ones(int(ok.sum()))
    out = _loglog_fit(e[ok], f[ok], w, dim=int(dim), fit="fraction", confidence=confidence,
                      dropped=dropped, absolute_weights=weighted, slope_to_alpha=lambda s: s)
    if math.isnan(out.alpha) and not ok.any():
        return _nan_exponent(int(dim), "fraction", confidence,
                             "no eps with an uncertain point: no boundary found at these scales "
                             "(a single outcome class?)", dropped)
    return out


def local_exponents(eps, fraction=None) -> np.ndarray:
    """Slopes of log f against log eps between successive eps: the local uncertainty exponent.

    ``eps`` may be an ``UncertainFraction``. Returns len(eps) - 1 values, NaN where either f is
    0 or undefined. A power law f ~ eps**alpha has every local exponent equal to alpha; a drift
    with eps says the exponent depends on the scale (e.g. a boundary that looks fractal at
    coarse scales and smooth, alpha -> 1, at fine ones)."""
    if isinstance(eps, UncertainFraction):
        eps, fraction = eps.eps, eps.fraction
    e, f = _curve(eps, fraction, "local_exponents")
    with np.errstate(divide="ignore", invalid="ignore"):
        lf = np.where(np.isfinite(f) & (f > 0), np.log(np.where(f > 0, f, 1.0)), np.nan)
        return np.diff(lf) / np.diff(np.log(e))


# --------------------------------------------------------------------------------------------
# uncertainty exponent: box counting on a finished map
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class GridUncertainty:
    """Box counts behind ``uncertainty_exponent_grid`` and the fitted exponent.

    Attributes
    ----------
    eps
        Box sizes in cells.
    uncertain_boxes
        Evidence boxes holding more than one label.
    evidence_boxes
        Complete boxes with every cell valid.
    complete_boxes
        Complete boxes (incomplete edge boxes are ignored).
    excluded_boxes
        Complete boxes skipped because they contain an invalid cell.
    fraction
        uncertain_boxes / evidence_boxes (NaN without evidence).
    exponent
        The fit (``fit == "count"``); see ``uncertainty_exponent_grid``.
    """

    eps: np.ndarray
    uncertain_boxes: np.ndarray
    evidence_boxes: np.ndarray
    complete_boxes: np.ndarray
    excluded_boxes: np.ndarray
    fraction: np.ndarray
    exponent: UncertaintyExponent

    @property
    def alpha(self) -> float:
        return self.exponent.alpha


def uncertainty_exponent_grid(labels, *, valid=None, eps=None, gap_correction=False,
                              confidence=0.95) -> GridUncertainty:
    """Uncertainty exponent of a finished map by box counting (no simulator needed).

    Follows Attractors.jl's ``uncertainty_exponent(basins; range_eps)`` (its
    ``basins_fractal_dimension``): for each box size eps (cells) the map is tiled into
    non-overlapping eps-boxes from the first cell (incomplete edge boxes ignored), N(eps) boxes hold
    more than one label, and an unweighted least-squares line log N = -d log eps + c gives the
    box-counting dimension d of the boundary; alpha = dim - d with dim = labels.ndim. Box sizes
    with N = 0 are dropped. The default eps = 2, 3, ..., max(shape) // 20 is Attractors.jl's
    default range (its own tests use 5:30 for Newton's basins on 300 x 300 and 3:15 for the map of
    Grebogi et al. on 251 x 251).

    Pixel bias and ``gap_correction``: a box of eps cells sees a frontier only where it crosses one
    of the eps - 1 gaps between the box's own cell centres; a frontier crossing the gap between two
    boxes is seen by neither. The Attractors.jl fit therefore overestimates alpha at small boxes:
    on 300 x 300, a straight line gives 1.26 with the default range and 1.07 with eps = 5..30, a
    disc 1.27 and 1.10, Newton's basins of z^3 - 1 0.74 and 0.61. With ``gap_correction=True`` the
    uncertain fraction f = N / boxes is fitted instead against the effective size eps - 1
    (log f = alpha log(eps - 1) + c; needs eps >= 2), which gives 1.00-1.04 for the line and the
    disc over either range, and 0.59 for Newton (the perturbation method gives 0.55-0.56 there,
    the published box-counting dimension 1.42 means 0.58). The default (False) keeps Attractors.jl's
    numbers so that its published windows apply.

    Invalid cells: boxes containing one are skipped (``excluded_boxes``); N(eps) is then estimated
    as fraction * complete_boxes, the uncertain fraction among evidence boxes scaled to the whole
    tiling (identical to the raw count when nothing is excluded). Skipping removes more area at
    larger eps, so with many invalid cells prefer eps small against their spacing.

    The interval on alpha is the t interval of the regression slope (see
    ``fit_uncertainty_exponent``); box counts at consecutive eps are strongly correlated, so read
    it as indicative. A map with a single class gives alpha = NaN with ``reason`` set. Raises
    ValueError if an eps is < 1 (< 2 with ``gap_correction``) or larger than the map.
    """
    lab, val = _labels_and_valid(labels, valid)
    if eps is None:
        hi = max(lab.shape) // 20
        eps = np.arange(2, hi + 1)
        if eps.size == 0:
            raise ValueError(f"map {lab.shape} too small for the default box sizes "
                             "2..max(shape)//20; pass eps explicitly")
    eps = np.atleast_1d(np.asarray(eps))
    if eps.ndim != 1 or eps.size == 0 or not np.issubdtype(eps.dtype, np.integer):
        raise ValueError(f"eps must be a non-empty 1-D sequence of integer box sizes, got {eps}")
    if gap_correction and eps.min() < 2:
        raise ValueError("gap_correction needs box sizes >= 2 cells (effective size eps - 1)")
    unc = np.zeros(eps.size, dtype=np.int64)
    ev = np.zeros(eps.size, dtype=np.int64)
    comp = np.zeros(eps.size, dtype=np.int64)
    for i, e in enumerate(eps):
        sizes = _box_sizes(int(e), lab.shape)
        blocks = _blocks(lab, sizes)
        mixed = blocks.min(axis=1) != blocks.max(axis=1)
        comp[i] = blocks.shape[0]
        if val is not None:
            ok = _blocks(val, sizes).all(axis=1)
            mixed &= ok
            ev[i] = int(ok.sum())
        else:
            ev[i] = blocks.shape[0]
        unc[i] = int(mixed.sum())
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(ev > 0, unc / np.maximum(ev, 1), math.nan)
    ok = (unc > 0) & (ev > 0)
    dim = lab.ndim
    fit = "fraction-gap" if gap_correction else "count"
    if not ok.any():
        n_classes = _classes(lab, val).size
        why = ("a single outcome class: no boundary" if n_classes < 2 else
               "no box holds more than one label at these sizes")
        exp = _nan_exponent(dim, fit, confidence, why, int(eps.size))
    elif gap_correction:
        exp = _loglog_fit(eps[ok] - 1.0, frac[ok], np.ones(int(ok.sum())), dim=dim, fit=fit,
                          confidence=confidence, dropped=int((~ok).sum()),
                          absolute_weights=False, slope_to_alpha=lambda s: s)
    else:
        count = frac * comp  # == unc when nothing is excluded
        exp = _loglog_fit(eps[ok].astype(float), count[ok], np.ones(int(ok.sum())), dim=dim,
                          fit=fit, confidence=confidence, dropped=int((~ok).sum()),
                          absolute_weights=False, slope_to_alpha=lambda s: dim + s)
    return GridUncertainty(eps=eps.astype(np.int64), uncertain_boxes=unc, evidence_boxes=ev,
                           complete_boxes=comp, excluded_boxes=comp - ev, fraction=frac,
                           exponent=exp)


# --------------------------------------------------------------------------------------------
# Wada test: merging method
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class WadaResult:
    """Outcome of the merging test for the Wada property (Daza et al., Sci. Rep. 8, 9954, 2018).

    Attributes
    ----------
    is_wada
        True when, for some dilation r <= max_dilation, every testable boundary cell of every
        merged basin lies within L1 distance r (cells) of the boundary of every other merged basin,
        up to ``tolerance`` (a fraction of the testable boundary cells). Always False with fewer
        than 3 classes: the Wada property needs three basins sharing one boundary, by definition.
        A verdict at the grid's resolution only.
    dilation
        The smallest such r, or None. With tolerance 0 it is ``hausdorff_distance``.
    hausdorff_distance
        Largest L1 distance (cells) from a testable cell of one merged boundary to another merged
        boundary, over all pairs: the Hausdorff distance between the merged boundaries. A few cells
        for Wada basins at any resolution; a macroscopic fraction of the map otherwise.
    max_dilation, tolerance
        The settings used.
    failing_fraction
        Largest fraction (over ordered pairs of merged basins) of a merged boundary's testable cells
        farther than r from the other merged boundary, at r = ``dilation`` (or ``max_dilation``
        when the test fails). NaN with fewer than 3 classes or without evidence.
    failing_fraction_of_cells
        The largest failing count over the pairs divided by the number of cells of the map, at the
        same r: the number Attractors.jl's ``test_wada_merge(basins, r)`` returns.
    dilations
        r = 1 .. max_dilation.
    failing_by_dilation, failing_cells_by_dilation
        ``failing_fraction`` and ``failing_fraction_of_cells`` for each r.
    worst_pair
        (i, j): the boundary of the merged basin of class j tested against that of class i, where
        they disagree most at the reported r (None when nothing fails or nothing is tested).
    classes
        The outcome classes among valid cells.
    boundary_cells
        Boundary cells of each merged basin (class vs the union of the others), in ``classes``
        order.
    excluded_boundary_cells
        Boundary cells left untested at the reported r (summed over classes) because an invalid
        cell lies within L1 distance r + 1 (the other boundary might be hidden there).
    reason
        Why the verdict is False by definition or has no evidence, else None.
    """

    is_wada: bool
    dilation: int | None
    hausdorff_distance: float
    max_dilation: int
    tolerance: float
    failing_fraction: float
    failing_fraction_of_cells: float
    dilations: np.ndarray
    failing_by_dilation: np.ndarray
    failing_cells_by_dilation: np.ndarray
    worst_pair: tuple | None
    classes: np.ndarray
    boundary_cells: tuple[int, ...]
    excluded_boundary_cells: int
    reason: str | None = None

    @property
    def n_classes(self) -> int:
        return int(self.classes.size)


def _boundary(member: np.ndarray, usable: np.ndarray) -> np.ndarray:
    """Usable cells with a usable face neighbour on the other side of `member`.

    With every cell usable this is Attractors.jl's ``get_boundary``: the cells at L1 distance 1
    from the complement, on both sides of the frontier; the edges of the map are not boundary."""
    bnd = np.zeros(member.shape, dtype=bool)
    for ax in range(member.ndim):
        a = [slice(None)] * member.ndim
        b = [slice(None)] * member.ndim
        a[ax] = slice(0, -1)
        b[ax] = slice(1, None)
        a, b = tuple(a), tuple(b)
        diff = (member[a] != member[b]) & usable[a] & usable[b]
        bnd[a] |= diff
        bnd[b] |= diff
    return bnd


def _l1_distance_to(mask: np.ndarray) -> np.ndarray:
    """L1 (city-block) distance of every cell to the nearest True cell of `mask` (inf if none)."""
    from scipy import ndimage

    if not mask.any():
        return np.full(mask.shape, np.inf)
    return ndimage.distance_transform_cdt(~mask, metric="taxicab").astype(float)


def wada_merge(labels, *, valid=None, max_dilation=6, tolerance=0.0) -> WadaResult:
    """Test the Wada property of a map by the merging method.

    Daza, Wagemakers and Sanjuan, "Ascertaining when a basin is Wada: the merging method",
    Sci. Rep. 8, 9954 (2018): a Wada boundary is the only one left unaltered when basins are
    merged. For each class i the other classes are merged into one set and the boundary of that
    two-set map is computed (``boundary_cells``); then for every pair (i, j) each merged boundary
    is compared with the other: its cells farther than r (L1, in cells) from the other fail. With
    N >= 3 basins all merged boundaries coincide (up to the grid's resolution) iff the basins are
    Wada.

    Conventions follow Attractors.jl's ``test_wada_merge(basins, r)``: boundary cells are the cells
    with a face neighbour (4-neighbour in 2-D) across the frontier, on both sides; distances are
    city-block distances; its return value (the largest failing count over the pairs divided by the
    number of *cells of the map*) is ``failing_fraction_of_cells``, and it calls the map Wada when
    that is 0 for the r the user chose, leaving any other threshold to the user.

    Threshold used here: r runs over 1 .. ``max_dilation`` and the map is called Wada at the first
    r where the failing cells are at most ``tolerance`` of the testable boundary cells. The default
    tolerance 0 is Attractors.jl's p == 0, i.e. a Hausdorff distance <= max_dilation between the
    merged boundaries. Thin filaments of a basin narrower than a cell are missed at a finite
    resolution, so Wada basins need r of a few cells: Newton's basins of z^3 - 1 on [-1, 1]^2
    need r = 5 at 150 x 150 and 300 x 300 and r = 6 at 600 x 600; hence the default
    ``max_dilation=6``. A Hausdorff distance that grows in proportion to the resolution marks a
    non-Wada map (Daza et al. 2018); check by recomputing at a finer grid when the verdict matters.
    Works for any number of axes (face neighbours along every axis).

    Invalid cells belong to no basin: they are neither boundary cells nor neighbours that make one,
    and a boundary cell within L1 distance r + 1 of an invalid cell is not tested at that r (the
    other boundary could hide among the invalid cells); ``excluded_boundary_cells`` counts those.

    Fewer than 3 classes: ``is_wada`` is False by definition, with ``reason`` set (Attractors.jl
    logs an error and returns Inf there); no exception.
    """
    lab, val = _labels_and_valid(labels, valid)
    max_dilation = int(max_dilation)
    if max_dilation < 1:
        raise ValueError(f"max_dilation must be >= 1, got {max_dilation}")
    if not 0.0 <= float(tolerance) < 1.0:
        raise ValueError(f"tolerance must be in [0, 1), got {tolerance}")
    usable = np.ones(lab.shape, dtype=bool) if val is None else val
    classes = _classes(lab, val)
    dil = np.arange(1, max_dilation + 1)
    if classes.size < 3:
        return WadaResult(
            is_wada=False, dilation=None, hausdorff_distance=math.nan, max_dilation=max_dilation,
            tolerance=float(tolerance), failing_fraction=math.nan,
            failing_fraction_of_cells=math.nan, dilations=dil,
            failing_by_dilation=np.full(max_dilation, math.nan),
            failing_cells_by_dilation=np.full(max_dilation, math.nan), worst_pair=None,
            classes=classes, boundary_cells=(), excluded_boundary_cells=0,
            reason=f"{classes.size} outcome class(es): the Wada property needs at least 3 basins "
                   "(False by definition)")
    bnds = [_boundary(lab == c, usable) for c in classes]
    dists = [_l1_distance_to(b) for b in bnds]
    d_invalid = _l1_distance_to(~usable)
    pairs = [(a, b) for i, j in combinations(range(classes.size), 2) for a, b in ((i, j), (j, i))]
    # Work on the boundary cells only (a small part of the map): for each class b the flat
    # indices of its merged boundary and their distance to an invalid cell; for each pair the
    # distances of b's boundary cells to a's boundary. Cost ~ classes x boundary cells, which
    # keeps maps with dozens of classes fast.
    cells_of = [np.flatnonzero(b.ravel()) for b in bnds]
    dinv_of = [d_invalid.ravel()[c] for c in cells_of]
    flat_dists = [d.ravel() for d in dists]

    hd = -math.inf  # Hausdorff distance over the cells a hidden boundary cannot bring closer
    fails = np.zeros((len(pairs), max_dilation), dtype=np.int64)
    for k, (a, b) in enumerate(pairs):
        d = flat_dists[a][cells_of[b]]
        exact = dinv_of[b] > d + 1
        if exact.any():
            hd = max(hd, float(d[exact].max()))
        for ri, r in enumerate(dil):
            fails[k, ri] = int(np.count_nonzero((dinv_of[b] > r + 1) & (d > r)))
    hd = math.nan if hd == -math.inf else hd

    fail_b = np.full(max_dilation, math.nan)
    fail_c = np.full(max_dilation, math.nan)
    pair_at: list = [None] * max_dilation
    excl_at = [0] * max_dilation
    for ri, r in enumerate(dil):
        n_testable = [int(np.count_nonzero(dv > r + 1)) for dv in dinv_of]
        excl_at[ri] = int(sum(c.size for c in cells_of) - sum(n_testable))
        worst, worst_count, worst_pair, tested = 0.0, 0, None, False
        for k, (a, b) in enumerate(pairs):  # merged boundary of b tested against that of a
            nt = n_testable[b]
            if nt == 0:
                continue
            tested = True
            nf = int(fails[k, ri])
            worst_count = max(worst_count, nf)
            if nf / nt > worst:
                worst, worst_pair = nf / nt, (classes[a].item(), classes[b].item())
        if tested:
            fail_b[ri] = worst
            fail_c[ri] = worst_count / lab.size
            pair_at[ri] = worst_pair
    passing = np.flatnonzero(np.isfinite(fail_b) & (fail_b <= tolerance))
    reason = None
    if passing.size:
        ri = int(passing[0])
        is_wada, dilation = True, int(dil[ri])
    else:
        ri = max_dilation - 1
        is_wada, dilation = False, None
        if not np.isfinite(fail_b).any():
            reason = "no testable boundary cell (all within reach of invalid cells)"
    return WadaResult(
        is_wada=is_wada, dilation=dilation, hausdorff_distance=hd, max_dilation=max_dilation,
        tolerance=float(tolerance), failing_fraction=float(fail_b[ri]),
        failing_fraction_of_cells=float(fail_c[ri]), dilations=dil, failing_by_dilation=fail_b,
        failing_cells_by_dilation=fail_c, worst_pair=pair_at[ri], classes=classes,
        boundary_cells=tuple(int(b.sum()) for b in bnds), excluded_boundary_cells=excl_at[ri],
        reason=reason)
