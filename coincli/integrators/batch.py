"""One entry point for every method (:func:`integrate`), the verification ladder over a batch
of initial states (:func:`run_ladder`), and what their callers hand them and get back (the
shapes and dtypes every caller uses). The labeller (:mod:`coincli.labeller`) is the one door to
them: it runs them from the kernel set of a scene's model and backend.

Methods are identified by their :class:`coincli.enums.Method` value so that one compiled kernel
serves them all; their names, orders and properties live in :mod:`.registry`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..enums import Certainty, Status
from ..jit import kernel
from ..models.interface import FRICTION, rounded_quarter_turns
from ..params import RunSettings
from .adaptive import integrate_adaptive
from .common import EVENT_COLUMNS, NO_WELL, SAMPLE_COLUMNS
from .fixed import integrate_fixed
from .pairs import (
    integrate_adaptive_dop853,
    integrate_adaptive_dop853_rodas,
    integrate_adaptive_rodas,
)
from .registry import (
    DOP853_PAIR,
    DOP853_RODAS_PAIR,
    DOPRI5_PAIR,
    DOPRI5_RODAS_PAIR,
    DRIVER_OF,
)

NO_LABEL = NO_WELL  # quarter_turns of a cell without a count (int16 fill of the stores)


@kernel(inline=True)  # in the batch runners, a run costs no call and no reference counting
def integrate(p, settings, state, samples, events, final, control):
    """Run one trajectory from ``state`` with ``settings`` (a RunSettings), on the driver the
    registry names for its method; returns a RunResult and writes the final state into
    ``final``. Setting ``control[0]`` (from another thread)
    stops it with status INTERRUPTED."""
    driver = DRIVER_OF[settings.method]
    if FRICTION:
        # a model with friction runs its adaptive methods on their switching pairs (the
        # explicit pair where friction is not stiff, which is what the pair alone would do,
        # Rodas5P where it is), and only those are compiled for it
        if driver == DOPRI5_PAIR or driver == DOPRI5_RODAS_PAIR:
            return integrate_adaptive_rodas(p, settings, state, samples, events, final, control)
        if driver == DOP853_PAIR or driver == DOP853_RODAS_PAIR:
            return integrate_adaptive_dop853_rodas(p, settings, state, samples, events, final,
                                                   control)
        return integrate_fixed(p, settings, state, samples, events, final, control)
    if driver == DOPRI5_RODAS_PAIR:  # without friction the switching pair is its explicit pair
        driver = DOPRI5_PAIR
    elif driver == DOP853_RODAS_PAIR:
        driver = DOP853_PAIR
    if driver == DOPRI5_PAIR:
        return integrate_adaptive(p, settings, state, samples, events, final, control)
    if driver == DOP853_PAIR:
        return integrate_adaptive_dop853(p, settings, state, samples, events, final, control)
    return integrate_fixed(p, settings, state, samples, events, final, control)


@kernel
def outcome_label(status, n_well, final_phi):
    """The count of quarter turns a run decides: the well that holds the coin once it has
    settled, the paper's round(2 phi / pi) at t_end if it has not (flagged unsettled by the
    status), nothing for a run that went non-finite, used up its budget or was interrupted."""
    if status == Status.SETTLED:
        return n_well
    if status == Status.UNSETTLED:
        return rounded_quarter_turns(final_phi)
    return NO_LABEL


@kernel(inline=True)
def rung_settings(settings, methods, rtols, dts, budgets, k):
    """The settings of rung k of a ladder: the base settings with that rung's method, rtol, dt
    and step budget."""
    return RunSettings(methods[k], dts[k], rtols[k], settings.t_end,
                       settings.stop_on_settle, budgets[k], settings.sample_dt)


@kernel
def rungs_agree(label_a, run_a, label_b, run_b, change_tolerance, settle_tolerance):
    """The ladder's rule: two runs (RunResults, with their labels) agree when both settled with
    the same count of quarter turns, passed into their final well at the same moment, within
    ``change_tolerance`` seconds (their last change of well; NaN, never changed, matches NaN),
    and settled at the same moment, within ``settle_tolerance`` seconds. The label is decided
    when the energy falls below E_crit, not when the coin enters its final well: two runs that
    entered it together can still bounce apart while they have the energy to leave it, and the
    true trajectory may then leave where neither did. Afterwards the coin only rocks inside its
    well, chaotically, so their final states need not agree. Labels alone are weak evidence
    where outcomes are nearly random among a few wells: two runs that took different paths
    often end in the same well by chance, and pass into it at clearly different times."""
    if not (run_a.status == Status.SETTLED and run_b.status == Status.SETTLED
            and label_a == label_b):
        return False
    if abs(run_a.settle_time - run_b.settle_time) > settle_tolerance:
        return False
    change_a = run_a.last_change
    change_b = run_b.last_change
    if change_a != change_a or change_b != change_b:  # NaN: no change of well at all
        return change_a != change_a and change_b != change_b
    return abs(change_a - change_b) <= change_tolerance


@kernel
def stops_ladder(result):
    """Whether a rung's run ends its ladder: it used up its budget (a tighter rung would run
    out too), was told to stop, or could not start (non-finite at t = 0 without a step: an
    initial state no setting can integrate)."""
    return (result.status == Status.BUDGET or result.status == Status.INTERRUPTED
            or (result.status == Status.NONFINITE and result.steps == 0 and result.t == 0.0))


@kernel
def run_ladder(p, settings, methods, rtols, dts, budgets, change_tolerance, settle_tolerance,
               states, no_samples, no_events, final, quarter_turns, status, settle_time, steps,
               certainty, rung, control):
    """Verified labels: each row of ``states`` is run at rung 0, 1, ... of the ladder (methods,
    rtols, dts, budgets: the rungs' settings, coarse to fine) until two successive rungs agree
    (:func:`rungs_agree`). Writes the finest run's outcome, the total steps, the certainty
    (CERTAIN; if no two rungs agreed, UNCERTAIN when the last two compared had both settled,
    UNDECIDED when one had not; UNVERIFIED for a one-rung ladder) and the index of the last
    rung run. Releases the GIL; ``control[0]`` set stops it."""
    n_rungs = rtols.shape[0]
    for row in range(states.shape[0]):
        result = integrate(p, rung_settings(settings, methods, rtols, dts, budgets, 0),
                           states[row], no_samples, no_events, final, control)
        label = outcome_label(result.status, result.n_well, final[2])
        total = result.steps
        verdict = Certainty.UNVERIFIED if n_rungs == 1 else Certainty.UNCERTAIN
        decided = result.status == Status.SETTLED  # both runs of the last comparison settled
        last = 0
        for k in range(1, n_rungs):
            if stops_ladder(result):
                break
            finer = integrate(p, rung_settings(settings, methods, rtols, dts, budgets, k),
                              states[row], no_samples, no_events, final, control)
            finer_label = outcome_label(finer.status, finer.n_well, final[2])
            total += finer.steps
            last = k
            decided = result.status == Status.SETTLED and finer.status == Status.SETTLED
            agree = rungs_agree(label, result, finer_label, finer, change_tolerance,
                                settle_tolerance)
            result = finer
            label = finer_label
            if agree:
                verdict = Certainty.CERTAIN
                break
        if verdict == Certainty.UNCERTAIN and not decided:
            verdict = Certainty.UNDECIDED
        quarter_turns[row] = label
        status[row] = result.status
        settle_time[row] = result.settle_time
        steps[row] = total
        certainty[row] = verdict
        rung[row] = last


class VerifiedLabels(NamedTuple):
    """Per-trajectory verified outcomes: Labels plus how sure each is."""

    quarter_turns: np.ndarray  # int16, NO_LABEL where there is none
    status: np.ndarray  # uint8 Status values
    settle_time: np.ndarray  # float32 s
    steps: np.ndarray  # int64, summed over the rungs run
    certainty: np.ndarray  # uint8 Certainty values
    rung: np.ndarray  # int8, index of the last rung run


def new_control():
    """A control flag for kernels: set element 0 to 1 to stop them (from any thread)."""
    return np.zeros(1, np.int64)


def interruptible(run, control):
    """``run()`` (compiled kernels, which release the GIL and poll ``control``) in a worker
    thread, so that this thread still takes Ctrl-C: it then sets the control flag, the kernels
    return within microseconds and KeyboardInterrupt goes on up. Returns what ``run`` returns,
    or raises what it raised."""
    import threading

    box = []

    def target():
        try:
            box.append((True, run()))
        except BaseException as exc:  # handed to the caller's thread
            box.append((False, exc))

    worker = threading.Thread(target=target, daemon=True, name="coin-kernel")
    worker.start()
    try:
        while worker.is_alive():
            worker.join(0.1)
    except KeyboardInterrupt:
        control[0] = 1
        worker.join()
        raise
    ok, value = box[0]
    if not ok:
        raise value
    return value


def unrecorded():
    """(no_samples, no_events, final): what a run that records nothing on the way is given, the
    arrays typed as the batch kernels pass them on. Made here, once per batch, rather than in
    the kernels, once per run."""
    return np.empty((0, SAMPLE_COLUMNS)), np.empty((0, EVENT_COLUMNS)), np.empty(6)


__all__ = ["NO_LABEL", "VerifiedLabels", "integrate", "interruptible", "new_control",
           "outcome_label", "run_ladder", "rungs_agree", "stops_ladder", "unrecorded"]
