"""P(outcome) against the parameter of a continuation, with 95 % interval bands (matplotlib,
loaded lazily; PNG, SVG or PDF by the file's suffix)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..montecarlo import PARAMETER_UNITS, FractionsOver, pender_uhrin
from .charts import PANELS_HINT, figure_axes
from .paths import check_figure_path, save_figure


def _band(ax, x, rows, label, colour, marker="o"):
    p = np.array([r["probability"] for r in rows], dtype=float)
    lo = np.array([r["low"] for r in rows], dtype=float)
    hi = np.array([r["high"] for r in rows], dtype=float)
    ax.fill_between(x, lo, hi, color=colour, alpha=0.25, linewidth=0)
    ax.plot(x, p, marker=marker, ms=3, lw=1.2, color=colour, label=label)
    return p, lo, hi


PANELS = ("standing", "outcomes")  # P(standing) and the uncertain fraction; P(n)


def plot_over(result: FractionsOver, out=None, *, title: str | None = None, dpi: int = 150,
              ax=None, panels=PANELS):
    """The ``panels`` (of :data:`PANELS`, in that order), stacked in a new Figure or drawn into
    ``ax`` (one Axes a panel), returned; written to ``out`` (.png, .svg, .pdf) unless None.
    "standing": P(standing) (log scale when it spans more than two decades) with the uncertain
    fraction and, for thickness or diameter, the planar-die formula of Pender and Uhrin;
    "outcomes": P(n) of the most probable outcomes. The title is the figure's: drawn on a new
    one, or when given."""
    if out is not None:
        out = check_figure_path(Path(out), "plot")
    panels = tuple(panels)
    unknown = [p for p in panels if p not in PANELS]
    if unknown or not panels:
        raise ValueError(f"unknown panel {unknown[0] if unknown else '(none)'!r}; panels are "
                         f"{', '.join(PANELS)}")
    fig, axes, own = figure_axes(ax, len(panels), (7.5, 3.75 * len(panels)),
                                 hint=PANELS_HINT, nrows=len(panels), sharex=True)
    x = np.asarray(result.values, dtype=float)
    draw = {"standing": _plot_standing, "outcomes": _plot_outcomes}
    for name, one in zip(panels, axes, strict=True):
        draw[name](one, result, x)
        if one is axes[-1] or not own:  # stacked in a new figure, the bottom one says x
            one.set_xlabel(f"{result.parameter} ({PARAMETER_UNITS[result.parameter]})")
    samples = sorted({r.samples for r in result.results})
    count = f"{samples[0]:,}" if len(samples) == 1 else f"{samples[0]:,}-{samples[-1]:,}"
    if own or title:
        fig.suptitle(title or f"Outcome probabilities against {result.parameter}: {count} "
                     "samples a value,\nthe same points at every value; bands: 95 % Wilson "
                     "intervals", fontsize=9)
    if out is not None:
        save_figure(fig, out, dpi)
    return fig


def _plot_standing(top, result: FractionsOver, x: np.ndarray) -> None:
    name = result.parameter
    p, lo, _ = _band(top, x, [r.standing for r in result.results], "P(standing), certain labels",
                     "#000000")
    _band(top, x, [r.all_labelled["standing"] for r in result.results],
          "P(standing), all labelled (uncertain ones included)", "#1f77b4", marker="^")
    _band(top, x, [r.uncertain for r in result.results], "uncertain (of all samples)",
          "#888888", marker=".")
    if name in ("thickness", "diameter"):
        ratios = np.array([r.scene["coin"]["thickness"] / r.scene["coin"]["diameter"]
                           for r in result.results])
        fine = np.linspace(ratios.min(), ratios.max(), 400)
        xs = np.interp(fine, ratios, x) if ratios[0] < ratios[-1] else \
            np.interp(fine, ratios[::-1], x[::-1])
        top.plot(xs, pender_uhrin(fine), "--", color="#d62728", lw=1.2,
                 label="planar die, Pender & Uhrin (random orientation)")
    positive = p[np.isfinite(p) & (p > 0)]
    if positive.size and positive.max() / max(positive.min(), 1e-300) > 100:
        top.set_yscale("log")
        floor = np.nanmin(np.where(lo > 0, lo, np.nan)) if np.any(lo > 0) else positive.min()
        top.set_ylim(bottom=max(floor / 2, 1e-7))
    diameters = {r.scene["coin"]["diameter"] for r in result.results}
    thicknesses = {r.scene["coin"]["thickness"] for r in result.results}
    if name == "thickness" and len(diameters) == 1:
        d = diameters.pop()
        top.secondary_xaxis("top", functions=(lambda t: t / d, lambda q: q * d)) \
            .set_xlabel("t / d")
    elif name == "diameter" and len(thicknesses) == 1:
        t = thicknesses.pop()
        top.secondary_xaxis("top", functions=(lambda d: t / np.maximum(d, 1e-12),
                                              lambda q: t / np.maximum(q, 1e-12))) \
            .set_xlabel("t / d")
    top.set_ylabel("probability")
    top.legend(fontsize=8, loc="best")
    top.grid(True, which="both", alpha=0.3)


def _plot_outcomes(bottom, result: FractionsOver, x: np.ndarray) -> None:
    """P(n) of the most probable outcomes n, by their largest probability over the values."""
    from matplotlib import colormaps

    best: dict[int, float] = {}
    for r in result.results:
        for row in r.outcomes:
            if math.isfinite(row["probability"]):
                best[row["n"]] = max(best.get(row["n"], 0.0), row["probability"])
    shown = sorted(sorted(best, key=lambda n: -best[n])[:8])
    colours = colormaps["tab10"]
    for i, n in enumerate(shown):
        rows = [r.probability(n) for r in result.results]
        _band(bottom, x, rows, f"n = {n} ({'standing' if n % 2 else 'lying'})", colours(i % 10),
              marker="o" if n % 2 == 0 else "s")
    bottom.set_ylabel("P(n), certain labels")
    bottom.legend(fontsize=8, ncol=2, loc="best")
    bottom.grid(True, alpha=0.3)


__all__ = ["PANELS", "plot_over"]
