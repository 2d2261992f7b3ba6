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
from pathlib import Path

import numpy as np

from ..enums import Certainty, Status
from ..grid import AXIS_INFO
from ..integrators import NO_LABEL
from .dataset import Basin
from .paths import atomic_output

WHITE = (1.0, 1.0, 1.0, 1.0)
STANDING = (0.0, 0.0, 0.0, 1.0)
UNCERTAIN = (0.62, 0.62, 0.62, 1.0)
UNCERTAIN_MARK = "#505050"
UNSETTLED = (0.56, 0.27, 0.68, 1.0)
NONFINITE = (1.0, 0.0, 1.0, 1.0)
NOT_COMPUTED_BG = "#eeeeee"
NOT_COMPUTED_HATCH = "////"


def _ramp_colours(n_max_even: int):
    """Colours of the even n in -n_max..n_max (n_max even, >= 2), as {n: rgba}."""
    from matplotlib import colormaps

    steps = n_max_even // 2
    cw = colormaps["YlOrRd"]
    ccw = colormaps["YlGnBu"]
    colours = {0: WHITE}
    for k in range(1, steps + 1):
        t = (k - 1) / max(steps - 1, 1)
        colours[-2 * k] = tuple(cw(0.22 + 0.78 * t))
        colours[2 * k] = tuple(ccw(0.30 + 0.70 * t))
    return colours


def _labelled_mask(basin: Basin) -> np.ndarray:
    st = basin.arrays["status"]
    # a label needs a labelled status and a count: never draw the fill value as an n
    return (((st == Status.SETTLED) | (st == Status.UNSETTLED))
            & (basin.arrays["quarter_turns"] != NO_LABEL))


def n_range(basin: Basin, n_max: int | None = None) -> int:
    """Largest even |n| on the colour bar (at least 2): ``n_max`` rounded up to even if given
    (a fixed scale keeps the colours of a zoom equal to those of the full map), else the
    largest |n| in the store."""
    if n_max is None:
        q = basin.arrays["quarter_turns"][_labelled_mask(basin)].astype(np.int64)
        n_max = int(np.abs(q).max()) if q.size else 2
    n_max = int(n_max) + int(n_max) % 2
    return max(n_max, 2)


def basin_rgba(basin: Basin, n_max: int | None = None) -> tuple[np.ndarray, dict]:
    """RGBA image (axis 0 = first swept axis) and the cells of each overlay class; even n
    beyond the colour bar take its end colours."""
    q = basin.arrays["quarter_turns"].astype(np.int64)
    st = basin.arrays["status"]
    labelled = _labelled_mask(basin)
    top = n_range(basin, n_max)
    colours = _ramp_colours(top)
    rgba = np.zeros(q.shape + (4,), dtype=float)  # transparent = not computed
    even = labelled & (q % 2 == 0)
    clipped = np.clip(q, -top, top)
    for n, colour in colours.items():
        rgba[even & (clipped == n)] = colour
    standing = labelled & (q % 2 == 1)
    rgba[standing] = STANDING
    classes = {"standing": standing}
    if basin.verified:
        uncertain = labelled & (basin.arrays["certainty"] == Certainty.UNCERTAIN)
        rgba[uncertain] = UNCERTAIN
        classes["uncertain"] = uncertain
        classes["standing"] = standing & ~uncertain
    unsettled = st == Status.UNSETTLED
    rgba[unsettled] = UNSETTLED
    classes["unsettled"] = unsettled
    nonfinite = st == Status.NONFINITE
    rgba[nonfinite] = NONFINITE
    classes["non-finite"] = nonfinite
    classes["not computed"] = st == Status.NOT_COMPUTED
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


def render_png(basin: Basin, out: str | os.PathLike, title: str | None = None,
               dpi: int = 150, size: tuple[float, float] = (8.6, 6.8),
               n_max: int | None = None) -> Path:
    """Draw the map to a PNG file; returns its path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    out = Path(out)
    if out.parent and not out.parent.exists():
        raise FileNotFoundError(f"directory {out.parent} does not exist")
    rgba, classes = basin_rgba(basin, n_max)
    ax0, ax1 = basin.axes
    x, y = basin.coords
    dx = (x[-1] - x[0]) / (x.size - 1)
    dy = (y[-1] - y[0]) / (y.size - 1)
    extent = (x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2)

    fig, ax = plt.subplots(figsize=size, layout="constrained")
    ax.set_facecolor(NOT_COMPUTED_BG)
    ax.patch.set_hatch(NOT_COMPUTED_HATCH)
    ax.patch.set_edgecolor("#b0b0b0")
    ax.imshow(np.transpose(rgba, (1, 0, 2)), origin="lower", extent=extent, aspect="auto",
              interpolation="nearest")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel(_axis_label(ax0))
    ax.set_ylabel(_axis_label(ax1))

    # ring the standing cells when one cell is only a pixel or two on the image
    standing = classes["standing"]
    fig_w_px = size[0] * dpi * 0.75
    ring = standing.any() and fig_w_px / x.size < 4 and standing.mean() < 0.05
    if ring:
        i, j = np.nonzero(standing)
        ax.scatter(x[i], y[j], s=14, facecolors="none", edgecolors="black", linewidths=0.6,
                   zorder=3)

    # likewise cross the uncertain cells when they are few and small
    uncertain = classes.get("uncertain")
    cross = (uncertain is not None and uncertain.any() and fig_w_px / x.size < 4
             and uncertain.mean() < 0.05)
    if cross:
        i, j = np.nonzero(uncertain)
        ax.scatter(x[i], y[j], s=12, marker="x", color=UNCERTAIN_MARK, linewidths=0.7,
                   zorder=3)

    n_max = n_range(basin, n_max)
    colours = _ramp_colours(n_max)
    evens = list(range(-n_max, n_max + 1, 2))
    cmap = ListedColormap([colours[n] for n in evens])
    norm = BoundaryNorm([n - 1 for n in evens] + [n_max + 1], cmap.N)
    mappable = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    cbar = fig.colorbar(mappable, ax=ax, pad=0.02, fraction=0.05)
    tick_step = 2 * max(1, math.ceil(len(evens) / 18))
    cbar.set_ticks([n for n in evens if n % tick_step == 0])
    cbar.set_label("n lying (even): < 0 clockwise, > 0 counter-clockwise")
    cbar.ax.tick_params(labelsize=8)

    counts = {name: int(mask.sum()) for name, mask in classes.items()}
    handles = [Patch(facecolor=STANDING, edgecolor="black",
                     label=f"standing (odd n): {counts['standing']:,}")]
    if ring:
        handles[0] = Line2D([], [], marker="o", markersize=7, linestyle="none",
                            markeredgecolor="black", markerfacecolor="none",
                            label=f"standing (odd n): black cell, ringed: "
                                  f"{counts['standing']:,}")
    for name, colour in (("uncertain", UNCERTAIN), ("unsettled", UNSETTLED),
                         ("non-finite", NONFINITE)):
        if name in counts and (counts[name] or name == "uncertain"):
            label = {"unsettled": "unsettled at t_end"}.get(name, name)
            if name == "uncertain" and cross:
                handles.append(Line2D([], [], marker="x", markersize=6, linestyle="none",
                                      color=UNCERTAIN_MARK,
                                      label=f"uncertain: grey cell, crossed: {counts[name]:,}"))
                continue
            handles.append(Patch(facecolor=colour, edgecolor="black",
                                 label=f"{label}: {counts[name]:,}"))
    if counts["not computed"]:
        handles.append(Patch(facecolor=NOT_COMPUTED_BG, edgecolor="#808080",
                             hatch=NOT_COMPUTED_HATCH,
                             label=f"not computed: {counts['not computed']:,}"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, -0.09), ncols=3,
              fontsize=8, frameon=False)

    attrs = basin.attrs
    method = attrs["method"]
    setting = (f"rtol {method['rtol']:g}" if method["adaptive"] else f"h = {method['dt']:g} s")
    done = int(basin.done.sum())
    total = int(basin.done.size)
    if title is None:
        title = (f"Final number n of quarter turns, {x.size} x {y.size} cells"
                 + (f" (partial: {done} of {total} tiles" if done < total else "")
                 + (f", {len(basin.damaged)} damaged" if basin.damaged else "")
                 + (")" if done < total else ""))
    fig.suptitle(title, fontsize=11)
    params = attrs["parameters"]
    ax.set_title(f"{_fixed_text(basin)}; k = {params['foundation']['k']:g} N/m, "
                 f"c = {params['foundation']['c']:g} N s/m; {method['name']} {setting}, "
                 f"$t_{{end}}$ = {method['t_end']:g} s", fontsize=8, color="#444444")
    try:
        with atomic_output(out) as tmp:  # complete or absent, never truncated
            fig.savefig(tmp, dpi=dpi, format="png")
    finally:
        plt.close(fig)
    return out


def log_rerun(basin: Basin, rrd: str | os.PathLike) -> Path:
    """Save the map to a Rerun recording: ``basin/n`` a SegmentationImage of the outcome classes
    (one class per n, plus not computed and non-finite) with their colours and names in an
    AnnotationContext, and ``basin/flags`` the uncertain and unsettled cells."""
    import rerun as rr

    rrd = Path(rrd)
    q = basin.arrays["quarter_turns"].astype(np.int64)
    st = basin.arrays["status"]
    labelled = _labelled_mask(basin)
    n_even = n_range(basin)
    n_max = n_even + 1  # odd n up to one past the largest even n
    offset = 10
    ramp = _ramp_colours(n_even)
    classes = [rr.ClassDescription(info=(0, "not computed", (0, 0, 0, 0))),
               rr.ClassDescription(info=(1, "non-finite", (255, 0, 255, 255)))]
    for n in range(-n_max, n_max + 1):
        if n % 2:
            colour, pose = STANDING, "standing"
        else:
            colour, pose = ramp.get(n, WHITE), "lying"
        rgb = tuple(int(round(255 * c)) for c in colour)
        classes.append(rr.ClassDescription(info=(offset + n + n_max, f"n = {n} ({pose})", rgb)))
    ids = np.zeros(q.shape, dtype=np.uint16)
    ids[labelled] = (offset + q[labelled] + n_max).astype(np.uint16)
    ids[st == Status.NONFINITE] = 1
    flags = np.zeros(q.shape, dtype=np.uint8)
    flags[st == Status.UNSETTLED] = 2
    if basin.verified:
        flags[labelled & (basin.arrays["certainty"] == Certainty.UNCERTAIN)] = 1
    # images are row = vertical axis from the top: second swept axis, highest value first
    rec = rr.RecordingStream("coin_basin")
    rec.save(str(rrd))
    rec.log("basin", rr.AnnotationContext(classes), static=True)
    rec.log("basin/n", rr.SegmentationImage(np.ascontiguousarray(ids.T[::-1])), static=True)
    rec.log("basin/flags", rr.AnnotationContext([
        rr.ClassDescription(info=(0, "certain", (0, 0, 0, 0))),
        rr.ClassDescription(info=(1, "uncertain", (160, 160, 160, 255))),
        rr.ClassDescription(info=(2, "unsettled at t_end", (143, 69, 173, 255)))]), static=True)
    rec.log("basin/flags", rr.SegmentationImage(np.ascontiguousarray(flags.T[::-1]),
                                                opacity=0.8), static=True)
    ax0, ax1 = basin.axes
    rec.log("basin/description", rr.TextDocument(
        f"Basin map of {basin.path or 'a basin computed in memory'}: horizontal {ax0['name']} "
        f"from {ax0['lo']} to {ax0['hi']} "
        f"{ax0['units']} ({ax0['n']} cells), vertical {ax1['name']} from {ax1['hi']} (top) to "
        f"{ax1['lo']} {ax1['units']} ({ax1['n']} cells)."), static=True)
    rec.flush()
    return rrd


__all__ = ["basin_rgba", "log_rerun", "render_png"]
