"""The work-precision chart (matplotlib, loaded lazily) and its table; and what every chart
shares: a new Figure or the caller's Axes (:func:`figure_axes`)."""

from __future__ import annotations

import csv
import functools
import io
import json
import math
from pathlib import Path

from ..files import atomic_output, save_figure
from ..integrators.registry import METHODS
from ..version import __version__

COLOURS = {method: entry.colour for method, entry in METHODS.items()}  # the registry's


PANELS_HINT = " (panels= says which to draw)"  # for the charts of several panels


def figure_axes(ax, count: int, size: tuple[float, float], hint: str = "", **subplots):
    """``(figure, axes, own)`` for a chart of ``count`` panels: the caller's ``ax`` (an Axes
    for one panel, a sequence of ``count`` Axes for more; own = False), or a new Figure of
    ``size`` inches with ``count`` Axes laid out by ``subplots`` (``Figure.subplots``
    arguments; own = True). ``hint`` ends the message of a count that differs. A new Figure is
    made without pyplot: no backend is switched (a notebook's stays inline), and a figure
    nobody keeps is freed like any object."""
    if ax is None:
        fig = _shown_figure()(figsize=size, layout="constrained")
        axes = fig.subplots(squeeze=False, **subplots).ravel().tolist()
        return fig, axes, True
    if _is_axes(ax) or isinstance(ax, str) or not hasattr(ax, "__iter__"):
        axes = [ax]
    else:  # a list, or the array of Axes that subplots gives
        import numpy as np

        axes = list(np.asarray(ax, dtype=object).ravel())
    for one in axes:
        if not _is_axes(one):
            raise TypeError(f"ax must be a matplotlib Axes"
                            f"{'' if count == 1 else f' or a sequence of {count}'}, got "
                            f"{type(one).__name__}")
    if len(axes) != count:
        raise ValueError(f"ax: {count} panel{'s' * (count != 1)} to draw, got {len(axes)} "
                         f"Axes{hint}")
    return axes[0].figure, axes, False


@functools.cache
def _shown_figure():
    """A matplotlib Figure that shows itself in a notebook (as a PNG): a Figure made without
    pyplot has no display of its own until pyplot has loaded a notebook's inline backend."""
    from matplotlib.figure import Figure

    class ShownFigure(Figure):
        def _repr_png_(self) -> bytes:
            buffer = io.BytesIO()
            self.savefig(buffer, format="png", bbox_inches="tight")
            return buffer.getvalue()

    return ShownFigure


def _is_axes(ax) -> bool:
    from matplotlib.axes import Axes

    return isinstance(ax, Axes)


def study_rows(study) -> list[dict]:
    rows = []
    for p in study.points:
        rows.append({
            "method": p.setting.method.label,
            "knob": "rtol" if p.setting.adaptive else "dt",
            "value": p.setting.knob,
            "cpu_ms_per_trajectory": p.cpu_per_trajectory * 1e3,
            "trajectory_error": p.trajectory_error,
            "label_error_robust": p.label_error,
            "nonfinite_cells": p.nonfinite,
            "unsettled_cells": p.unsettled,
        })
    return rows


def write_table(study, path: Path, scene) -> None:
    rows = study_rows(study)
    if path.suffix == ".csv":
        with atomic_output(path) as tmp, open(tmp, "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
        return
    paper = study.paper_point
    best = study.best_under(0.01)
    data = {
        "version": __version__,
        "parameters": scene.to_dict(),
        "grid": {axis.name: [axis.lo, axis.hi, axis.n] for axis in study.grid.axes},
        "robust_cells": study.robust_cells,
        "cells": int(study.robust.size),
        "reference_agreement": study.reference_agreement,
        "trajectory_reference_gap": study.trajectory_reference_gap,
        "rows": rows,
        "paper_setting": None if paper is None else {
            "cpu_ms_per_trajectory": paper.cpu_per_trajectory * 1e3,
            "label_error_robust": paper.label_error,
            "trajectory_error": paper.trajectory_error},
        "cheapest_under_1_percent": None if best is None else best.setting.label,
        "verified_default": None if study.verified_point is None else {
            "setting": study.verified_point.setting.label,
            "cpu_ms_per_trajectory": study.verified_point.cpu_per_trajectory * 1e3,
            "certain_and_wrong_robust": study.verified_point.label_error,
            "uncertain_robust": study.verified_point.uncertain,
            "trajectory_error": study.verified_point.trajectory_error},
    }
    with atomic_output(path) as tmp:
        tmp.write_text(json.dumps(data, indent=2) + "\n")


def _knob_text(point) -> str:
    return f"{point.setting.knob:.0e}".replace("e-0", "e-")


def plot_study(study, path: Path, title: str = "") -> None:
    fig, (ax_traj, ax_label), _ = figure_axes(None, 2, (13, 6.0), ncols=2)
    floor = 0.5 / max(study.robust_cells, 1)  # a label error of 0 is drawn here
    by_method: dict[str, list] = {}
    for p in study.points:
        by_method.setdefault(p.setting.method, []).append(p)
    for method, points in by_method.items():
        points.sort(key=lambda p: p.cpu_per_trajectory)
        cost = [p.cpu_per_trajectory * 1e3 for p in points]
        traj = [p.trajectory_error if math.isfinite(p.trajectory_error) else float("nan")
                for p in points]
        label = [max(p.label_error, floor) for p in points]
        style = dict(color=COLOURS.get(method), marker="o", ms=4, lw=1.5, label=method.label)
        ax_traj.plot(cost, traj, **style)
        ax_label.plot(cost, label, **style)
        at_floor = [p for p in points if p.label_error <= 0]
        for p, x, y in zip(points, cost, label, strict=True):
            if p.label_error > 0:
                ax_label.annotate(_knob_text(p), (x, y), textcoords="offset points",
                                  xytext=(3, 3), fontsize=6, color=COLOURS.get(method))
        if at_floor:  # one note for the run of zeros, not a pile of labels on the floor
            first = min(at_floor, key=lambda p: p.cpu_per_trajectory)
            below = 10 + 8 * len([m for m in by_method if m < method])
            ax_label.annotate(f"0 from {_knob_text(first)}", (first.cpu_per_trajectory * 1e3,
                                                              floor),
                              textcoords="offset points", xytext=(0, -below), fontsize=7,
                              color=COLOURS.get(method), ha="center")
    if study.paper_point is not None:
        pp = study.paper_point
        for ax, y in ((ax_traj, pp.trajectory_error), (ax_label, max(pp.label_error, floor))):
            ax.plot([pp.cpu_per_trajectory * 1e3], [y], marker="*", ms=16, color="black",
                    ls="none", label="paper: symplectic Euler h=1e-6, 2 s", zorder=5)
    vp = study.verified_point
    if vp is not None:
        ax_label.plot([vp.cpu_per_trajectory * 1e3], [max(vp.label_error, floor)], marker="D",
                      ms=10, color="#9467bd", markeredgecolor="black", ls="none", zorder=6,
                      label=f"the default, verified ({vp.setting.label.replace(' verified', '')}"
                            f" and up): {100 * vp.uncertain:.2g} % of the robust cells uncertain")
    ax_label.axhline(0.01, color="grey", ls="--", lw=1, label="1 % label error")
    ax_label.axhline(floor, color="lightgrey", ls=":", lw=1, label="no wrong label (drawn here)")
    for ax in (ax_traj, ax_label):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time per trajectory [ms]")
        ax.grid(True, which="both", alpha=0.25)
    ax_traj.set_ylabel("state error ~0.06 s after the first impact [natural units: r, 1 rad,\n"
                       "$\\sqrt{2gr}$, $\\sqrt{2gr}/r$] (median of 5 throws)")
    ax_traj.set_title("Trajectory error vs cost")
    ax_label.set_ylabel(f"label error: fraction of the {study.robust_cells} robust cells "
                        "wrong [1]")
    ax_label.set_title("Basin label error vs cost")
    ax_label.set_ylim(bottom=floor / 5)  # room for the "0 from" notes above the ticks
    # one legend for both panels, below them: it never covers a curve
    handles, labels = ax_label.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8, frameon=False)
    if title:
        fig.suptitle(title, fontsize=10)
    save_figure(fig, path, 130)
