"""The ball test for fractal boundaries (Puy, Daza, Wagemakers and Sanjuan 2021, as
Attractors.jl's ``basins_fractal_test``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .common import label_classes, labels_and_valid

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
    lab, val = labels_and_valid(labels, valid)
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
    if label_classes(lab, val).size < 2:
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
