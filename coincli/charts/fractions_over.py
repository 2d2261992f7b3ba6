"""A continuation's results with their Dataset view (:class:`FractionsOver`): what
``coincli.fractions_over`` returns; xarray is loaded when the Dataset is asked for."""

from __future__ import annotations

import json
from dataclasses import fields

import numpy as np

from ..montecarlo import PARAMETER_UNITS
from ..montecarlo.over import Continuation
from ..montecarlo.tally import INTERVAL_NOTE


class FractionsOver(Continuation):
    """A continuation (:class:`coincli.montecarlo.over.Continuation`): the outcome
    probabilities at each value of one physical parameter, or at each point of a grid of two,
    the same sample points at every value; :meth:`to_dataset` gives them one dimension a
    parameter."""

    @classmethod
    def of(cls, continuation: Continuation) -> FractionsOver:
        """The engine's result with its views."""
        return cls(**{f.name: getattr(continuation, f.name) for f in fields(continuation)})

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
