"""A continuation's results (:class:`FractionsOver`): the outcome probabilities at each value of
one physical parameter, or at each point of a grid of two; where P(standing) crosses a level, and
the whole as an xarray Dataset (xarray loaded when asked for)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from ..montecarlo import PARAMETER_UNITS, Fractions
from ..montecarlo.results import BASES, level_crossing, percent_text
from ..montecarlo.tally import INTERVAL_NOTE
from ..params import ParameterError


@dataclass
class FractionsOver:
    """A continuation: the outcome probabilities at each value of one physical parameter, or at
    each point of a grid of two, the same sample points at every value. ``results`` are flat,
    the first parameter outermost (``results[i * len(axes[1]) + j]`` is at ``axes[0][i]``,
    ``axes[1][j]``); :meth:`to_dataset` gives them one dimension a parameter."""

    parameters: tuple[str, ...]
    axes: tuple[tuple[float, ...], ...]  # the values of each parameter
    results: list[Fractions]
    note: str | None
    cost: dict = field(default_factory=dict)
    store: str | None = None

    @property
    def parameter(self) -> str | None:
        """The parameter of a continuation along one (None for a grid)."""
        return self.parameters[0] if len(self.parameters) == 1 else None

    @property
    def values(self) -> list[float] | None:
        """The values of a continuation along one parameter (None for a grid)."""
        return list(self.axes[0]) if len(self.parameters) == 1 else None

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(values) for values in self.axes)

    @property
    def standing(self) -> np.ndarray:
        """(*shape, 3): P(standing), low, high at each value (over the certain labels)."""
        return self.estimate("certain")

    @property
    def interrupted(self) -> bool:
        return any(r.interrupted for r in self.results)

    def __repr__(self) -> str:
        if self.parameter is None:
            size = " x ".join(f"{len(v)} {name} ({PARAMETER_UNITS[name]})"
                              for name, v in zip(self.parameters, self.axes, strict=True))
            p = self.standing[..., 0]
            return (f"FractionsOver({size}, P(standing) from {100 * np.nanmin(p):.3g} % to "
                    f"{100 * np.nanmax(p):.3g} %)")
        unit = PARAMETER_UNITS[self.parameter]
        rows = "; ".join(f"{v:g}: {percent_text(r.standing)}" for v, r in
                         zip(self.values, self.results, strict=True))
        if len(rows) > 300:
            rows = rows[:300].rsplit(";", 1)[0] + "; ..."
        return (f"FractionsOver({self.parameter} ({unit}), {len(self.values)} values, "
                f"P(standing) {rows})")

    def to_dict(self) -> dict:
        out = {"parameters": list(self.parameters),
               "axes": {name: {"units": PARAMETER_UNITS[name], "values": list(values)}
                        for name, values in zip(self.parameters, self.axes, strict=True)},
               "shape": list(self.shape), "note": self.note, "cost": self.cost,
               "store": self.store, "results": [r.to_dict() for r in self.results]}
        if self.parameter is not None:  # as along one parameter before grids
            out = {"parameter": self.parameter, "units": PARAMETER_UNITS[self.parameter],
                   "values": self.values, **out}
        return out

    def estimate(self, basis: str = "certain") -> np.ndarray:
        """(*shape, 3): P(standing), low, high at each value over the ``basis``: "certain"
        labels, all "decided" samples, or all "labelled" ones."""
        if basis not in BASES:
            raise ParameterError(f"basis must be one of {', '.join(BASES)}, got {basis!r}")
        rows = [BASES[basis](r) for r in self.results]
        return np.array([[row["probability"], row["low"], row["high"]] for row in rows],
                        dtype=np.float64).reshape(*self.shape, 3)

    def crossing(self, level: float = 1 / 3, along: str | None = None,
                 basis: str = "certain") -> dict[str, np.ndarray]:
        """Where P(standing) (over ``basis``, see :meth:`estimate`) rises through ``level``
        along the parameter ``along`` (default: the first), at each value of the other one:
        ``{"at": ..., "from": ..., "to": ...}`` in that parameter's units, arrays over the
        other parameter (0-d along one), by :func:`level_crossing` (the interval: where the
        95 % intervals' high and low ends cross the level). NaN where it does not cross within
        the values."""
        along = along or self.parameters[0]
        if along not in self.parameters:
            raise ParameterError(f"along: {along!r} is not a parameter of this result "
                                 f"({', '.join(self.parameters)})")
        axis = self.parameters.index(along)
        x = np.asarray(self.axes[axis], dtype=np.float64)
        order = np.argsort(x)
        grid = np.moveaxis(self.estimate(basis), axis, -2)[..., order, :]
        out = {key: np.empty(grid.shape[:-2]) for key in ("at", "from", "to")}
        for index in np.ndindex(*grid.shape[:-2]):
            p, low, high = grid[index].T
            found = level_crossing(x[order], p, low, high, level)
            for key, value in zip(("at", "from", "to"), found, strict=True):
                out[key][index] = value
        return out

    def to_dataset(self):
        """An xarray Dataset, one dimension a parameter (its values the coordinates): for
        ``outcome`` standing and lying, ``probability``, ``low``, ``high`` and ``count`` over
        the certain labels (of ``counted``) and the same with ``decided_`` over all decided
        samples (of ``decided``); ``n_probability``, ``n_low``, ``n_high``, ``n_count`` per n
        (certain labels); ``uncertain`` (its ``low``, ``high``), a share of ``samples``, and its
        causes ``chaotic`` and ``undecided`` (counts); each point's ``thickness_over_diameter``,
        ``mass`` and ``inertia``. ``to_netcdf`` writes it."""
        import xarray as xr

        dims = tuple(self.parameters)
        shape = self.shape
        results = self.results
        ns = sorted({row["n"] for r in results for row in r.outcomes})

        def grid(values, dtype=np.float64, extra=()):
            return np.asarray(values, dtype=dtype).reshape(*shape, *extra)

        def rows(pick) -> dict[str, np.ndarray]:
            """probability, low, high, count of (standing, lying) by ``pick(result, pose)``."""
            return {key: grid([[pick(r, pose)[key] for pose in ("standing", "lying")]
                               for r in results], np.int64 if key == "count" else np.float64,
                              (2,)) for key in ("probability", "low", "high", "count")}

        certain = rows(lambda r, pose: getattr(r, pose))
        decided = rows(lambda r, pose: r.all_decided[pose])
        by_n = {key: grid([[r.probability(n)[key] for n in ns] for r in results],
                          np.int64 if key == "count" else np.float64, (len(ns),))
                for key in ("probability", "low", "high", "count")}
        pose = (*dims, "outcome")
        per_n = (*dims, "n")
        variables = {
            **{key: (pose, value) for key, value in certain.items()},
            **{f"decided_{key}": (pose, value) for key, value in decided.items()},
            **{f"n_{key}": (per_n, value) for key, value in by_n.items()},
            "samples": (dims, grid([r.samples for r in results], np.int64)),
            "counted": (dims, grid([r.counted for r in results], np.int64)),
            "decided": (dims, grid([r.all_decided.get("decided", 0) for r in results],
                                   np.int64)),
            **{name: (dims, grid([r.uncertain[key] for r in results])) for name, key in
               (("uncertain", "probability"), ("uncertain_low", "low"),
                ("uncertain_high", "high"))},
            **{cause: (dims, grid([r.uncertain[cause] for r in results], np.int64))
               for cause in ("chaotic", "undecided")},
            **{name: (dims, grid([r.scene["coin"][name] for r in results]))
               for name in ("mass", "inertia")},
            "thickness_over_diameter": (dims, grid(
                [r.scene["coin"]["thickness"] / r.scene["coin"]["diameter"] for r in results])),
        }
        ds = xr.Dataset(variables, coords={
            **{name: (name, np.asarray(values, dtype=np.float64),
                      {"units": PARAMETER_UNITS[name]})
               for name, values in zip(dims, self.axes, strict=True)},
            "outcome": ("outcome", ["standing", "lying"]), "n": ("n", np.asarray(ns, np.int64))})
        ds.attrs = {"title": "coin fractions: outcome probabilities over "
                             + " and ".join(dims),
                    "interval": INTERVAL_NOTE, "note": self.note or "",
                    "store": self.store or "",
                    "sampling": json.dumps(results[0].sampling if results else {}),
                    "goal": json.dumps(results[0].goal if results else {})}
        for name, text in DATASET_ATTRS.items():
            ds[name].attrs["long_name"] = text
        return ds


DATASET_ATTRS = {
    "probability": "P(outcome) over the certain labels (of counted)",
    "low": "low end of the 95 % Wilson interval of probability",
    "high": "high end of the 95 % Wilson interval of probability",
    "count": "samples with a certain label of that outcome",
    "decided_probability": "P(outcome) over every decided sample (of decided), chaotic ones "
                           "with their deepest rung's label",
    "decided_low": "low end of the 95 % Wilson interval of decided_probability",
    "decided_high": "high end of the 95 % Wilson interval of decided_probability",
    "decided_count": "decided samples of that outcome",
    "n_probability": "P(n) over the certain labels",
    "n_low": "low end of the 95 % Wilson interval of n_probability",
    "n_high": "high end of the 95 % Wilson interval of n_probability",
    "n_count": "samples with the certain label n",
    "samples": "samples drawn", "counted": "samples with a certain label",
    "decided": "samples whose deepest rung settled",
    "uncertain": "share of the samples without a certain label",
    "uncertain_low": "low end of the 95 % Wilson interval of uncertain",
    "uncertain_high": "high end of the 95 % Wilson interval of uncertain",
    "chaotic": "uncertain samples: every rung decided, no two successive ones agree",
    "undecided": "uncertain samples: a rung did not settle within its horizon or budget",
    "mass": "the coin's mass at this point (kg)", "inertia": "its moment of inertia (kg m^2)",
    "thickness_over_diameter": "t / d of the coin at this point",
}


__all__ = ["DATASET_ATTRS", "FractionsOver"]
