"""One entry point for every method (:func:`integrate`) and the batch runner the sweeps use.

Methods are identified by small integers so that a single compiled kernel serves them all; the
names, orders and properties live in :mod:`coincli.integrators.registry`.
"""

from __future__ import annotations

import numpy as np

from ..model import jit, rounded_quarter_turns
from .adaptive import integrate_adaptive
from .fixed import NONFINITE, RK4, SETTLED, SYMPLECTIC_EULER, VERLET, integrate_fixed

DOPRI5, EVENT = 3, 4
FIXED_STEP_IDS = (SYMPLECTIC_EULER, VERLET, RK4)
NOT_COMPUTED = np.int16(-32768)  # quarter_turns of a cell that has no finite outcome


@jit
def integrate(method, p, state, dt, rtol, t_end, stop_on_settle, sample_dt, samples, events,
              final):
    """Run one trajectory with method id ``method``.
    Returns (t, steps, status, settle_time, n_well, n_samples, n_events)."""
    if method == DOPRI5 or method == EVENT:
        return integrate_adaptive(p, state, rtol, dt, t_end, stop_on_settle, method == EVENT,
                                  sample_dt, samples, events, final)
    return integrate_fixed(method, p, state, dt, t_end, stop_on_settle, sample_dt, samples,
                           events, final)


@jit
def outcome_label(status, n_well, final_phi):
    """The count of quarter turns a run decides: the well that holds the coin once it has
    settled, the paper's round(2 phi / pi) at the end time otherwise (flagged unsettled by the
    status), nothing for a non-finite run."""
    if status == NONFINITE:
        return NOT_COMPUTED
    if status == SETTLED:
        return n_well
    return rounded_quarter_turns(final_phi)


@jit
def run_batch(method, p, states, dt, rtol, t_end, stop_on_settle, quarter_turns, status,
              settle_time, steps):
    """Integrate every row of ``states`` (N x 6) and write the outcome of each into the output
    arrays (quarter_turns int16, status uint8, settle_time float32, steps int64). Releases the
    GIL, so threads run batches on all cores."""
    no_samples = np.empty((0, 7))
    no_events = np.empty((0, 9))
    final = np.empty(6)
    for row in range(states.shape[0]):
        _, n_steps, run_status, t_settle, n_well, _, _ = integrate(
            method, p, states[row], dt, rtol, t_end, stop_on_settle, 0.0, no_samples,
            no_events, final)
        quarter_turns[row] = outcome_label(run_status, n_well, final[2])
        status[row] = run_status
        settle_time[row] = t_settle
        steps[row] = n_steps


# -- plain-Python conveniences over the kernels (the shapes and dtypes every caller uses) --------
def label_states(method, p, states, dt, rtol, t_end, stop_on_settle):
    """Run every row of ``states``; return (quarter_turns, status, settle_time, steps)."""
    n = states.shape[0]
    outs = (np.empty(n, np.int16), np.empty(n, np.uint8), np.empty(n, np.float32),
            np.empty(n, np.int64))
    run_batch(method, p, np.ascontiguousarray(states), dt, rtol, t_end, stop_on_settle, *outs)
    return outs


def final_state(method, p, state, dt, rtol, t_end, stop_on_settle):
    """(final state, status) of one run, nothing recorded on the way."""
    final = np.empty(6)
    _, _, status, _, _, _, _ = integrate(method, p, state, dt, rtol, t_end, stop_on_settle,
                                         0.0, np.empty((0, 7)), np.empty((0, 9)), final)
    return final, status


def warm_up(method, p, state, dt, rtol):
    """Load the compiled kernels (from numba's cache) for one method before a clock starts.
    The arrays have the same types as in every real call, so the same specialisations load."""
    final_state(method, p, np.ascontiguousarray(state, dtype=np.float64), dt, rtol, dt * 4,
                False)
    label_states(method, p, np.array([state], dtype=np.float64), dt, rtol, dt * 4, True)
