"""The benchmark behind ``coin bench`` (a measurement, not a test): per-trajectory cost of each
method's default setting and of the paper's setting, measured side by side on the same cells,
and each one's label agreement with the converged reference on the same grid.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass, replace

import numpy as np

from .accuracy import (
    Setting,
    label_error,
    run_grid,
    run_references,
    uncertain_fraction,
)
from .enums import Method
from .grid import Grid
from .integrators.batch import interruptible, new_control
from .labeller import Labeller
from .params import Scene

# Each method's default setting: for the fixed-step methods the paper's step (on the chart none
# of them reaches 1 % label error at any affordable step), for the adaptive ones the cheapest
# tolerance under 1 % label error with 95 % confidence on the chart (docs/accuracy.png).
METHOD_DEFAULTS = {method: Setting(method, 1e-6, 1e-6) for method in Method}
PAPER = "paper: SE h=1e-6, 2 s"
VERIFIED = "event, verified (default)"


@dataclass
class CostRow:
    name: str
    setting: Setting
    full_run: bool
    seconds_per_trajectory: float  # median over repeats, one thread
    repeats: list[float]
    label_agreement: float = float("nan")  # on the robust cells of the label grid
    uncertain: float = float("nan")  # verified setting: robust cells flagged uncertain


def time_cells(scene: Scene, setting: Setting, states: np.ndarray, full_run: bool) -> float:
    """Seconds per trajectory (per cell of a verified setting: all its rungs) for one pass over
    ``states`` on this thread."""
    run_scene = setting.apply(scene, stop_on_settle=not full_run, t_end=2.0)
    labeller = Labeller.of(run_scene)
    labeller.load(states[0])  # load the compiled kernel first
    control = new_control()

    def run() -> float:  # thread time of the thread that runs the kernels
        start = time.thread_time()
        labeller.label(states, control)
        return time.thread_time() - start

    return interruptible(run, control) / states.shape[0]


def side_by_side(scene: Scene, cost_grid: Grid, repeats: int = 3,
                 progress=None) -> list[CostRow]:
    """Cost of every default setting and of the paper's, interleaved round by round on the same
    cells so that machine noise hits them alike; the median of the rounds is reported."""
    say = progress or (lambda text: None)
    states = cost_grid.states()
    entries = [(s.label, s, False) for s in METHOD_DEFAULTS.values()]
    entries.append((VERIFIED, replace(METHOD_DEFAULTS[Method.EVENT], verify=True), False))
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
        row.label_agreement = 1.0 - label_error(run, refs.a.quarter_turns, robust)
        row.uncertain = uncertain_fraction(run, robust)
    paper = next(r for r in rows if r.full_run)
    paper.label_agreement = next(r.label_agreement for r in rows
                                 if r.setting == paper.setting and not r.full_run)
    return LabelCheck(robust, refs.a.quarter_turns, refs.agreement)
