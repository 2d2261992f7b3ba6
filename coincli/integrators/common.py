"""What every integration method shares: the result of a run, and the bookkeeping of its samples,
contact events and final state (kernels on plain floats and arrays)."""

from __future__ import annotations

import math
from typing import NamedTuple

from ..enums import Status
from ..jit import kernel
from ..models.interface import CORNERS

NO_WELL = -32768  # n_well of a run that has not settled (the int16 fill of the stores)

# Event kinds recorded in the events buffer.
ONSET, LIFTOFF = 1, -1
EVENT_COLUMNS = 9  # t, corner, kind, x, y, phi, vx, vy, vphi
SAMPLE_COLUMNS = 7  # t, x, y, phi, vx, vy, vphi


class RunResult(NamedTuple):
    """What a kernel returns for one trajectory (its final state goes into the caller's array)."""

    t: float  # s, time reached
    steps: int  # integrator steps taken (a closed-form flight counts as one)
    status: Status
    settle_time: float  # s, when the energy fell below E_crit (NaN if it did not)
    n_well: int  # the well holding the coin once settled (NO_WELL otherwise)
    n_samples: int  # rows written to the samples buffer
    n_events: int  # rows written to the events buffer
    last_change: float  # s, when the coin last passed from one well to another (NaN: never)
    friction_work: float  # J friction took from the coin (a recorded run; 0 otherwise)
    sliding_work: float  # J per unit friction coefficient: the integral of max(0, N_i) |v_xi|
    # over the corners in contact (a recorded run): what friction mu would take, about mu x it


FINITE_BOUND = 1e30  # a state value this large counts as non-finite (is_finite_state)
ANGLE_BOUND = 1e15  # rad: past it a quarter turn is below the angle's rounding (ulp 0.125)


@kernel
def is_finite_state(st):
    """Whether the state (a 6-tuple or array) can be integrated on. NaN fails every comparison;
    FINITE_BOUND catches a blow-up before it overflows to inf. An angle past ANGLE_BOUND has no
    count of quarter turns (round(2 phi / pi) would be rounding noise, and past 1.4e19 rad
    overflow the count's integer)."""
    big = FINITE_BOUND
    return (abs(st[0]) < big and abs(st[1]) < big and abs(st[2]) < ANGLE_BOUND
            and abs(st[3]) < big and abs(st[4]) < big and abs(st[5]) < big)


@kernel
def unstartable(state, final):
    """The result of a run whose initial state is already past :func:`is_finite_state`'s bound
    (a speed of 1e308 m/s, which a sweep's range can hold): status NONFINITE at t = 0, not a
    step taken. Run, it would overflow at once (to a NaN that ends a closed-form flight at
    t_end as if it had gone well) and, as plain Python, stop on a math domain error."""
    store_state(final, state)
    return RunResult(0.0, 0, Status.NONFINITE, math.nan, NO_WELL, 0, 0, math.nan, 0.0, 0.0)


@kernel
def record_events(events, n_events, t, old_mask, new_mask, st):
    """Append one row per corner whose contact state changed between old_mask and new_mask,
    with the state ``st`` there."""
    changed = old_mask ^ new_mask
    if changed == 0:
        return n_events
    for i in range(CORNERS):
        if changed & (1 << i) and n_events < events.shape[0]:
            row = events[n_events]
            row[0] = t
            row[1] = i
            row[2] = ONSET if new_mask & (1 << i) else LIFTOFF
            for j in range(6):
                row[3 + j] = st[j]
            n_events += 1
    return n_events


@kernel
def store_state(out, st):
    """The state ``st`` into the array ``out``."""
    for j in range(6):
        out[j] = st[j]


@kernel
def record_sample(samples, n_samples, t, st):
    """Append the state ``st`` at time ``t`` to the samples, while they have room."""
    if n_samples < samples.shape[0]:
        row = samples[n_samples]
        row[0] = t
        for j in range(6):
            row[1 + j] = st[j]
        n_samples += 1
    return n_samples


__all__ = ["ANGLE_BOUND", "EVENT_COLUMNS", "FINITE_BOUND", "LIFTOFF", "NO_WELL", "ONSET",
           "RunResult", "SAMPLE_COLUMNS", "is_finite_state", "record_events", "record_sample",
           "store_state", "unstartable"]
