"""The merging method for Wada basins (Daza, Wagemakers and Sanjuan 2018, as Attractors.jl's
``test_wada_merge``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations

import numpy as np

from .common import label_classes, labels_and_valid


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
    lab, val = labels_and_valid(labels, valid)
    max_dilation = int(max_dilation)
    if max_dilation < 1:
        raise ValueError(f"max_dilation must be >= 1, got {max_dilation}")
    if not 0.0 <= float(tolerance) < 1.0:
        raise ValueError(f"tolerance must be in [0, 1), got {tolerance}")
    usable = np.ones(lab.shape, dtype=bool) if val is None else val
    classes = label_classes(lab, val)
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
