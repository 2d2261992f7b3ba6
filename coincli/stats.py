"""Statistics of a basin map (pure numpy): outcome counts, the probability of standing with a
Wilson 95 % interval, the cells without a trustworthy label, and the sweep's cost.

Fractions and probabilities are taken over the *labelled* cells: computed and finite (settled, or
unsettled at t_end and labelled round(2 phi / pi) there, as the paper labels every run). With a
certified sweep they are given twice: over all labelled cells, and over the certain ones only.
Where there is nothing to divide by they are NaN.
"""

from __future__ import annotations

import math

import numpy as np

from .enums import Status


def wilson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval for k successes in n trials (scipy's; NaN, NaN for n = 0)."""
    if n <= 0:
        return math.nan, math.nan
    from scipy.stats import binomtest

    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    lo = 0.0 if k == 0 else float(ci.low)  # exact ends, not rounding noise
    hi = 1.0 if k == n else float(ci.high)
    return lo, hi


def _direction(n: int) -> str:
    # phi grows counter-clockwise, so n > 0 is a counter-clockwise net rotation
    return "none" if n == 0 else ("counter-clockwise" if n > 0 else "clockwise")


def outcome_table(labels: np.ndarray) -> tuple[list[dict], dict]:
    """Count and fraction per n, and the standing probability with its interval."""
    labels = np.asarray(labels).ravel().astype(np.int64)
    total = int(labels.size)
    values, counts = np.unique(labels, return_counts=True)
    rows = [{"n": int(v), "pose": "standing" if v % 2 else "lying", "direction": _direction(int(v)),
             "count": int(c), "fraction": c / total if total else math.nan}
            for v, c in zip(values, counts, strict=True)]
    standing = int(np.count_nonzero(labels % 2))
    lo, hi = wilson(standing, total)
    return rows, {"count": standing, "of": total,
                  "probability": standing / total if total else math.nan, "ci95": [lo, hi]}


def basin_stats(quarter_turns: np.ndarray, status: np.ndarray,
                uncertain: np.ndarray | None = None, tile_seconds: np.ndarray | None = None,
                done: np.ndarray | None = None, runs: list[dict] | None = None) -> dict:
    """Everything `coin basin stats` reports, as plain JSON-able values."""
    q = np.asarray(quarter_turns)
    st = np.asarray(status)
    computed = st != Status.NOT_COMPUTED
    labelled = computed & ((st == Status.SETTLED) | (st == Status.UNSETTLED))
    out: dict = {
        "cells": int(q.size),
        "computed": int(computed.sum()),
        "not_computed": int((~computed).sum()),
        "settled": int((st == Status.SETTLED).sum()),
        "unsettled": int((st == Status.UNSETTLED).sum()),
        "non_finite": int((st == Status.NONFINITE).sum()),
        "labelled": int(labelled.sum()),
    }
    out["outcomes"], out["standing"] = outcome_table(q[labelled])
    if uncertain is not None:
        unc = np.asarray(uncertain)
        flagged = labelled & (unc == 1)
        certain = labelled & (unc == 0)
        rows, standing = outcome_table(q[certain])
        out["certified"] = True
        out["uncertain"] = {
            "count": int(flagged.sum()),
            "fraction": flagged.sum() / labelled.sum() if labelled.any() else math.nan,
            "certain": int(certain.sum()),
            "outcomes_certain": rows,
            "standing_certain": standing,
            "standing_uncertain": int(np.count_nonzero(q[flagged] % 2)),
        }
    else:
        out["certified"] = False
        out["uncertain"] = None
    cost: dict = {}
    if tile_seconds is not None:
        ts = np.asarray(tile_seconds, dtype=float)
        mask = np.isfinite(ts) if done is None else (np.asarray(done) == 1) & np.isfinite(ts)
        cpu = float(ts[mask].sum())
        cost["cpu_seconds"] = cpu
        cost["trajectories_per_cpu_second"] = out["computed"] / cpu if cpu > 0 else math.nan
        cost["cpu_ms_per_cell"] = 1e3 * cpu / out["computed"] if out["computed"] else math.nan
    if runs:
        wall = float(sum(r.get("wall_seconds", 0.0) for r in runs))
        cells = int(sum(r.get("cells", 0) for r in runs))
        cost["runs"] = len(runs)
        cost["wall_seconds"] = wall
        cost["trajectories_per_second"] = cells / wall if wall > 0 else math.nan
    out["cost"] = cost
    return out


__all__ = ["basin_stats", "outcome_table", "wilson"]
