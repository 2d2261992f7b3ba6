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
from collections.abc import Mapping

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


class BasinStats(Mapping):
    """The statistics of a basin (``coincli.basin_stats``): outcome counts and fractions,
    P(standing) with its 95 % Wilson interval, the cells without a label, the certain and
    uncertain cells of a verified sweep, the tiles (done, damaged) and the cost. The figures
    most asked for are attributes (``stats.standing["probability"]``, ``stats.outcomes``);
    :meth:`to_dict` gives everything as plain values (``coin basin stats --json``: a value that
    cannot be known is None), and the object reads as that mapping too
    (``stats["standing"]``)."""

    def __init__(self, counts: BasinCounts, done: np.ndarray, damaged,
                 tile_seconds: np.ndarray, runs: list[dict], metadata_damaged=(),
                 parameters_changed=()):
        from .jsonable import jsonable

        out = counts.summary()
        out.update({"tiles_total": int(np.size(done)),
                    "tiles_done": int(np.count_nonzero(done)),
                    "tiles_damaged": [list(map(int, t)) for t in sorted(damaged)]})
        out["cost"] = cost_summary(out["computed"], tile_seconds, done, runs)
        out["metadata_damaged"] = list(metadata_damaged)
        out["parameters_changed"] = list(parameters_changed)
        out["warnings"] = stats_warnings(out)
        self._values = jsonable(out)

    def to_dict(self) -> dict:
        import copy

        return copy.deepcopy(self._values)

    def __getitem__(self, key: str):
        return self._values[key]

    def __iter__(self):
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    @property
    def outcomes(self) -> list[dict]:
        return self._values["outcomes"]

    @property
    def standing(self) -> dict:
        return self._values["standing"]

    @property
    def standing_certain(self) -> dict | None:
        return self._values.get("standing_certain")

    @property
    def uncertain(self) -> dict | None:
        return self._values.get("uncertain")

    @property
    def warnings(self) -> list[str]:
        return self._values["warnings"]

    @property
    def complete(self) -> bool:
        return self._values["tiles_done"] == self._values["tiles_total"]

    def __repr__(self) -> str:
        p = self.standing
        return (f"BasinStats({self._values['cells']:,} cells, {self._values['computed']:,} "
                f"computed; P(standing) = {p['probability']:.4g} "
                f"[{p['low']:.4g}, {p['high']:.4g}])" if p["probability"] is not None
                else f"BasinStats({self._values['cells']:,} cells, nothing labelled)")


def stats_warnings(stats: dict) -> list[str]:
    """What the numbers of a basin's statistics do not say: a partial store's fractions are of
    the tiles computed so far, which are no random sample of the map (a sweep computes the
    highest-energy tiles first); changed parameters and damaged metadata (what verifying the
    store finds)."""
    out = []
    done, total = stats["tiles_done"], stats["tiles_total"]
    if done < total:
        out.append(f"partial store: {done} of {total} tiles computed "
                   f"({100 * done / total:.1f} %); the fractions and intervals are over the "
                   "computed cells only, which are no random sample of the map: they need not "
                   "hold for the whole map")
    out += [f"parameters changed in {problem}" for problem in stats.get("parameters_changed", [])]
    metadata = stats.get("metadata_damaged", [])
    if metadata:
        out.append(f"{len(metadata)} metadata file{'s' if len(metadata) > 1 else ''} damaged "
                   f"({', '.join(metadata[:4])}{' ...' if len(metadata) > 4 else ''}): "
                   "verifying the store lists them, resuming the sweep rewrites them")
    return out


__all__ = ["BasinCounts", "BasinStats", "basin_stats", "cost_summary", "outcome_rows",
           "proportion", "stats_warnings", "wilson"]
