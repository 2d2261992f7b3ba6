"""The work-precision chart (matplotlib, loaded lazily) and its table."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

from ..enums import Method
from ..version import __version__
from .paths import atomic_output

COLOURS = {Method.SYMPLECTIC_EULER: "#d62728", Method.VERLET: "#ff7f0e", Method.RK4: "#2ca02c",
           Method.DOPRI5: "#1f77b4", Method.EVENT: "#9467bd"}


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
    }
    with atomic_output(path) as tmp:
        tmp.write_text(json.dumps(data, indent=2) + "\n")


def plot_study(study, path: Path, title: str = "") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_traj, ax_label) = plt.subplots(1, 2, figsize=(13, 5.2), constrained_layout=True)
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
        for p, x, y in zip(points, cost, label, strict=True):
            ax_label.annotate(f"{p.setting.knob:.0e}".replace("e-0", "e-"), (x, y),
                              textcoords="offset points", xytext=(3, 3), fontsize=6,
                              color=COLOURS.get(method))
    if study.paper_point is not None:
        pp = study.paper_point
        for ax, y in ((ax_traj, pp.trajectory_error), (ax_label, max(pp.label_error, floor))):
            ax.plot([pp.cpu_per_trajectory * 1e3], [y], marker="*", ms=16, color="black",
                    ls="none", label="paper: symplectic Euler h=1e-6, 2 s", zorder=5)
    ax_label.axhline(0.01, color="grey", ls="--", lw=1)
    ax_label.text(ax_label.get_xlim()[0], 0.0105, " 1 % label error", color="grey",
                  fontsize=8, va="bottom")
    ax_label.axhline(floor, color="lightgrey", ls=":", lw=1)
    for ax in (ax_traj, ax_label):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time per trajectory [ms]")
        ax.grid(True, which="both", alpha=0.25)
    ax_traj.set_ylabel("state error ~0.06 s after the first impact (median of 5 throws)")
    ax_traj.set_title("Trajectory error vs cost")
    ax_label.set_ylabel(f"label error on the {study.robust_cells} robust cells "
                        f"(0 drawn at {floor:.1e})")
    ax_label.set_title("Basin label error vs cost")
    ax_label.legend(loc="lower right", fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    try:
        with atomic_output(path) as tmp:
            fig.savefig(tmp, dpi=130, format="png")
    finally:
        plt.close(fig)
