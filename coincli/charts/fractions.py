"""P(outcome) against the parameter of a continuation, with 95 % interval bands, and over a grid
of two parameters, maps of P(standing) with a level line and its band (matplotlib, loaded
lazily; PNG, SVG or PDF by the file's suffix)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..defaults import parameter_label
from ..files import check_figure_path, save_figure
from ..montecarlo import pender_uhrin
from ..montecarlo.over import Continuation
from .accuracy import PANELS_HINT, figure_axes


def _band(ax, x, rows, label, colour, marker="o"):
    p = np.array([r["probability"] for r in rows], dtype=float)
    lo = np.array([r["low"] for r in rows], dtype=float)
    hi = np.array([r["high"] for r in rows], dtype=float)
    ax.fill_between(x, lo, hi, color=colour, alpha=0.25, linewidth=0)
    ax.plot(x, p, marker=marker, ms=3, lw=1.2, color=colour, label=label)
    return p, lo, hi


PANELS = ("standing", "outcomes")  # P(standing) and the uncertain fraction; P(n)


def plot_over(result: Continuation, out=None, *, title: str | None = None, dpi: int = 150,
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
            one.set_xlabel(parameter_label(result.parameter))
    samples = sorted({r.samples for r in result.results})
    count = f"{samples[0]:,}" if len(samples) == 1 else f"{samples[0]:,}-{samples[-1]:,}"
    if own or title:
        fig.suptitle(title or f"Outcome probabilities against {result.parameter}: {count} "
                     "samples a value,\nthe same points at every value; bands: 95 % Wilson "
                     "intervals", fontsize=9)
    if out is not None:
        save_figure(fig, out, dpi)
    return fig


def _plot_standing(top, result: Continuation, x: np.ndarray) -> None:
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


def _plot_outcomes(bottom, result: Continuation, x: np.ndarray) -> None:
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




MAP_TOP = 0.5  # P(standing) at the top of a map's colour scale (above: its colour)
FEW_TICKS = 6  # a log axis of this many values or fewer is ticked at its values
# a cell of a map of P(standing) this much uncertain is hatched; the share is written in it on
# a map of at most WRITTEN_CELLS cells
UNCERTAIN_MARK = 0.05
UNCERTAIN_HATCH = "#ff6e6e"  # seen on viridis's dark and light ends alike
WRITTEN_CELLS = 64
GRID_PANELS = ("certain", "decided", "uncertain")  # P(standing) over each basis; uncertain
GRID_TITLES = {"certain": "P(standing), certain labels",
               "decided": "P(standing), all decided labels",
               "uncertain": "uncertain (of all samples)"}


def plot_grid(result: Continuation, out=None, *, level: float = 1 / 3,
              title: str | None = None, dpi: int = 150, ax=None,
              panels=("certain", "decided")):
    """A grid of two parameters as maps, one a panel (of :data:`GRID_PANELS`): P(standing)
    over the certain labels, over all decided labels, and the uncertain share, the first
    parameter across (as t/d when it is the thickness or the diameter), the second up (on a
    log scale when it spans more than a decade). Either is on a log scale too where cells as
    wide as the gaps between its values would reach zero: no cell of a positive parameter is
    drawn at a negative value. On P(standing): the line P = ``level`` and
    the lines where the 95 % intervals' low and high ends cross it (its 95 % band); across t/d,
    where the no-bounce geometric limit (2/pi) arctan(t/d) and Pender and Uhrin's planar die
    reach the level; the cells where UNCERTAIN_MARK of the samples or more are uncertain
    hatched (on a small map, with the share written in). Drawn in a new Figure or into
    ``ax`` (one Axes a panel), returned; written to ``out`` (.png, .svg, .pdf) unless None."""
    if out is not None:
        out = check_figure_path(Path(out), "plot")
    if len(result.parameters) != 2:
        raise ValueError(f"a map draws a grid of two parameters, got {len(result.parameters)}")
    panels = tuple(panels)
    unknown = [p for p in panels if p not in GRID_PANELS]
    if unknown or not panels:
        raise ValueError(f"unknown panel {unknown[0] if unknown else '(none)'!r}; panels are "
                         f"{', '.join(GRID_PANELS)}")
    fig, axes, own = figure_axes(ax, len(panels), (5.2 * len(panels), 4.4), hint=PANELS_HINT,
                                 ncols=len(panels), sharey=True)
    x, x_label, ratio = _across(result)
    y = np.asarray(result.axes[1], dtype=float)
    ox, oy = np.argsort(x), np.argsort(y)  # the values as given, drawn in order
    x, y = x[ox], y[oy]

    def ordered(field: np.ndarray) -> np.ndarray:
        return field.reshape(result.shape)[ox][:, oy]
    log_x, log_y = _logarithmic(x, decades=False), _logarithmic(y, decades=True)
    x_edges, y_edges = _edges(x, log_x), _edges(y, log_y)
    for name, one in zip(panels, axes, strict=True):
        if name == "uncertain":
            mesh = one.pcolormesh(x_edges, y_edges, ordered(uncertain_share(result)).T,
                                  cmap="Greys", vmin=0, vmax=1, shading="flat")
            fig.colorbar(mesh, ax=one, label="uncertain share")
        else:
            p, low, high = (ordered(f) for f in np.moveaxis(result.estimate(name), -1, 0))
            mesh = one.pcolormesh(x_edges, y_edges, p.T, cmap="viridis", vmin=0,
                                  vmax=MAP_TOP, shading="flat")
            fig.colorbar(mesh, ax=one, label="P(standing)", extend="max")
            handles = _level_lines(one, x, y, p, low, high, level, ratio)
            handles += _uncertain_marks(one, x, y, x_edges, y_edges,
                                        ordered(uncertain_share(result)))
            if handles and name == next(n for n in panels if n != "uncertain"):
                one.legend(handles=handles, fontsize=7, loc="upper left",
                           bbox_to_anchor=(0, -0.14), ncol=2, frameon=False)
        one.set_title(GRID_TITLES[name], fontsize=9)
        one.set_xlabel(x_label)
        if log_x:
            _log_scale(one, "x", x)
        if log_y:
            _log_scale(one, "y", y)
        if one is axes[0] or not own:
            second = result.parameters[1]
            one.set_ylabel(parameter_label(second))
    if own or title:
        samples = sorted({r.samples for r in result.results})
        count = f"{samples[0]:,}" if len(samples) == 1 else f"{samples[0]:,}-{samples[-1]:,}"
        fig.suptitle(title or f"P(standing) over {' and '.join(result.parameters)}: {count} "
                     f"samples a point, the same samples at every point; lines: P = "
                     f"{level:.3g} and its 95 % band", fontsize=9)
    if out is not None:
        save_figure(fig, out, dpi)
    return fig


def _across(result: Continuation) -> tuple[np.ndarray, str, bool]:
    """The first parameter's values as drawn across, their label, and whether they are t/d
    (the thickness or the diameter, the other dimension the same at every point)."""
    name = result.parameters[0]
    x = np.asarray(result.axes[0], dtype=float)
    coins = [r.scene["coin"] for r in result.results]
    other = {"thickness": "diameter", "diameter": "thickness"}.get(name)
    if other is not None and len({c[other] for c in coins}) == 1:
        ratio = np.array([c["thickness"] / c["diameter"] for c in coins[::len(result.axes[1])]])
        return ratio, f"t / d ({name} across)", True
    return x, parameter_label(name), False


def _logarithmic(centres: np.ndarray, *, decades: bool) -> bool:
    """Whether sorted centres are drawn on a log scale: all positive, and with cells of linear
    edges reaching zero or below (or, with ``decades``, spanning more than a decade)."""
    if centres.size < 2 or not np.all(centres > 0):
        return False
    return bool((decades and centres[-1] / centres[0] > 10) or _edges(centres, False)[0] <= 0)


def _log_scale(ax, which: str, centres: np.ndarray) -> None:
    """A log scale on ``ax``'s x or y axis; with a few values, ticked at those values alone
    (the powers of ten between two or three values say little and crowd)."""
    from matplotlib.ticker import NullLocator

    getattr(ax, f"set_{which}scale")("log")
    if centres.size <= FEW_TICKS:
        getattr(ax, f"set_{which}ticks")(centres, labels=[f"{v:.3g}" for v in centres])
        getattr(ax, f"{which}axis").set_minor_locator(NullLocator())


def _edges(centres: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around sorted centres: halfway between neighbours (geometrically on a log
    scale), the outer ones as far out as the inner."""
    c = np.log(centres) if log else np.asarray(centres, dtype=float)
    if c.size == 1:
        edges = np.array([c[0] - 0.5, c[0] + 0.5])
    else:
        mid = (c[1:] + c[:-1]) / 2
        edges = np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])
    return np.exp(edges) if log else edges


def uncertain_share(result: Continuation) -> np.ndarray:
    """The uncertain share of each point's samples (chaotic or undecided: no two rungs
    agreed), flat as the points are counted."""
    return np.array([r.uncertain["probability"] for r in result.results], dtype=float)


def _uncertain_marks(ax, x, y, x_edges, y_edges, share: np.ndarray) -> list:
    """Hatch the cells of a map of P(standing) (values ``x`` across, ``y`` up, sorted) whose
    uncertain share (``share``, [across, up]) is UNCERTAIN_MARK or more: P there stands on
    fewer labels (certain) or on labels the ladder did not agree on (decided). On a map of at
    most WRITTEN_CELLS cells, the share is written in each hatched cell. Their legend's
    handle, if any cell is hatched."""
    from matplotlib import patheffects
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Patch, Rectangle

    cells = [(i, j) for i, j in zip(*np.nonzero(share >= UNCERTAIN_MARK), strict=True)]
    if not cells:
        return []
    ax.add_collection(PatchCollection(
        [Rectangle((x_edges[i], y_edges[j]), x_edges[i + 1] - x_edges[i],
                   y_edges[j + 1] - y_edges[j]) for i, j in cells],
        facecolor="none", edgecolor=UNCERTAIN_HATCH, hatch="///", linewidth=0))
    if share.size <= WRITTEN_CELLS:
        outline = [patheffects.withStroke(linewidth=2, foreground="black")]
        for i, j in cells:  # at the cell's value: its centre on either scale
            ax.text(x[i], y[j], f"{100 * share[i, j]:.0f} %\nuncertain", ha="center",
                    va="center", fontsize=7, color="white", path_effects=outline)
    return [Patch(facecolor="none", edgecolor="0.35", hatch="///",
                  label=f"{100 * UNCERTAIN_MARK:.0f} % or more uncertain")]


def _level_lines(ax, x, y, p, low, high, level: float, ratio: bool) -> list:
    """The line P = level and its 95 % band (where the intervals' ends cross it); across t/d,
    the t/d at which the geometric limit and Pender and Uhrin reach the level. Their legend's
    handles."""
    from matplotlib.lines import Line2D

    handles = []
    if x.size > 1 and y.size > 1:
        for field, style, label in ((p, "-", f"P = {level:.3g}"),
                                    (low, "--", "95 % band (low, high ends)"), (high, "--", None)):
            if np.nanmin(field) < level < np.nanmax(field):
                ax.contour(x, y, field.T, levels=[level], colors="white", linestyles=style,
                           linewidths=1.6 if style == "-" else 1.0)
                if label:
                    handles.append(Line2D([], [], color="black", ls=style, label=label))
    if ratio:
        from scipy.optimize import brentq

        for t_d, style, label in (
                (math.tan(level * math.pi / 2), ":", "no bounce, (2/pi) arctan(t/d)"),
                (brentq(lambda q: pender_uhrin(q) - level, 1e-3, 1.0) if level < 0.5 else None,
                 "-.", "Pender & Uhrin, planar die")):
            if t_d is not None and x.min() <= t_d <= x.max():
                ax.axvline(t_d, color="#ff7f0e", ls=style, lw=1.2)
                handles.append(Line2D([], [], color="#ff7f0e", ls=style,
                                      label=f"{label}: {t_d:.3f}"))
    return handles


__all__ = ["GRID_PANELS", "PANELS", "plot_grid", "plot_over"]
