"""One trajectory: run a scene, return its outcome as plain data (no printing, no files).

:func:`simulate` returns a :class:`Throw` (outcome, status, certainty, final state,
energies, and on request the samples at a display rate and every contact event);
:func:`classify` only the :class:`Outcome` of one initial condition, as Attractors.jl classifies
one initial condition. Both climb the ladder of settings (:mod:`coincli.integrators.ladder`)
until two successive rungs agree, unless the scene's integration says ``verify=False``; the
trajectory returned is the last rung's.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .enums import Certainty, Engine, Status
from .integrators import check_step, new_control
from .integrators.batch import NO_LABEL
from .integrators.common import (
    ANGLE_BOUND,
    EVENT_COLUMNS,
    FINITE_BOUND,
    LIFTOFF,
    ONSET,
    SAMPLE_COLUMNS,
)
from .integrators.ladder import scene_ladder
from .jit import NUMBA, PYTHON, is_built, kernels_cached
from .labeller import Labeller
from .models import MODELS, horizon_text, scene_horizon
from .params import (
    OVERRIDE_KEYS,
    STATE_NAMES,
    ParameterError,
    Scene,
    require_scene,
    state_array,
    validate,
)

# The columns of ``Throw.samples`` and ``Throw.events``, named once: every table,
# Dataset, CSV header and recording of a throw takes its names from here, its units and
# descriptions from QUANTITIES.
SAMPLE_NAMES = ("t", *STATE_NAMES)
EVENT_NAMES = ("t", "corner", "kind", *STATE_NAMES)
EVENT_KINDS = {ONSET: "onset", LIFTOFF: "lift-off"}  # the ``kind`` column's values
QUANTITIES = {  # name: (units, long name)
    "t": ("s", "time"),
    "x": ("m", "horizontal position of the centroid"),
    "y": ("m", "height of the centroid"),
    "phi": ("rad", "angle of the coin"),
    "vx": ("m/s", "horizontal velocity of the centroid"),
    "vy": ("m/s", "vertical velocity of the centroid"),
    "vphi": ("rad/s", "angular velocity"),
    "corner": ("1", "corner of the coin (0-3)"),
    "kind": ("1", "contact onset (+1) or lift-off (-1)"),
    "kinetic": ("J", "kinetic energy"),
    "gravitational": ("J", "gravitational energy m g y"),
    "elastic": ("J", "elastic energy stored in the foundation"),
    "energy": ("J", "total energy"),
}
assert len(SAMPLE_NAMES) == SAMPLE_COLUMNS and len(EVENT_NAMES) == EVENT_COLUMNS

MAX_EVENTS = 200_000
MAX_SAMPLES = 10_000_000  # states a trajectory keeps at most (560 MB)
CAPPED_SAMPLES = 1_000_000  # ... where the cap is infinite (56 MB; see _sample_rows)
# Engine.AUTO runs the kernel as Python (no numba to import, no machine code to load: ~0.7 s
# saved) when the run is adaptive and stops once settled; a typical throw takes under a hundred
# steps (about 5 ms in Python). One that needs more than PYTHON_STEPS is run again compiled.
PYTHON_STEPS = 3000
# the interval between kept states of a run that keeps none: only its first and last are
# kept, and it is a recorded run, which integrates the friction and the sliding work
WORK_ONLY = math.inf


class State(NamedTuple):
    """A state of the coin by name (SI units): ``run.final.phi``."""

    x: float
    y: float
    phi: float
    vx: float
    vy: float
    vphi: float


assert State._fields == STATE_NAMES


class Rung(NamedTuple):
    """One run of the ladder: its setting and what it gave."""

    setting: str  # "rtol = 1e-06"
    quarter_turns: int | None
    status: Status
    settle_time: float
    steps: int
    last_change: float  # s, when the coin passed into its final well (NaN: it never moved)


@dataclass
class Throw:
    """Outcome of one throw (:func:`coincli.simulate` gives it as a :class:`coincli.Trajectory`,
    with its views: a Dataset, a table, an animation, a viewer). ``quarter_turns`` is the
    final count (the well holding the coin once its energy fell below E_crit) when
    ``settled``, else round(2 phi / pi) at the end time; ``rounded_quarter_turns`` is always
    the paper's round(2 phi / pi) at the end. ``certainty`` says whether it converged on the
    ladder (``rungs``: every run made, coarse to fine; the throw's own numbers are the last
    one's)."""

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
    samples: np.ndarray | None = None  # columns: SAMPLE_NAMES
    events: np.ndarray | None = None  # columns: EVENT_NAMES
    notes: list[str] = field(default_factory=list)
    certainty: Certainty = Certainty.UNVERIFIED
    rungs: list[Rung] = field(default_factory=list)
    sample_dt: float | None = None  # s between samples (None: none kept)
    # J friction took from the coin over the throw (0 without friction), and J per unit
    # friction coefficient: the integral of max(0, N_i) |v_xi| over the corners in contact,
    # what a friction coefficient mu would take of it, about mu times it to first order (the
    # last rung's run; None: not integrated)
    friction_work: float | None = None
    sliding_work: float | None = None

    @property
    def settled(self) -> bool:
        return self.status == Status.SETTLED

    @property
    def final(self) -> State:
        """The final state by name (``final_state`` is the same as an array)."""
        return State(*map(float, self.final_state))

    def __repr__(self) -> str:  # one line in a notebook; everything: summary()
        n = "no count" if self.quarter_turns is None else \
            f"n = {self.quarter_turns} ({self.pose})"
        when = (f" at {self.settle_time:.4g} s" if self.settled else
                f" at t = {self.t_final:.4g} s")
        rung = f" at {self.rungs[-1].setting}" if self.rungs and \
            self.certainty == Certainty.CERTAIN else ""
        kept = []
        if self.samples is not None and len(self.samples):
            kept.append(f"{len(self.samples):,} samples")
        if self.events is not None and len(self.events):
            kept.append(f"{len(self.events):,} events")
        return (f"{type(self).__name__}({n}, {self.status}{when}, {self.certainty}{rung}, "
                f"{self.steps:,} step{'s' * (self.steps != 1)}"
                f"{''.join(', ' + k for k in kept)})")

    @property
    def pose(self) -> str:
        return pose_of(self.quarter_turns)

    def to_dict(self) -> dict:
        """The same as :meth:`summary` (as every result of the API names it)."""
        return self.summary()

    def summary(self) -> dict:
        """Everything a user or a script needs, as plain JSON-able values."""
        integ = self.scene.integration
        return {
            "quarter_turns": self.quarter_turns,
            "pose": self.pose,
            "status": self.status.label,
            "settled": self.settled,
            "certainty": self.certainty.label,
            "certain": self.certainty == Certainty.CERTAIN,
            "rungs": [{"setting": r.setting, "quarter_turns": r.quarter_turns,
                       "status": r.status.label, "steps": r.steps} for r in self.rungs],
            "settle_time": None if math.isnan(self.settle_time) else self.settle_time,
            "rounded_quarter_turns": self.rounded_quarter_turns,
            "t_final": self.t_final,
            "final_state": dict(zip(STATE_NAMES, map(float, self.final_state), strict=True)),
            "energy_initial": self.energy_initial,
            "energy_final": self.energy_final,
            "energy_dissipated": self.energy_initial - self.energy_final,
            "mu": self.scene.foundation.mu,
            "slip_velocity": self.scene.foundation.slip_velocity,
            "friction_work": self.friction_work,
            "sliding_work": self.sliding_work,
            "e_crit": self.e_crit,
            "method": integ.method.label,
            # the rungs' settings, each with the method it ran (a friction scene's ladder
            # runs the method's switching pair: event as event_rodas), as a store records them
            "verification": scene_ladder(self.scene).to_dict(),
            "dt": integ.dt,
            "rtol": integ.rtol,
            "t_end": integ.t_end,
            "horizon": scene_horizon(self.scene),
            "horizon_rule": horizon_text(self.scene),
            "certainty_reason": self.certainty.message,
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
    certainty: Certainty  # CERTAIN: converged on the ladder of settings

    @property
    def pose(self) -> str:
        return pose_of(self.quarter_turns)


def pose_of(quarter_turns: int | None) -> str:
    """Odd n: the coin stands on its rim; even n: it lies on a face."""
    if quarter_turns is None:
        return "unknown"
    return "standing" if quarter_turns % 2 else "lying"


def with_keywords(scene: Scene, overrides: dict, function: str) -> Scene:
    """``scene`` with the keyword ``overrides`` of a call of ``function``; an unknown keyword
    is a TypeError, as Python says it of any function."""
    require_scene(scene)
    if not overrides:
        return scene
    unknown = sorted(set(overrides) - set(OVERRIDE_KEYS))
    if unknown:
        raise TypeError(f"{function}() got an unexpected keyword argument {unknown[0]!r}; a "
                        f"scene's values are: {', '.join(OVERRIDE_KEYS)}")
    return scene.with_overrides(**overrides)


def simulate(scene: Scene, *, sample_dt: float | None = None, record_events: bool = False,
             force: bool = False, engine: Engine = Engine.AUTO, control=None,
             before_compile=None, **overrides) -> Throw:
    """One throw, as :func:`coincli.simulate` describes (which gives it with its views).
    ``before_compile`` (no arguments) is called before the compiled kernels of the scene's
    model are first compiled on this machine (not when they only load), for a front end to
    say so (it may compile them itself: :func:`coincli.api.throws.compile_kernels`). A run
    that keeps no samples still integrates the friction and sliding work: it records its
    first and last state only (WORK_ONLY)."""
    scene = with_keywords(scene, overrides, "simulate")
    validate(scene)
    method = check_step(scene, force=force)
    integ = scene.integration
    horizon = scene_horizon(scene)
    _check_sample_dt(sample_dt, horizon)
    try:
        engine = Engine.parse(engine)
    except ValueError:
        raise ParameterError(f"engine must be one of {', '.join(e.label for e in Engine)}, "
                             f"got {engine!r}") from None
    labeller = Labeller.of(scene, sample_dt=float(sample_dt) if sample_dt else WORK_ONLY)
    before_compile = _once(before_compile)
    ladder = labeller.ladder
    state0 = state_array(scene)
    if sample_dt:
        samples = np.empty((_sample_rows(horizon, sample_dt), SAMPLE_COLUMNS))
    else:  # the first and the last state: a recorded run, which integrates the work
        samples = np.empty((2, SAMPLE_COLUMNS))
    events = np.empty((MAX_EVENTS if record_events else 0, EVENT_COLUMNS))
    final = np.empty(6)
    control = new_control() if control is None else control
    if engine == Engine.AUTO:
        short = (method.adaptive and integ.stop_on_settle
                 and not is_built(MODELS[labeller.model], NUMBA))
        engine = Engine.PYTHON if short else Engine.NUMBA
    rules = labeller.python  # the ladder's rule, run by CPython on a few values
    rungs: list[Rung] = []
    certainty = Certainty.UNVERIFIED if not ladder.verified else Certainty.UNCERTAIN
    wall = 0.0
    previous = None  # the last rung's RunResult and label
    decided = True  # both runs of the last comparison settled (else: undecided, not chaotic)
    for k in range(len(ladder)):
        settings = labeller.rung_settings(k)
        result, seconds, engine = _run(labeller, settings, state0, samples, events, final,
                                       control, engine, before_compile)
        wall += seconds
        label = rules.outcome_label(result.status, result.n_well, final[2])
        rungs.append(Rung(ladder.rung_text(k), None if label == NO_LABEL else int(label),
                          Status(result.status), float(result.settle_time), int(result.steps),
                          float(result.last_change)))
        if rules.stops_ladder(result):
            decided = False
            break
        if previous is not None:
            decided = previous[0].status == Status.SETTLED and result.status == Status.SETTLED
        if previous is not None and rules.rungs_agree(previous[1], previous[0], label, result,
                                                ladder.change_tolerance,
                                                ladder.settle_tolerance):
            certainty = Certainty.CERTAIN
            break
        previous = (result, label)
    if certainty == Certainty.UNCERTAIN and not decided:
        certainty = Certainty.UNDECIDED
    return _trajectory(scene, labeller, state0, final, result, samples, events, sample_dt,
                       record_events, wall, certainty, rungs, settings.max_steps)


def _once(hook):
    """``hook`` called once at most (None: None)."""
    if hook is None:
        return None
    called = []

    def once():
        if not called:
            called.append(True)
            hook()

    return once


def _sample_rows(horizon: float, sample_dt: float) -> int:
    """Rows of the buffer of kept states: every state to the horizon (t_end, or the throw's
    cap); CAPPED_SAMPLES for an infinite cap (a start no run can integrate, or no damping:
    the run keeps its first states, and its notes say so)."""
    span = horizon / sample_dt
    return (int(span) if math.isfinite(span) else CAPPED_SAMPLES) + 3


def _check_sample_dt(sample_dt, horizon: float) -> None:
    """ParameterError (one line) unless ``sample_dt`` is None, 0 or a usable interval over
    ``horizon`` (t_end, or the throw's cap; not checked where that is infinite)."""
    if sample_dt is None or (isinstance(sample_dt, numbers.Real) and sample_dt == 0):
        return  # keep no states
    if isinstance(sample_dt, bool) or not isinstance(sample_dt, numbers.Real) or \
            not math.isfinite(sample_dt) or sample_dt < 0:
        raise ParameterError(f"sample_dt must be a number of seconds > 0 (0 or None: keep "
                             f"none), got {sample_dt!r}")
    if math.isfinite(horizon) and horizon / sample_dt > MAX_SAMPLES:
        raise ParameterError(f"sample_dt = {sample_dt:g} s would keep {horizon / sample_dt:.3g} "
                             f"states over {horizon:g} s, at most {MAX_SAMPLES:,}: take "
                             f"sample_dt >= {horizon / MAX_SAMPLES:.2g} s")


def _run(labeller: Labeller, settings, state0, samples, events, final, control,
         engine: Engine, before_compile=None):
    """One kernel run: (result, wall seconds, the engine for the next rung). A Python run that
    outgrows PYTHON_STEPS is run again compiled, from the start, and so is every rung after."""
    if engine == Engine.PYTHON:
        start = time.perf_counter()
        capped = settings._replace(max_steps=min(settings.max_steps, PYTHON_STEPS))
        result = labeller.with_backend(PYTHON).run(capped, state0, samples, events, final,
                                                   control)
        if not (result.status == Status.BUDGET and capped.max_steps < settings.max_steps):
            return result, time.perf_counter() - start, engine
    if before_compile is not None and not kernels_cached(labeller.model):
        before_compile()
    labeller.load(state0, trajectory=True)  # before the clock
    start = time.perf_counter()
    result = labeller.run(settings, state0, samples, events, final, control)
    return result, time.perf_counter() - start, Engine.NUMBA


def _trajectory(scene, labeller, state0, final, result, samples, events, sample_dt, record_events,
                wall, certainty, rungs, budget) -> Throw:
    integ = scene.integration
    status = Status(result.status)
    t = result.t
    finite = status in (Status.SETTLED, Status.UNSETTLED)
    rules, p = labeller.python, labeller.params
    rounded = int(rules.rounded_quarter_turns(final[2])) if finite else None
    quarter_turns = rungs[-1].quarter_turns
    settle_time = result.settle_time
    notes = []
    if status == Status.SETTLED and not integ.stop_on_settle and rounded != quarter_turns:
        notes.append(f"the coin is still rocking at t = {t:g} s: round(2 phi / pi) = {rounded}, "
                     f"but its energy fell below E_crit at t = {settle_time:.4g} s inside the "
                     f"well n = {quarter_turns}, which is the true outcome")
    if status == Status.UNSETTLED:
        end = ("" if scene.fixed_horizon else
               f" (the cap of this throw: {horizon_text(scene)})")
        notes.append(f"the energy is still above E_crit at t = {t:g} s{end}: n = {rounded} is "
                     "round(2 phi / pi) at the end and may still change; raise --t-end")
    if status == Status.NONFINITE and not rules.is_finite_state(state0):
        notes.append(f"the initial state is beyond what can be integrated (a value of "
                     f"{FINITE_BOUND:g} or more, or an angle of {ANGLE_BOUND:g} rad or more, "
                     "far outside any throw): no outcome; give physical initial values")
    elif status == Status.NONFINITE:
        notes.append(f"the run went non-finite near t = {t:.4g} s: no outcome (try a smaller "
                     "step or tolerance)")
    if status == Status.BUDGET:
        # The budget counts rejected steps and flight iterations too, so not result.steps.
        notes.append(f"the run used up its budget of {budget:,} steps at "
                     f"t = {t:.4g} s: "
                     "no outcome (raise --max-steps, or check the throw: a spin or a damping "
                     "this large needs steps too small to finish)")
    if sample_dt and result.n_samples >= samples.shape[0]:
        notes.append(f"the recording keeps the first {samples.shape[0]:,} states, to "
                     f"t = {samples[-1, 0]:.4g} s: give --t-end (a fixed horizon) or a longer "
                     "interval between states to keep them all")
    if certainty == Certainty.UNCERTAIN and status == Status.SETTLED:
        tried = "; ".join(f"{r.setting}: n = {r.quarter_turns} {r.status.label}" for r in rungs)
        notes.append(f"the label did not converge: no two successive rungs agreed ({tried}): "
                     "chaotic at this precision")
    if certainty == Certainty.UNDECIDED:
        tried = "; ".join(f"{r.setting}: n = {r.quarter_turns} {r.status.label}" for r in rungs)
        notes.append(f"the label is undecided: a rung did not settle ({tried})")
    with np.errstate(over="ignore", invalid="ignore"):  # a state past FINITE_BOUND: inf
        e0 = sum(rules.energies(p, state0))
    e1 = sum(rules.energies(p, final)) if status != Status.NONFINITE else math.nan
    return Throw(
        scene=scene, status=status, t_final=float(t), final_state=final.copy(),
        steps=int(sum(r.steps for r in rungs)), settle_time=float(settle_time),
        quarter_turns=quarter_turns, rounded_quarter_turns=rounded, energy_initial=float(e0),
        energy_final=float(e1), e_crit=scene.e_crit, wall_time=wall,
        samples=samples[:result.n_samples].copy() if sample_dt else None,
        events=events[:result.n_events].copy() if record_events else None, notes=notes,
        certainty=certainty, rungs=rungs, sample_dt=float(sample_dt) if sample_dt else None,
        friction_work=float(result.friction_work), sliding_work=float(result.sliding_work))


def classify(scene: Scene, *, force: bool = False, **overrides) -> Outcome:
    """The outcome of the scene's initial condition (nothing recorded on the way);
    ``overrides`` as :func:`simulate` takes them."""
    run = simulate(with_keywords(scene, overrides, "classify"), force=force)
    return Outcome(run.quarter_turns, run.status, run.settle_time, run.certainty)
