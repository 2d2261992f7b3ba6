"""The figure of ``coin basin analyze`` (matplotlib, loaded lazily): the uncertain fraction
f(eps) against eps on log-log axes with the fitted power laws, and S_b, S_bb and alpha by band
of the first swept axis."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..boundary import LOG2
from ..files import check_figure_path, save_figure
from .accuracy import PANELS_HINT, figure_axes

WHOLE_COLOUR = "black"


def band_colours(n: int) -> list:
    import matplotlib

    cmap = matplotlib.colormaps["viridis"]
    return [cmap(0.1 + 0.75 * i / max(n - 1, 1)) for i in range(n)]


def _axis_text(axis: dict) -> str:
    from ..defaults import AXIS_INFO

    label = AXIS_INFO.get(axis["name"], (axis["name"],))[0]
    return f"{label} [{axis['units']}]"


def _span_text(region, axis: dict) -> str:
    from ..defaults import AXIS_INFO

    label = AXIS_INFO.get(axis["name"], (axis["name"],))[0]
    lo, hi = region.span
    return f"{label} {lo:.2f}-{hi:.2f} {axis['units']}"


def _alpha_text(exp) -> str:
    if exp is None or not math.isfinite(exp.alpha):
        return "alpha: -"
    if math.isfinite(exp.alpha_low):
        return (rf"$\alpha$ = {exp.alpha:.2f} [{exp.alpha_low:.2f}, {exp.alpha_high:.2f}]")
    return rf"$\alpha$ = {exp.alpha:.2f} (2 points)"


def _plot_fractions(ax, analysis) -> None:
    axis0 = analysis.axes[0]
    regions = [(analysis.whole, WHOLE_COLOUR, "o")]
    regions += list(zip(analysis.bands, band_colours(len(analysis.bands)), ["s"] * 99,
                        strict=False))
    shown_bound = False
    for k, (region, colour, marker) in enumerate(regions):
        p, exp = region.perturbation, region.exponent
        if p is None:
            continue
        eps = p.eps
        pos = p.uncertain > 0
        has = p.evidence > 0
        name = "whole map" if region is analysis.whole else _span_text(region, axis0)
        # small horizontal offsets keep the error bars of the regions apart
        shift = 10 ** (0.06 * (k - (len(regions) - 1) / 2))
        ax.errorbar(eps[pos] * shift, p.fraction[pos],
                    yerr=[p.fraction[pos] - p.ci_low[pos], p.ci_high[pos] - p.fraction[pos]],
                    ls="none", marker=marker, ms=5 if k == 0 else 4, color=colour,
                    mfc=colour if k == 0 else "white", capsize=2, lw=1,
                    label=f"{name}: {_alpha_text(exp)}", zorder=3 if k == 0 else 2)
        zero = has & ~pos
        if zero.any():
            ax.plot(eps[zero] * shift, p.ci_high[zero], ls="none", marker="v", ms=5,
                    color=colour, mfc="white", zorder=2,
                    label=None if shown_bound else "f = 0: 95 % upper bound (not fitted)")
            shown_bound = True
        if exp is not None and math.isfinite(exp.alpha) and exp.eps.size:
            x = np.array([exp.eps.min(), exp.eps.max()])
            ax.plot(x, np.exp(exp.intercept) * x ** exp.alpha, color=colour,
                    lw=1.8 if k == 0 else 1.1, ls="-" if k == 0 else "--", zorder=1)
    whole = analysis.whole.perturbation
    if whole is not None and (whole.uncertain > 0).any():
        # a smooth boundary's slope, through the whole map's smallest-eps point
        i = int(np.flatnonzero(whole.uncertain > 0)[0])
        x = np.array([whole.eps[i], whole.eps[i] * 10 ** 2.5])
        ax.plot(x, whole.fraction[i] * (x / x[0]), color="grey", ls=":", lw=1.5, zorder=0,
                label=r"slope 1 ($\alpha$ = 1): a smooth boundary")
    spacing = min(1.0 / (a["n"] - 1) for a in analysis.axes)
    ax.axvline(spacing, color="grey", ls=":", lw=1)
    ax.text(spacing, 0.98, "grid spacing ", transform=ax.get_xaxis_transform(),
            color="grey", fontsize=7, ha="right", va="top", rotation=90)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(r"perturbation $\varepsilon$ [fraction of each axis's range]")
    ax.set_ylabel(r"uncertain fraction $f(\varepsilon)$ [1]")
    p = analysis.whole.perturbation
    n_points = p.n_points if p is not None else 0
    ax.set_title(f"Perturbation method: {n_points:,} points, lines: fits "
                 r"$f \propto \varepsilon^{\alpha}$", fontsize=10)
    ax.grid(True, which="both", alpha=0.25)
    if ax.get_legend_handles_labels()[0]:  # nothing to name without the perturbation method
        ax.legend(loc="lower right", fontsize=7, framealpha=0.9)


def _band_x(analysis):
    centres = np.array([0.5 * (b.span[0] + b.span[1]) for b in analysis.bands])
    half = np.array([0.5 * (b.span[1] - b.span[0]) for b in analysis.bands])
    return centres, half


def _plot_entropy(ax, analysis) -> None:
    x, half = _band_x(analysis)
    sb = [b.entropy.basin_entropy for b in analysis.bands]
    sbb = [b.entropy.boundary_basin_entropy for b in analysis.bands]
    ball = [b.fractal_test.boundary_basin_entropy if b.fractal_test else math.nan
            for b in analysis.bands]
    box = analysis.options.box
    w = analysis.whole
    ax.errorbar(x, sb, xerr=half, ls="-", marker="o", color="#1f77b4", capsize=0, lw=1.2,
                label=rf"$S_b$ (boxes of {box} cells); whole map {w.entropy.basin_entropy:.2f}")
    ax.errorbar(x, sbb, xerr=half, ls="-", marker="s", color="#d62728", capsize=0, lw=1.2,
                label=rf"$S_{{bb}}$ (boxes); whole map {w.entropy.boundary_basin_entropy:.2f}")
    whole_ball = (f"{w.fractal_test.boundary_basin_entropy:.2f}" if w.fractal_test
                  else "-")
    ax.plot(x, ball, ls="none", marker="D", color="#ff7f0e", mfc="white",
            label=rf"$S_{{bb}}$ in balls of radius {analysis.options.radius:g} "
                  f"(ball test); whole map {whole_ball}")
    right = x.max() + half[-1]
    ax.axhline(LOG2, color="grey", ls="--", lw=1)
    ax.text(right, LOG2, r"log 2: box $S_{bb}$ above it means fractal (sufficient) ",
            color="grey", fontsize=7, va="bottom", ha="right")
    smooth = next((b.fractal_test for b in analysis.bands if b.fractal_test), None)
    if smooth is not None and math.isfinite(smooth.high):
        ax.axhspan(smooth.low, smooth.high, color="#ff7f0e", alpha=0.12, lw=0)
        ax.text(right, smooth.low, "ball test: smooth band ", color="#ff7f0e", fontsize=7,
                va="top", ha="right")
    ax.set_xlabel(_axis_text(analysis.axes[0]))
    ax.set_ylabel("entropy [nat]")
    ax.set_xlim(x.min() - half[0], right)
    ax.set_ylim(bottom=0)
    ax.set_title("Basin entropy by band", fontsize=10)
    ax.grid(True, alpha=0.25)
    ax.legend(loc="upper left", fontsize=7, framealpha=0.9)


def _plot_alpha(ax, analysis) -> None:
    x, half = _band_x(analysis)
    alpha = np.array([b.alpha for b in analysis.bands])
    lo = np.array([b.exponent.alpha_low if b.exponent else math.nan for b in analysis.bands])
    hi = np.array([b.exponent.alpha_high if b.exponent else math.nan for b in analysis.bands])
    yerr = np.vstack([np.where(np.isfinite(lo), alpha - lo, 0.0),
                      np.where(np.isfinite(hi), hi - alpha, 0.0)])
    w = analysis.whole
    conf = int(round(100 * analysis.options.confidence))
    ax.errorbar(x, alpha, xerr=half, yerr=yerr, ls="-", marker="o", color="#2ca02c", capsize=3,
                lw=1.2, label=rf"$\alpha$, perturbation method ({conf} % interval); "
                              f"whole map {w.alpha:.2f}")
    grid_alpha = [b.grid_exponent.alpha if b.grid_exponent else math.nan
                  for b in analysis.bands]
    whole_alpha = w.grid_exponent.alpha if w.grid_exponent else math.nan
    whole_grid = (f"whole map {whole_alpha:.2f}" if math.isfinite(whole_alpha)
                  else "none: too small a map to count boxes on" if w.grid_exponent is None
                  else "whole map none")
    ax.plot(x, grid_alpha, ls="none", marker="^", color="#7f7f7f", mfc="white",
            label=rf"$\alpha$ by box counting on the map (Attractors.jl); {whole_grid}")
    ax.axhline(1.0, color="grey", ls="--", lw=1)
    ax.text(x.max() + half[-1], 1.0, r"smooth boundary: $\alpha$ = 1, $D$ = 1 ",
            color="grey", fontsize=7, va="bottom", ha="right")
    ax.set_xlabel(_axis_text(analysis.axes[0]))
    ax.set_ylabel(r"uncertainty exponent $\alpha$ [1]")
    finite = np.concatenate([alpha[np.isfinite(alpha)],
                             np.asarray(grid_alpha)[np.isfinite(grid_alpha)], [0.0]])
    # wide intervals (few uncertain points) run off the axes rather than squash them
    ax.set_ylim(min(-0.05, float(finite.min()) - 0.05), 1.3)
    ax.set_xlim(x.min() - half[0], x.max() + half[-1])
    sec = ax.secondary_yaxis("right", functions=(lambda a: 2 - a, lambda d: 2 - d))
    sec.set_ylabel(r"boundary dimension $D = 2 - \alpha$ [1]")
    ax.set_title("Uncertainty exponent by band", fontsize=10)
    ax.grid(True, alpha=0.25)
    ax.legend(loc="upper right", bbox_to_anchor=(1.0, 0.93), fontsize=7, framealpha=0.9)


PANELS = ("fractions", "entropy", "alpha")  # f(eps) with the fits; S_b and S_bb; alpha
WIDTHS = {"fractions": 1.35, "entropy": 1.0, "alpha": 1.0}  # a new figure's panel widths


def plot_analysis(analysis, path: Path | None = None, title: str | None = None,
                  dpi: int = 150, ax=None, panels=PANELS):
    """Draw the analysis figure and return it: the ``panels`` (of :data:`PANELS`, in that
    order) into ``ax`` (one Axes a panel) or a new Figure; written to ``path`` (.png, .svg,
    .pdf) unless it is None. The title is the figure's: drawn on a new one, or when given."""
    if path is not None:
        check_figure_path(path)
    panels = tuple(panels)
    unknown = [p for p in panels if p not in PANELS]
    if unknown or not panels:
        raise ValueError(f"unknown panel {unknown[0] if unknown else '(none)'!r}; panels are "
                         f"{', '.join(PANELS)}")
    draw = {"fractions": _plot_fractions, "entropy": _plot_entropy, "alpha": _plot_alpha}
    fig, axes, own = figure_axes(ax, len(panels), (17 * sum(WIDTHS[p] for p in panels) / 3.35,
                                                   5.6),
                                 hint=PANELS_HINT, ncols=len(panels),
                                 gridspec_kw={"width_ratios": [WIDTHS[p] for p in panels]})
    for name, one in zip(panels, axes, strict=True):
        draw[name](one, analysis)
    a0, a1 = analysis.axes
    if own or title:
        fig.suptitle(title or f"How fractal are the basin boundaries: {a0['name']} "
                              f"{a0['lo']:g}:{a0['hi']:g} {a0['units']} x {a1['name']} "
                              f"{a1['lo']:g}:{a1['hi']:g} {a1['units']}, "
                              f"{a0['n']} x {a1['n']} cells"
                              + (f", $\\mu$ = {analysis.friction:g}" if analysis.friction else ""),
                     fontsize=11)
    if path is not None:
        save_figure(fig, path, dpi)
    return fig


__all__ = ["PANELS", "band_colours", "plot_analysis"]
