"""Pictures of a basin store: a PNG in the paper's colours (matplotlib, Agg) and, optionally, a
Rerun recording of the map as a SegmentationImage with an AnnotationContext.

Colours: phi grows counter-clockwise, so n < 0 is a net clockwise rotation, drawn yellow (small
|n|) to red (large |n|) as in the paper; n > 0 (counter-clockwise) green to blue; n = 0 white.
Standing cells (odd n) are black, ringed when the cells are too small to see one alone. Cells
without a trustworthy label are drawn over the colours: uncertain (not converged on the ladder)
grey (and crossed when they are few and small), unsettled at t_end purple, non-finite
magenta; cells not computed are left transparent over a hatched background. The first swept
axis is horizontal, the second vertical.
"""

from __future__ import annotations

import math
import os
import textwrap

import numpy as np

from ..enums import Certainty, Status
from ..files import check_figure_path, save_figure
from ..grid import AXIS_INFO
from ..integrators import NO_LABEL
from ..params import ParameterError, scene_from_dict
from ..quantities import parse_quantity
from ..stores.basin_schema import method_text
from ..stores.dataset import Basin
from .accuracy import figure_axes

WHITE = (1.0, 1.0, 1.0, 1.0)
STANDING = (0.0, 0.0, 0.0, 1.0)
UNCERTAIN = (0.62, 0.62, 0.62, 1.0)
UNDECIDED = (0.36, 0.36, 0.36, 1.0)  # a rung not settled: darker than chaotic uncertain cells
UNSETTLED = (0.56, 0.27, 0.68, 1.0)
NONFINITE = (1.0, 0.0, 1.0, 1.0)
NOT_COMPUTED_BG = "#eeeeee"
NOT_COMPUTED_HATCH = "////"


DEFAULT_N_MAX = 24  # the colour scale's end: the same colours on every map, partial or zoomed
MIN_MARK_PX = 2.0  # standing and uncertain cells are drawn at least this many pixels wide


def ramp_colours(n_max_even: int):
    """Colours of the even n in -n_max..n_max (n_max even, >= 2), as {n: rgba}: clockwise
    yellow to red, counter-clockwise green to blue as in the paper, spaced by the square root of
    |n| so that the common small counts stay far apart and visible against white."""
    from matplotlib import colormaps

    steps = n_max_even // 2
    cw = colormaps["YlOrRd"]
    ccw = colormaps["YlGnBu"]
    colours = {0: WHITE}
    for k in range(1, steps + 1):
        t = math.sqrt((k - 1) / max(steps - 1, 1))
        colours[-2 * k] = tuple(cw(0.30 + 0.68 * t))
        colours[2 * k] = tuple(ccw(0.35 + 0.63 * t))
    return colours


def cell_classes(arrays: dict, verified: bool) -> dict[str, np.ndarray]:
    """The cells of each class a map draws, as boolean masks, in the order drawn (a later
    class covers an earlier one): "labelled" (an n, in its colour), "uncertain" and
    "undecided" (verified sweeps: rungs that disagree, a rung not settled), "unsettled",
    "non-finite", "not computed". The one classification of `coin basin render` and of the
    Rerun view (:mod:`coincli.io.live`)."""
    st, q = arrays["status"], arrays["quarter_turns"]
    # a label needs a labelled status and a count: never draw the fill value as an n
    labelled = ((st == Status.SETTLED) | (st == Status.UNSETTLED)) & (q != NO_LABEL)
    classes = {"labelled": labelled}
    if verified:
        classes["uncertain"] = labelled & (arrays["certainty"] == Certainty.UNCERTAIN)
        classes["undecided"] = labelled & (arrays["certainty"] == Certainty.UNDECIDED)
    classes["unsettled"] = st == Status.UNSETTLED
    classes["non-finite"] = st == Status.NONFINITE
    classes["not computed"] = st == Status.NOT_COMPUTED
    return classes


def n_range(basin: Basin, n_max: int | None = None) -> int:
    """Largest even |n| on the colour bar (at least 2): ``n_max`` rounded up to even, by default
    DEFAULT_N_MAX, so that every map (partial, zoomed, another scene) has the same colours;
    larger |n| take the ends of the scale."""
    n_max = DEFAULT_N_MAX if n_max is None else int(n_max)
    n_max = n_max + n_max % 2
    return max(n_max, 2)


def basin_rgba(basin: Basin, n_max: int | None = None) -> tuple[np.ndarray, dict]:
    """RGBA image (axis 0 = first swept axis) and the cells of each overlay class; even n
    beyond the colour bar take its end colours."""
    q = basin.arrays["quarter_turns"].astype(np.int64)
    cells = cell_classes(basin.arrays, basin.verified)
    labelled = cells["labelled"]
    top = n_range(basin, n_max)
    colours = ramp_colours(top)
    rgba = np.zeros(q.shape + (4,), dtype=float)  # transparent = not computed
    even = labelled & (q % 2 == 0)
    clipped = np.clip(q, -top, top)
    for n, colour in colours.items():
        rgba[even & (clipped == n)] = colour
    standing = labelled & (q % 2 == 1)
    rgba[standing] = STANDING
    classes = {"standing": standing}
    if basin.verified:
        rgba[cells["uncertain"]] = UNCERTAIN
        rgba[cells["undecided"]] = UNDECIDED
        classes["uncertain"] = cells["uncertain"]
        # undecided and unsettled: counted as unsettled, drawn so
        classes["undecided"] = cells["undecided"] & ~cells["unsettled"]
        classes["standing"] = standing & ~cells["uncertain"] & ~cells["undecided"]
    for name, colour in (("unsettled", UNSETTLED), ("non-finite", NONFINITE)):
        rgba[cells[name]] = colour
        classes[name] = cells[name]
    classes["not computed"] = cells["not computed"]
    return rgba, classes


def _axis_label(axis: dict) -> str:
    label, unit, long_name = AXIS_INFO[axis["name"]]
    return f"{long_name} {label} [{unit}]"


def _fixed_text(basin: Basin) -> str:
    fixed = basin.attrs["sweep"]["fixed"]
    parts = []
    for name, value in fixed.items():
        label, unit, _ = AXIS_INFO[name]
        parts.append(f"{label} = {value:.4g} {unit}")
    return ", ".join(parts)


FIELDS = ("n", "settle_time")


def render_map(basin: Basin, out: str | os.PathLike | None = None, title: str | None = None,
               dpi: int = 150, size: tuple[float, float] = (8.6, 6.8),
               n_max: int | None = None, field: str = "n", marks=(), ax=None):
    """Draw the map into ``ax`` (a matplotlib Axes; its colour bar takes room from that Axes
    alone, so maps side by side keep their own) or into a new Figure of ``size`` inches, and
    write the figure to ``out`` (PNG, SVG or PDF by its extension) unless it is None; returns
    the Figure. ``field``: "n", the outcome in the paper's colours, or "settle_time", when
    each throw's outcome was decided (its energy fell below E_crit). ``marks``: points (value
    of the first swept axis, value of the second) drawn as white circles with a black
    edge."""
    from matplotlib.patches import Patch
    from matplotlib.transforms import offset_copy

    if out is not None:
        out = check_figure_path(out, "picture")
        if out.parent and not out.parent.exists():
            raise FileNotFoundError(f"directory {out.parent} does not exist")
    if field not in FIELDS:
        raise ValueError(f"unknown field {field!r}; one of {', '.join(FIELDS)}")
    ax0, ax1 = basin.axes
    x, y = basin.coords
    dx = (x[-1] - x[0]) / (x.size - 1)
    dy = (y[-1] - y[0]) / (y.size - 1)
    extent = (x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2)
    marks = check_marks(basin, marks)

    fig, (ax,), own = figure_axes(ax, 1, size)
    ax.set_facecolor(NOT_COMPUTED_BG)
    ax.patch.set_hatch(NOT_COMPUTED_HATCH)
    ax.patch.set_edgecolor("#b0b0b0")
    if field == "n":
        rgba, classes = basin_rgba(basin, n_max)
        ax.imshow(np.transpose(rgba, (1, 0, 2)), origin="lower", extent=extent, aspect="auto",
                  interpolation="nearest")
        # cells a pixel or two wide vanish in the image: mark standing and uncertain cells
        # as squares at least MIN_MARK_PX wide (the same look at any resolution)
        width = size[0] * 0.75 if own else _axes_width(ax)  # inches
        cell_px = width * dpi / x.size
        if cell_px < 3 * MIN_MARK_PX:
            side = max(cell_px, MIN_MARK_PX) * 72.0 / dpi  # points
            for name, colour in (("uncertain", UNCERTAIN), ("undecided", UNDECIDED),
                                 ("standing", STANDING)):
                mask = classes.get(name)
                if mask is not None and mask.any():
                    i, j = np.nonzero(mask)
                    ax.scatter(x[i], y[j], s=side ** 2, marker="s", color=colour,
                               linewidths=0, zorder=3)
        _n_colour_bar(fig, ax, n_range(basin, n_max), short=not own)
        handles = _class_handles(basin, classes, Patch)
    else:
        handles = _settle_time_image(basin, ax, fig, extent, Patch)
    if marks:
        mx, my = zip(*marks, strict=True)
        ax.scatter(mx, my, s=MARK_SIZE, marker="o", facecolors="white", edgecolors="black",
                   linewidths=1.2, zorder=5)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(_axis_label(ax0))
    ax.set_ylabel(_axis_label(ax1))
    # a panel of the caller's figure: one column, so that the legend is no wider than the map
    # (the layout would narrow the map to make room for a wider one)
    # below the tick labels and the axis label, whatever the map's height
    below = offset_copy(ax.transAxes, fig=fig, y=-LEGEND_DROP_PT, units="points")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, 0.0),
              bbox_transform=below, ncols=3 if own else 1, fontsize=8, frameon=False)

    attrs = basin.attrs
    method = attrs["method"]
    setting = (f"rtol {method['rtol']:g}" if method["adaptive"] else f"h = {method['dt']:g} s")
    if len(method.get("verification", {}).get("rungs", [])) > 1:
        setting += ", verified"
    done = int((basin.done != 0).sum())
    total = int(basin.done.size)
    if title is None:
        what = ("Final number n of quarter turns" if field == "n"
                else "When the outcome was decided (energy below E_crit)")
        title = (f"{what}, {x.size} x {y.size} cells"
                 + (f" (partial: {done} of {total} tiles" if done < total else "")
                 + (f", {len(basin.damaged)} damaged" if basin.damaged else "")
                 + (")" if done < total else ""))
    params = attrs["parameters"]
    mu = params["foundation"].get("mu") or 0.0  # a store without friction records no mu
    setting_parts = (_fixed_text(basin),
                     f"k = {params['foundation']['k']:g} N/m, c = {params['foundation']['c']:g} "
                     "N s/m" + (f", $\\mu$ = {mu:g}" if mu else ""),
                     f"{method_text(method)} {setting}, "
                     + (f"$t_{{end}}$ = {method['t_end']:g} s" if method["t_end"] is not None
                        else "until decided"))
    setting_text = "; ".join(setting_parts)
    if own:
        fig.suptitle(title, fontsize=11)
        subtitle = ax.set_title(setting_text, fontsize=8, color="#444444")
        _fit_width(subtitle, setting_parts, WIDTH_USED * fig.bbox.width)
    else:  # the figure's title is the caller's: each map says what it is over itself, its
        # settings wrapped to the map's width
        chars = max(30, int(_axes_width(ax) * 72 / (0.5 * 8)))
        ax.set_title(f"{title}\n{textwrap.fill(setting_text, chars)}", fontsize=8)
    if out is not None:
        save_figure(fig, out, dpi)
    return fig


def _fit_width(text, parts, width: float) -> None:
    """Set ``text`` (an artist) to ``parts`` joined by '; ', in one line if it is at most
    ``width`` display units wide, else broken after a '; ' wherever the line would be wider
    (measured as drawn: the mathtext of the parts is narrower than its source)."""
    lines: list[str] = []
    current = ""
    for part in parts:
        candidate = f"{current}; {part}" if current else part
        text.set_text(candidate)
        if current and text.get_window_extent().width > width:
            lines.append(current + ";")
            current = part
        else:
            current = candidate
    text.set_text("\n".join([*lines, current]))


def _axes_width(ax) -> float:
    """The width of ``ax`` in inches (as placed before the layout adjusts it)."""
    return ax.get_position().width * ax.figure.get_size_inches()[0]


LEGEND_DROP_PT = 30.0  # from the map's lower edge to the legend's top: under the axis label
WIDTH_USED = 0.96  # of the figure's width, at most, for a map's line of settings
MARK_SIZE = 64.0  # points^2: a circle about 3 mm wide at any resolution


def check_marks(basin: Basin, marks) -> list[tuple[float, float]]:
    """The marks as (first axis, second axis) pairs of finite numbers inside the swept ranges
    (each a number or text as :mod:`coincli.quantities` reads it: ``("pi/2", 3.5)``);
    ValueError naming the mark otherwise."""
    out = []
    axes = basin.axes
    r = scene_from_dict(basin.attrs["parameters"]).coin.r
    for mark in marks or ():
        try:
            v, w = (parse_quantity(axis["name"], c).resolve(r)
                    for axis, c in zip(axes, mark, strict=True))
        except ParameterError as exc:
            raise ValueError(f"mark {mark!r:.40}: {exc}") from None
        except (TypeError, ValueError):  # not a pair
            raise ValueError(f"a mark is a pair of numbers ({axes[0]['name']}, "
                             f"{axes[1]['name']}), got {mark!r:.40}") from None
        for axis, value in zip(axes, (v, w), strict=True):
            if not (math.isfinite(value) and axis["lo"] <= value <= axis["hi"]):
                raise ValueError(f"mark {v:g},{w:g}: {axis['name']} = {value:g} is outside the "
                                 f"swept range {axis['lo']:g} to {axis['hi']:g} "
                                 f"{axis['units']}")
        out.append((v, w))
    return out


def _n_colour_bar(fig, ax, n_max: int, short: bool = False) -> None:
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import BoundaryNorm, ListedColormap

    colours = ramp_colours(n_max)
    evens = list(range(-n_max, n_max + 1, 2))
    cmap = ListedColormap([colours[n] for n in evens])
    norm = BoundaryNorm([n - 1 for n in evens] + [n_max + 1], cmap.N)
    mappable = ScalarMappable(norm=norm, cmap=cmap)
    cbar = fig.colorbar(mappable, ax=ax, pad=0.02, fraction=0.05)
    tick_step = 2 * max(1, math.ceil(len(evens) / 18))
    ticks = [n for n in evens if n % tick_step == 0]
    cbar.set_ticks(ticks)
    cbar.set_ticklabels([f"≤ {n}" if n == -n_max else f"≥ {n}" if n == n_max else str(n)
                         for n in ticks])
    cbar.set_label("n (even: lying)" if short else
                   "n lying (even): < 0 clockwise, > 0 counter-clockwise")
    cbar.ax.tick_params(labelsize=8)


def _class_handles(basin: Basin, classes: dict, Patch) -> list:
    counts = {name: int(mask.sum()) for name, mask in classes.items()}
    handles = [Patch(facecolor=STANDING, edgecolor="black",
                     label=f"standing (odd n): {counts['standing']:,}")]
    for name, colour in (("uncertain", UNCERTAIN), ("undecided", UNDECIDED),
                         ("unsettled", UNSETTLED), ("non-finite", NONFINITE)):
        if name in counts and (counts[name] or (name == "uncertain" and basin.verified)):
            label = {"unsettled": "no outcome by the end",
                     "uncertain": "uncertain (decided, rungs disagree: chaotic)",
                     "undecided": "undecided (a rung did not settle)"}.get(name, name)
            handles.append(Patch(facecolor=colour, edgecolor="black",
                                 label=f"{label}: {counts[name]:,}"))
    if counts["not computed"]:
        handles.append(Patch(facecolor=NOT_COMPUTED_BG, edgecolor="#808080",
                             hatch=NOT_COMPUTED_HATCH,
                             label=f"not computed: {counts['not computed']:,}"))
    return handles


def _settle_time_image(basin: Basin, ax, fig, extent, Patch) -> list:
    """The settle time of the settled (and, verified, certain) cells; the rest grey."""
    st = basin.arrays["status"]
    shown = st == Status.SETTLED
    if basin.verified:
        shown &= basin.arrays["certainty"] == Certainty.CERTAIN
    times = np.where(shown, basin.arrays["settle_time"], np.nan).astype(float)
    other = (st != Status.NOT_COMPUTED) & ~shown
    grey = np.zeros(times.shape + (4,))
    grey[other] = UNCERTAIN
    ax.imshow(np.transpose(grey, (1, 0, 2)), origin="lower", extent=extent, aspect="auto",
              interpolation="nearest")
    image = ax.imshow(times.T, origin="lower", extent=extent, aspect="auto",
                      interpolation="nearest", cmap="viridis")
    cbar = fig.colorbar(image, ax=ax, pad=0.02, fraction=0.05)
    cbar.set_label("time at which the outcome was decided, t_settle [s]")
    handles = [Patch(facecolor=UNCERTAIN, edgecolor="black",
                     label=f"no certain outcome: {int(other.sum()):,}")]
    missing = int((st == Status.NOT_COMPUTED).sum())
    if missing:
        handles.append(Patch(facecolor=NOT_COMPUTED_BG, edgecolor="#808080",
                             hatch=NOT_COMPUTED_HATCH, label=f"not computed: {missing:,}"))
    return handles


__all__ = ["DEFAULT_N_MAX", "FIELDS", "MARK_SIZE", "basin_rgba", "check_marks",
           "render_map"]
