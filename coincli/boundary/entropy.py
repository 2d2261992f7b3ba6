"""Basin entropy S_b and boundary basin entropy S_bb (Daza et al. 2016, as Attractors.jl's
``basin_entropy``), on a whole map and per band of rows."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .common import LOG2, box_sizes, label_blocks, label_classes, labels_and_valid


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
    blocks = label_blocks(inv, sizes)
    n_complete = blocks.shape[0]
    if val is not None:
        ok = label_blocks(val, sizes).all(axis=1)
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
    lab, val = labels_and_valid(labels, valid)
    sizes = box_sizes(box, lab.shape)
    classes = label_classes(lab, val)
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
    lab, val = labels_and_valid(labels, valid)
    axis = int(axis)
    if not -lab.ndim <= axis < lab.ndim:
        raise ValueError(f"axis {axis} out of range for a map with {lab.ndim} axes")
    axis %= lab.ndim
    sizes = box_sizes(box, lab.shape)
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
