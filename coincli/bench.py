"""The benchmark behind ``coin bench`` (a measurement, not a test): per-trajectory cost of each
method's default setting and of the paper's setting, measured side by side on the same cells,
and each one's label agreement with the converged reference on the same grid.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

import numpy as np

from .accuracy import Setting, run_grid, run_references
from .enums import Method, Status
from .grid import Grid
from .integrators import label_states, warm_up
from .params import Scene, model_params, run_settings

# Each method's default setting: for the fixed-step methods the paper's step (on the chart none
# of them reaches 1 % label error at any affordable step), for the adaptive ones the cheapest
# tolerance under 1 % label error with 95 % confidence on the chart (docs/accuracy.png).
METHOD_DEFAULTS = {method: Setting(method, 1e-6, 1e-6) for method in Method}
PAPER = "paper (symplectic Euler h=1e-6, full 2 s)"


@dataclass
class CostRow:
    name: str
    setting: Setting
    full_run: bool
    seconds_per_trajectory: float  # median over repeats, one thread
    repeats: list[float]
    label_agreement: float = float("nan")  # on the robust cells of the label grid


def time_cells(scene: Scene, setting: Setting, states: np.ndarray, full_run: bool) -> float:
    """Seconds per trajectory for one pass over ``states`` on this thread."""
    run_scene = setting.apply(scene, stop_on_settle=not full_run, t_end=2.0)
    p = model_params(run_scene)
    settings = run_settings(run_scene.integration)
    warm_up(p, settings, states[0])  # load the compiled kernel first
    start = time.thread_time()
    label_states(p, settings, states)
    return (time.thread_time() - start) / states.shape[0]


def side_by_side(scene: Scene, cost_grid: Grid, repeats: int = 3,
                 progress=None) -> list[CostRow]:
    """Cost of every default setting and of the paper's, interleaved round by round on the same
    cells so that machine noise hits them alike; the median of the rounds is reported."""
    say = progress or (lambda text: None)
    states = cost_grid.states()
    entries = [(method.label, s, False) for method, s in METHOD_DEFAULTS.items()]
    entries.append((PAPER, METHOD_DEFAULTS[Method.SYMPLECTIC_EULER], True))
    times: dict[str, list[float]] = {name: [] for name, _, _ in entries}
    for r in range(repeats):
        for name, setting, full in entries:
            say(f"cost round {r + 1}/{repeats}: {name}")
            times[name].append(time_cells(scene, setting, states, full))
    return [CostRow(name, setting, full, statistics.median(times[name]), times[name])
            for name, setting, full in entries]


@dataclass
class LabelCheck:
    robust: np.ndarray
    reference: np.ndarray
    agreement_ab: float


def label_check(scene: Scene, grid: Grid, rows: list[CostRow], threads: int,
                progress=None) -> LabelCheck:
    say = progress or (lambda text: None)
    refs = run_references(scene, grid, threads, say)
    robust = refs.robust
    for row in rows:
        if row.full_run:
            continue  # the same labels as the early-stopped run of the same setting
        say(f"labels: {row.name}")
        run = run_grid(scene, row.setting, grid, threads)
        same = (run.quarter_turns == refs.a.quarter_turns) & (run.status == Status.SETTLED)
        row.label_agreement = float(same[robust].mean())
    paper = next(r for r in rows if r.full_run)
    paper.label_agreement = next(r.label_agreement for r in rows
                                 if r.setting == paper.setting and not r.full_run)
    return LabelCheck(robust, refs.a.quarter_turns, refs.agreement)
