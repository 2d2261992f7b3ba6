"""A continuation's results (:class:`Continuation`): the outcome probabilities at each value of
one physical parameter, or at each point of a grid of two, and where P(standing) crosses a
level. What the Monte Carlo engine returns; the API hands it out with its Dataset view
(:class:`coincli.charts.fractions_over.FractionsOver`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..defaults import parameter_label
from ..params import ParameterError
from .continuation import PARAMETER_UNITS
from .results import BASES, Fractions, level_crossing, percent_text


@dataclass
class Continuation:
    """A continuation: the outcome probabilities at each value of one physical parameter, or at
    each point of a grid of two, the same sample points at every value. ``results`` are flat,
    the first parameter outermost (``results[i * len(axes[1]) + j]`` is at ``axes[0][i]``,
    ``axes[1][j]``)."""

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
            size = " x ".join(f"{len(v)} {parameter_label(name)}"
                              for name, v in zip(self.parameters, self.axes, strict=True))
            p = self.standing[..., 0]
            return (f"{type(self).__name__}({size}, P(standing) from {100 * np.nanmin(p):.3g} % to "
                    f"{100 * np.nanmax(p):.3g} %)")
        rows = "; ".join(f"{v:g}: {percent_text(r.standing)}" for v, r in
                         zip(self.values, self.results, strict=True))
        if len(rows) > 300:
            rows = rows[:300].rsplit(";", 1)[0] + "; ..."
        return (f"{type(self).__name__}({parameter_label(self.parameter)}, "
                f"{len(self.values)} values, P(standing) {rows})")

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


__all__ = ["Continuation"]
