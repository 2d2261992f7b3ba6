"""One trajectory: run a scene, return its outcome as plain data (no printing, no files)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .integrators import SETTLED, STATUS_NAMES, check_step, integrate
from .integrators.fixed import EVENT_COLUMNS, SAMPLE_COLUMNS
from .integrators.kernels import warm_up
from .model import energies, rounded_quarter_turns
from .params import STATE_NAMES, Scene, param_array, state_array, validate

MAX_EVENTS = 200_000


@dataclass
class Trajectory:
    """Outcome of one run. ``quarter_turns`` is the certified count (the well holding the coin
    once its energy fell below E_crit) when ``settled``, else round(2 phi / pi) at the end time;
    ``rounded_quarter_turns`` is always the paper's round(2 phi / pi) at the end."""

    scene: Scene
    status: str
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
        return self.status == STATUS_NAMES[SETTLED]

    @property
    def pose(self) -> str:
        if self.quarter_turns is None:
            return "unknown"
        return "standing" if self.quarter_turns % 2 else "lying"

    def summary(self) -> dict:
        """Everything a user or a script needs, as plain JSON-able values."""
        integ = self.scene.integration
        return {
            "quarter_turns": self.quarter_turns,
            "pose": self.pose,
            "status": self.status,
            "settled": self.settled,
            "settle_time": None if math.isnan(self.settle_time) else self.settle_time,
            "rounded_quarter_turns": self.rounded_quarter_turns,
            "t_final": self.t_final,
            "final_state": dict(zip(STATE_NAMES, map(float, self.final_state), strict=True)),
            "energy_initial": self.energy_initial,
            "energy_final": self.energy_final,
            "energy_dissipated": self.energy_initial - self.energy_final,
            "e_crit": self.e_crit,
            "method": integ.method,
            "dt": integ.dt,
            "rtol": integ.rtol,
            "t_end": integ.t_end,
            "stop_on_settle": integ.stop_on_settle,
            "steps": self.steps,
            "wall_time": self.wall_time,
            "notes": self.notes,
        }


def simulate(scene: Scene, sample_dt: float | None = None, record_events: bool = False,
             force: bool = False) -> Trajectory:
    """Integrate one trajectory. With ``sample_dt`` the state is kept every ``sample_dt`` seconds
    of simulated time (exact times for the adaptive methods); with ``record_events`` every contact
    onset and lift-off is kept with its state."""
    validate(scene)
    method = check_step(scene, force=force)
    integ = scene.integration
    p = param_array(scene)
    state0 = state_array(scene)
    if sample_dt:
        samples = np.empty((int(integ.t_end / sample_dt) + 3, SAMPLE_COLUMNS))
    else:
        samples = np.empty((0, SAMPLE_COLUMNS))
    events = np.empty((MAX_EVENTS if record_events else 0, EVENT_COLUMNS))
    final = np.empty(6)
    warm_up(method.kernel_id, p, state0, integ.dt, integ.rtol)  # before the clock starts
    start = time.perf_counter()
    t, steps, status, settle_time, n_well, n_samples, n_events = integrate(
        method.kernel_id, p, state0, integ.dt, integ.rtol, integ.t_end, integ.stop_on_settle,
        float(sample_dt or 0.0), samples, events, final)
    wall = time.perf_counter() - start
    status_name = STATUS_NAMES[status]
    finite = status_name != "non-finite"
    rounded = int(rounded_quarter_turns(final[2])) if finite else None
    if status == SETTLED:
        quarter_turns = int(n_well)
    else:
        quarter_turns = rounded if finite else None
    notes = []
    if status == SETTLED and not integ.stop_on_settle and rounded != quarter_turns:
        notes.append(f"the coin is still rocking at t = {t:g} s: round(2 phi / pi) = {rounded}, "
                     f"but its energy fell below E_crit at t = {settle_time:.4g} s inside the "
                     f"well n = {quarter_turns}, which is the true outcome")
    if status_name == "unsettled":
        notes.append(f"the energy is still above E_crit at t = {t:g} s: n = {rounded} is "
                     "round(2 phi / pi) at the end and may still change; raise --t-end")
    if not finite:
        notes.append(f"the run went non-finite near t = {t:.4g} s: no outcome (try a smaller "
                     "step or tolerance)")
    e0 = sum(energies(p, state0))
    e1 = sum(energies(p, final)) if finite else math.nan
    return Trajectory(
        scene=scene, status=status_name, t_final=float(t), final_state=final.copy(),
        steps=int(steps), settle_time=float(settle_time), quarter_turns=quarter_turns,
        rounded_quarter_turns=rounded, energy_initial=float(e0), energy_final=float(e1),
        e_crit=scene.e_crit, wall_time=wall,
        samples=samples[:n_samples].copy() if sample_dt else None,
        events=events[:n_events].copy() if record_events else None, notes=notes)
