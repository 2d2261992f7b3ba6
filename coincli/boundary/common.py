"""What the estimators of :mod:`coincli.boundary` share: labels with their validity mask, box
sizes and the blocks of an array."""

from __future__ import annotations

import math

import numpy as np

LOG2 = math.log(2.0)


def labels_and_valid(labels, valid) -> tuple[np.ndarray, np.ndarray | None]:
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


def box_sizes(box, shape: tuple[int, ...]) -> tuple[int, ...]:
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


def label_blocks(a: np.ndarray, sizes: tuple[int, ...]) -> np.ndarray:
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


def label_classes(lab: np.ndarray, val: np.ndarray | None) -> np.ndarray:
    return np.unique(lab if val is None else lab[val])
