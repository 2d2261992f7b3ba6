"""Statistics of a basin map (pure numpy), accumulated tile by tile so that memory stays flat at
any resolution: outcome counts, the probability of standing with a Wilson 95 % interval, the
cells without a label, the verification, and the sweep's cost.

Fractions and probabilities are taken over the *labelled* cells: computed and finite (settled,
or unsettled at t_end and labelled round(2 phi / pi) there, as the paper labels every run); in a
verified sweep they are given again over the *certain* cells only, and over the *decided* cells
(the deepest rung run settled: its label is final for that run, converged or not). The cells
that are not certain are counted by cause: *uncertain* (decided, but no two rungs agree: chaotic
at this precision) and *undecided* (a rung not settled within its horizon or step budget).
Where there is nothing to divide by they are NaN.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from .enums import Certainty, Status
from .integrators import NO_LABEL


def wilson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval for k successes in n trials (scipy's; NaN, NaN for n = 0)."""
    if n <= 0:
        return math.nan, math.nan
    from scipy.stats import binomtest

    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    lo = 0.0 if k == 0 else float(ci.low)  # exact ends, not rounding noise
    hi = 1.0 if k == n else float(ci.high)
    return lo, hi


def proportion(count: int, total: int) -> dict:
    """A count out of a total with its probability and 95 % Wilson interval."""
    lo, hi = wilson(count, total)
    return {"count": int(count), "of": int(total),
            "probability": count / total if total else math.nan, "low": lo, "high": hi,
            "ci95": [lo, hi]}


def _direction(n: int) -> str:
    # phi grows counter-clockwise, so n > 0 is a counter-clockwise net rotation
    return "none" if n == 0 else ("counter-clockwise" if n > 0 else "clockwise")


def outcome_rows(counts: Counter) -> list[dict]:
    """One row per n: pose, direction, count and fraction with its interval."""
    total = sum(counts.values())
    return [{"n": int(n), "pose": "standing" if n % 2 else "lying", "direction": _direction(n),
             **proportion(c, total), "fraction": c / total if total else math.nan}
            for n, c in sorted(counts.items())]


class BasinCounts:
    """Counts of a basin, added tile by tile (:meth:`add`), summarised by :meth:`summary`."""

    def __init__(self):
        self.cells = 0
        self.status = Counter()
        self.certainty = Counter()
        self.outcomes = Counter()  # labelled cells
        self.certain_outcomes = Counter()  # labelled and certain
        self.uncertain_outcomes = Counter()  # labelled and not certain, either cause
        self.decided_outcomes = Counter()  # settled at the deepest rung run

    def add(self, quarter_turns: np.ndarray, status: np.ndarray,
            certainty: np.ndarray | None = None) -> None:
        q = np.asarray(quarter_turns).ravel().astype(np.int64)
        st = np.asarray(status).ravel()
        self.cells += q.size
        self.status.update(dict(zip(*np.unique(st, return_counts=True), strict=True)))
        # a label needs both a labelled status and a count (never the fill value)
        labelled = ((st == Status.SETTLED) | (st == Status.UNSETTLED)) & (q != NO_LABEL)
        self.outcomes.update(dict(zip(*np.unique(q[labelled], return_counts=True), strict=True)))
        if certainty is None:
            certainty = np.where(st == Status.NOT_COMPUTED, Certainty.NOT_COMPUTED,
                                 Certainty.UNVERIFIED)
        cert = np.asarray(certainty).ravel()
        self.certainty.update(dict(zip(*np.unique(cert, return_counts=True), strict=True)))
        unsure = (cert == Certainty.UNCERTAIN) | (cert == Certainty.UNDECIDED)
        for sel, counter in ((cert == Certainty.CERTAIN, self.certain_outcomes),
                             (unsure, self.uncertain_outcomes),
                             (st == Status.SETTLED, self.decided_outcomes)):
            sel = labelled & sel
            counter.update(dict(zip(*np.unique(q[sel], return_counts=True), strict=True)))

    def add_not_computed(self, cells: int) -> None:
        """Count ``cells`` cells without a result (a tile not done, or damaged)."""
        self.cells += int(cells)
        self.status[int(Status.NOT_COMPUTED)] += int(cells)
        self.certainty[int(Certainty.NOT_COMPUTED)] += int(cells)

    def summary(self) -> dict:
        """Everything `coin basin stats` reports, as plain values."""
        by_status = {s.label: int(self.status.get(int(s), 0)) for s in Status}
        labelled = sum(self.outcomes.values())
        standing = sum(c for n, c in self.outcomes.items() if n % 2)
        out = {
            "cells": self.cells,
            "computed": self.cells - by_status[Status.NOT_COMPUTED.label],
            "not_computed": by_status[Status.NOT_COMPUTED.label],
            "status": by_status,
            "labelled": labelled,
            "outcomes": outcome_rows(self.outcomes),
            "standing": proportion(standing, labelled),
            "lying": proportion(labelled - standing, labelled),
        }
        chaotic = int(self.certainty.get(int(Certainty.UNCERTAIN), 0))
        undecided = int(self.certainty.get(int(Certainty.UNDECIDED), 0))
        verified = self.certainty.get(int(Certainty.CERTAIN), 0) + chaotic + undecided > 0
        out["verified"] = verified
        decided = sum(self.decided_outcomes.values())
        standing_decided = sum(c for n, c in self.decided_outcomes.items() if n % 2)
        out["decided"] = proportion(decided, labelled)
        out["standing_decided"] = proportion(standing_decided, decided)
        if verified:
            certain = sum(self.certain_outcomes.values())
            computed = out["computed"]
            standing_certain = sum(c for n, c in self.certain_outcomes.items() if n % 2)
            out["certain"] = proportion(certain, labelled)
            out["uncertain"] = {**proportion(chaotic + undecided, computed),
                                "standing": sum(c for n, c in self.uncertain_outcomes.items()
                                                if n % 2),
                                "chaotic": chaotic, "undecided": undecided}
            out["outcomes_certain"] = outcome_rows(self.certain_outcomes)
            out["standing_certain"] = proportion(standing_certain, certain)
            out["lying_certain"] = proportion(certain - standing_certain, certain)
        return out


def basin_stats(quarter_turns: np.ndarray, status: np.ndarray,
                certainty: np.ndarray | None = None) -> dict:
    """The statistics of whole arrays (one tile)."""
    counts = BasinCounts()
    counts.add(quarter_turns, status, certainty)
    return counts.summary()


def cost_summary(cells: int, tile_seconds: np.ndarray, done: np.ndarray, runs: list[dict],
                 rungs_run: np.ndarray | None = None) -> dict:
    """CPU and wall time of a sweep: from the per-tile CPU seconds of the tiles done and the
    records of each invocation."""
    cost: dict = {}
    ts = np.asarray(tile_seconds, dtype=float)
    mask = (np.asarray(done) == 1) & np.isfinite(ts)
    if mask.any():
        cpu = float(ts[mask].sum())
        cost["cpu_seconds"] = cpu
        cost["trajectories_per_cpu_second"] = cells / cpu if cpu > 0 else math.nan
        cost["cpu_ms_per_cell"] = 1e3 * cpu / cells if cells else math.nan
    if runs:
        wall = float(sum(r.get("wall_seconds", 0.0) for r in runs))
        run_cells = int(sum(r.get("cells", 0) for r in runs))
        cost["runs"] = len(runs)
        cost["wall_seconds"] = wall
        cost["trajectories_per_second"] = run_cells / wall if wall > 0 else math.nan
    return cost


__all__ = ["BasinCounts", "basin_stats", "cost_summary", "outcome_rows", "proportion", "wilson"]
