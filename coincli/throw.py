"""One trajectory: run a scene, return its outcome as plain data (no printing, no files).

:func:`simulate` returns a :class:`Trajectory` (outcome, status, final state, energies, and on
request the samples at a display rate and every contact event); :func:`classify` only the
:class:`Outcome` of one initial condition, as Attractors.jl classifies one initial condition.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .enums import Engine, Status
from .integrators import check_step, integrate, new_control, warm_up
from .integrators.common import EVENT_COLUMNS, SAMPLE_COLUMNS
from .jit import compiled, is_active, python
from .model import energies, rounded_quarter_turns
from .params import STATE_NAMES, Scene, model_params, run_settings, state_array, validate

MAX_EVENTS = 200_000
# Engine.AUTO runs the kernel as Python (no numba to import, no machine code to load: ~0.7 s
# saved) when the run is adaptive and stops once settled; a typical throw takes under a hundred
# steps (about 5 ms in Python). One that needs more than PYTHON_STEPS is run again compiled.
PYTHON_STEPS = 3000


@dataclass
class Trajectory:
    """Outcome of one run. ``quarter_turns`` is the certified count (the well holding the coin
    once its energy fell below E_crit) when ``settled``, else round(2 phi / pi) at the end time;
    ``rounded_quarter_turns`` is always the paper's round(2 phi / pi) at the end."""

    scene: Scene
    status: Status
    t_final: float
    final_state: np.ndarray
    steps: int
    settle_time: float
    quarter_turns: int | None
    rounded_quarter_turns: int | None
    energy_initial: float
    energy_final: float
    e_crit: float
    wall_time: float
    samples: np.ndarray | None = None  # rows: t, x, y, phi, vx, vy, vphi
    events: np.ndarray | None = None  # rows: t, corner, kind (+1 onset, -1 lift-off), state
    notes: list[str] = field(default_factory=list)

    @property
    def settled(self) -> bool:
        return self.status == Status.SETTLED

    @property
    def pose(self) -> str:
        return pose_of(self.quarter_turns)

    def summary(self) -> dict:
        """Everything a user or a script needs, as plain JSON-able values."""
        integ = self.scene.integration
        return {
            "quarter_turns": self.quarter_turns,
            "pose": self.pose,
            "status": self.status.label,
            "settled": self.settled,
            "settle_time": None if math.isnan(self.settle_time) else self.settle_time,
            "rounded_quarter_turns": self.rounded_quarter_turns,
            "t_final": self.t_final,
            "final_state": dict(zip(STATE_NAMES, map(float, self.final_state), strict=True)),
            "energy_initial": self.energy_initial,
            "energy_final": self.energy_final,
            "energy_dissipated": self.energy_initial - self.energy_final,
            "e_crit": self.e_crit,
            "method": integ.method.label,
            "dt": integ.dt,
            "rtol": integ.rtol,
            "t_end": integ.t_end,
            "stop_on_settle": integ.stop_on_settle,
            "steps": self.steps,
            "wall_time": self.wall_time,
            "notes": self.notes,
        }


class Outcome(NamedTuple):
    """The outcome of one initial condition."""

    quarter_turns: int | None  # final n if settled; round(2 phi / pi) at t_end if unsettled
    status: Status
    settle_time: float  # s, NaN if it never settled

    @property
    def pose(self) -> str:
        return pose_of(self.quarter_turns)


def pose_of(quarter_turns: int | None) -> str:
    """Odd n: the coin stands on its rim; even n: it lies on a face."""
    if quarter_turns is None:
        return "unknown"
    return "standing" if quarter_turns % 2 else "lying"


def simulate(scene: Scene, *, sample_dt: float | None = None, record_events: bool = False,
             force: bool = False, engine: Engine = Engine.AUTO, control=None) -> Trajectory:
    """Integrate one trajectory. With ``sample_dt`` the state is kept every ``sample_dt`` seconds
    of simulated time (exact times for the adaptive methods); with ``record_events`` every contact
    onset and lift-off is kept with its state. ``force`` allows a fixed step beyond the method's
    stable step. ``engine`` chooses what runs the kernel (the result is the same to the bit);
    ``control`` (from :func:`coincli.integrators.new_control`) lets another thread stop it."""
    validate(scene)
    method = check_step(scene, force=force)
    integ = scene.integration
    p = model_params(scene)
    settings = run_settings(integ, float(sample_dt or 0.0))
    state0 = state_array(scene)
    if sample_dt:
        samples = np.empty((int(integ.t_end / sample_dt) + 3, SAMPLE_COLUMNS))
    else:
        samples = np.empty((0, SAMPLE_COLUMNS))
    events = np.empty((MAX_EVENTS if record_events else 0, EVENT_COLUMNS))
    final = np.empty(6)
    control = new_control() if control is None else control
    if engine == Engine.AUTO:
        short = method.adaptive and integ.stop_on_settle and not is_active()
        engine = Engine.PYTHON if short else Engine.NUMBA
    result = None
    if engine == Engine.PYTHON:
        start = time.perf_counter()
        capped = settings._replace(max_steps=min(settings.max_steps, PYTHON_STEPS))
        result = python(integrate)(p, capped, state0, samples, events, final, control)
        wall = time.perf_counter() - start
        if result.status == Status.BUDGET and capped.max_steps < settings.max_steps:
            result = None  # a long run: compiled code from the start (the same floats)
    if result is None:
        warm_up(p, run_settings(integ), state0)  # before the clock starts
        start = time.perf_counter()
        result = compiled(integrate)(p, settings, state0, samples, events, final, control)
        wall = time.perf_counter() - start
    status = Status(result.status)
    t = result.t
    finite = status != Status.NONFINITE
    rounded = int(rounded_quarter_turns(final[2])) if finite else None
    if status == Status.SETTLED:
        quarter_turns = int(result.n_well)
    else:
        quarter_turns = rounded if finite else None
    settle_time = result.settle_time
    notes = []
    if status == Status.SETTLED and not integ.stop_on_settle and rounded != quarter_turns:
        notes.append(f"the coin is still rocking at t = {t:g} s: round(2 phi / pi) = {rounded}, "
                     f"but its energy fell below E_crit at t = {settle_time:.4g} s inside the "
                     f"well n = {quarter_turns}, which is the true outcome")
    if status == Status.UNSETTLED:
        notes.append(f"the energy is still above E_crit at t = {t:g} s: n = {rounded} is "
                     "round(2 phi / pi) at the end and may still change; raise --t-end")
    if not finite:
        notes.append(f"the run went non-finite near t = {t:.4g} s: no outcome (try a smaller "
                     "step or tolerance)")
    e0 = sum(energies(p, state0))
    e1 = sum(energies(p, final)) if finite else math.nan
    return Trajectory(
        scene=scene, status=status, t_final=float(t), final_state=final.copy(),
        steps=int(result.steps), settle_time=float(settle_time), quarter_turns=quarter_turns,
        rounded_quarter_turns=rounded, energy_initial=float(e0), energy_final=float(e1),
        e_crit=scene.e_crit, wall_time=wall,
        samples=samples[:result.n_samples].copy() if sample_dt else None,
        events=events[:result.n_events].copy() if record_events else None, notes=notes)


def classify(scene: Scene, *, force: bool = False) -> Outcome:
    """The outcome of the scene's initial condition (nothing recorded on the way)."""
    run = simulate(scene, force=force)
    return Outcome(run.quarter_turns, run.status, run.settle_time)
