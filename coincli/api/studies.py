"""The studies of the integration methods: accuracy against cost over a grid of throws
(`coin accuracy`: :func:`plan_accuracy`, :func:`accuracy_study`, its chart and table), where
each fixed-step method fails (`coin accuracy --stability`: :func:`step_limits`) and the cost of
each method's default setting beside the paper's (`coin bench`: :func:`bench_methods`).

Measurements, not answers about one throw: each takes seconds to minutes on all cores. Their
options are checked before any work (ParameterError naming them); ranges and resolutions are
taken as a front end types them (``'0.05:2'``, ``'32'``, ``'32x16'``) or as numbers."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..enums import Method
from ..params import ParameterError, Scene, shown, validate


def _range(name: str, value) -> tuple[float, float]:
    """A required LO:HI range (``'0.05:2'`` or a pair)."""
    from ..grid import parse_range

    span = parse_range(name, value)
    if not isinstance(span, tuple):
        raise ParameterError(f"{name} must be a range LO:HI, got '{shown(value)}'",
                             parameters=(name,))
    return span


def _grid(scene: Scene, vy, vphi, res, name: str = "res"):
    """The (vy0, vphi0) grid of a study, its options checked."""
    from ..accuracy import vy_vphi_grid
    from ..grid import parse_pair

    return vy_vphi_grid(scene, _range("vy", vy), _range("vphi", vphi),
                        parse_pair(name, res, minimum=2))


def _threads(threads: int | None) -> int:
    from ..engines.executors import usable_cores

    if threads is None:
        return usable_cores()
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ParameterError(f"threads must be at least 1, got {threads!r}",
                             parameters=("threads",))
    return threads


@dataclass(frozen=True)
class AccuracyPlan:
    """An accuracy study checked before any work (:func:`plan_accuracy`)."""

    scene: Scene
    grid: object  # the (vy0, vphi0) Grid of the label errors
    settings: tuple  # the coincli.accuracy.Setting of each point
    threads: int


def plan_accuracy(scene: Scene, *, vy="0.05:2", vphi="-20:20", res=32, methods=None,
                  quick: bool = False, threads: int | None = None) -> AccuracyPlan:
    """Check an accuracy study before any work: every method (or ``methods``: Method members
    or names, or names in one string, ``'rk4,event'``) at the settings of its ladder (two each
    with ``quick``: a smoke test), over a ``res`` grid (N or NxM) of throws over ``vy`` x
    ``vphi``, on ``threads`` threads (default one per core)."""
    from .. import accuracy as acc

    scene = validate(scene)
    if isinstance(methods, str):  # 'rk4,event'
        methods = [name.strip() for name in methods.split(",") if name.strip()]
    try:
        names = [Method.parse(m) for m in (methods or list(Method))]
    except ValueError as exc:
        raise ParameterError(str(exc), parameters=("methods",)) from None
    threads = _threads(threads)
    grid = _grid(scene, vy, vphi, res)
    settings = acc.ladder_settings(names)
    if quick:
        settings = [s for s in settings
                    if s.knob in (acc.LADDERS[s.method][1], acc.LADDERS[s.method][-2])]
    return AccuracyPlan(scene, grid, tuple(settings), threads)


def accuracy_study(plan: AccuracyPlan, *, progress: Callable[[str], None] | None = None):
    """Accuracy against cost of the settings of ``plan`` (of :func:`plan_accuracy`): each
    setting's trajectory error (five throws about 0.06 s after their first impact, against
    the event method at rtol 1e-12) and label error (the robust cells of the grid, where that
    reference and RK4 at h = 2.5e-7 agree, whose n differs), with its CPU time a trajectory;
    the scene's own setting, verified, and the paper's. ``progress(text)`` before each piece.
    Returns a :class:`coincli.accuracy.Study`; :func:`plot_accuracy` draws it,
    :func:`write_accuracy_table` writes its points."""
    from .. import accuracy as acc

    return acc.run_study(plan.scene, plan.grid, list(plan.settings), plan.threads,
                         progress=progress)


def plot_accuracy(study, out: str | os.PathLike, *, title: str = "") -> Path:
    """Draw an accuracy study (trajectory error and label error against CPU time, a line a
    method) to a PNG, SVG or PDF; returns its path."""
    from ..charts.accuracy import plot_study

    plot_study(study, Path(out), title=title)
    return Path(out)


def write_accuracy_table(study, path: str | os.PathLike, scene: Scene) -> Path:
    """Write every point of an accuracy study to ``path``: JSON (with the references, the
    paper's setting and the scene) or CSV (a row a setting); complete or absent."""
    from ..charts.accuracy import write_table

    path = Path(path)
    if path.suffix not in (".json", ".csv"):
        raise ParameterError(f"table must end in .json or .csv, got {path}",
                             parameters=("table",))
    write_table(study, path, scene)
    return path


@dataclass(frozen=True)
class StepLimits:
    """Where each fixed-step method fails (:func:`step_limits`): a coin resting on two corners
    kicked by ``kick`` rad/s and run ``seconds`` s; a step fails if the run goes non-finite
    or gains energy, or, on a damped foundation, does not come to rest
    (:func:`coincli.accuracy.fails`)."""

    kick: float
    seconds: float
    # method, predicted_stable_step (the frictionless rocking mode's), at_rest_stable_step
    # (the step linearized at the resting coin under the scene's own law, friction included),
    # measured_failure_step, ratio (measured / predicted)
    methods: tuple[dict, ...]

    def to_dict(self) -> dict:
        """What `coin accuracy --stability --json` prints."""
        return {"test": {"kick_vphi": self.kick, "t_end": self.seconds},
                "methods": [dict(m) for m in self.methods]}


def step_limits(scene: Scene) -> StepLimits:
    """For each fixed-step method, the step predicted stable for ``scene`` (the spectral radius
    of its step on the damped rocking mode), the largest step stable linearized at the resting
    coin under the scene's own law (with friction: where a stick is a stiff damper on the
    slip), and the step measured to fail (bisection between a quarter and four times the
    linearized one; inf if even that does not fail)."""
    from .. import accuracy as acc
    from ..integrators import METHODS

    scene = validate(scene)
    rows = []
    for method in METHODS.values():
        if method.adaptive:
            continue
        limit = acc.measured_limit(scene, method.method)
        rows.append({"method": method.name, "predicted_stable_step": limit.predicted,
                     "at_rest_stable_step": limit.at_rest,
                     "measured_failure_step": limit.measured,
                     "ratio": limit.measured / limit.predicted})
    return StepLimits(acc.STABILITY_KICK, acc.STABILITY_TIME, tuple(rows))


@dataclass(frozen=True)
class MethodBench:
    """The cost of each method's default setting and of the paper's, side by side on the same
    cells, and their label agreement on a grid (:func:`bench_methods`)."""

    cost_shape: tuple[int, int]  # the cells timed
    label_shape: tuple[int, int]  # the grid of the label check
    repeats: int
    robust: int  # cells of the label grid where the two references agree
    label_cells: int
    reference_agreement: float  # fraction of the label grid where they agree
    rows: tuple[dict, ...]  # name, method, setting, verified, dt, rtol, full_run,
    # ms_per_trajectory, rounds_ms, speedup_vs_paper, label_agreement_robust,
    # uncertain_robust

    def to_dict(self) -> dict:
        """Plain values (what `coin bench --json` prints, beside its start-up and basin
        timings)."""
        return {"cost_cells": math.prod(self.cost_shape), "label_cells": self.label_cells,
                "robust_cells": self.robust, "reference_agreement": self.reference_agreement,
                "rows": [dict(r) for r in self.rows]}


def bench_methods(scene: Scene, *, vy="0.05:2", vphi="-20:20", cost_res=8, label_res=24,
                  repeats: int = 3, threads: int | None = None,
                  progress: Callable[[str], None] | None = None) -> MethodBench:
    """Time every method's default setting, the verified default and the paper's setting
    (symplectic Euler, h = 1e-6, always 2 s) on the same ``cost_res`` cells over ``vy`` x
    ``vphi``, one thread, interleaved round by round ``repeats`` times (the median kept); then
    their labels against the converged references on a ``label_res`` grid on ``threads``
    threads. ``progress(text)`` before each piece."""
    from .. import bench
    from ..integrators.registry import setting_text

    scene = validate(scene)
    threads = _threads(threads)
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise ParameterError(f"repeats must be at least 1, got {repeats!r}",
                             parameters=("repeats",))
    cost_grid = _grid(scene, vy, vphi, cost_res, "cost_res")
    label_grid = _grid(scene, vy, vphi, label_res, "label_res")
    rows = bench.side_by_side(scene, cost_grid, repeats, progress)
    check = bench.label_check(scene, label_grid, rows, threads, progress)
    paper = next(r for r in rows if r.full_run)
    table = tuple({"name": r.name, "method": r.setting.method.label,
                   "setting": setting_text(r.setting.method, r.setting.dt, r.setting.rtol),
                   "verified": r.setting.verify, "dt": r.setting.dt, "rtol": r.setting.rtol,
                   "full_run": r.full_run, "ms_per_trajectory": r.seconds_per_trajectory * 1e3,
                   "rounds_ms": [t * 1e3 for t in r.repeats],
                   "speedup_vs_paper": paper.seconds_per_trajectory / r.seconds_per_trajectory,
                   "label_agreement_robust": r.label_agreement,
                   "uncertain_robust": r.uncertain} for r in rows)
    return MethodBench(tuple(cost_grid.shape), tuple(label_grid.shape), repeats,
                       int(check.robust.sum()), int(check.robust.size), check.agreement_ab,
                       table)


__all__ = ["AccuracyPlan", "MethodBench", "StepLimits", "accuracy_study", "bench_methods",
           "plan_accuracy", "plot_accuracy", "step_limits", "write_accuracy_table"]
