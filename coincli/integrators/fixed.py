"""Fixed-step integrators: symplectic Euler (the paper's), Stormer-Verlet and classical RK4.

One driver, :func:`integrate_fixed`, runs any of them: settling, samples at a display rate,
contact onsets and lift-offs, non-finite states (the bookkeeping in :mod:`.common`).
The contact set of a fixed-step method is whatever corners penetrate at the point where the force
is evaluated, so a contact onset falls somewhere inside a step: that is the error the adaptive
methods avoid by landing on it.
"""

from __future__ import annotations

import math

from ..enums import Method, Status
from ..jit import kernel
from ..models.interface import (
    accelerations_auto,
    contact_mask,
    last_boundary,
    run_horizon,
    sliding,
    total_energy,
    verlet_half_kick,
    well_index,
)
from .common import (
    NO_WELL,
    RunResult,
    is_finite_state,
    record_events,
    record_sample,
    store_state,
    unstartable,
)

CONTROL_EVERY = 4096  # steps between looks at the control flag (a few microseconds apart)


@kernel
def step_symplectic_euler(p, h, st):
    """The paper's scheme: velocities from the force at the old state, positions from the new
    velocities."""
    ax, ay, aphi = accelerations_auto(p, st)
    vx = st[3] + h * ax
    vy = st[4] + h * ay
    vphi = st[5] + h * aphi
    return st[0] + h * vx, st[1] + h * vy, st[2] + h * vphi, vx, vy, vphi


@kernel
def step_verlet(p, h, st):
    """Generalised Stormer-Verlet (Lobatto IIIA-IIIB) for q'' = a0(q) - D(q) q':
    v_half = v + h/2 (a0(q) - D(q) v_half)           (implicit in what the model's law lets
                                                       solve exactly: :func:`verlet_half_kick`)
    q1 = q + h v_half
    v1 = v_half + h/2 (a0(q1) - D(q1) v_half)         (explicit)
    Second order with damping, symplectic when c = 0."""
    h2 = 0.5 * h
    vx, vy, vphi = verlet_half_kick(p, h2, st)
    moved = (st[0] + h * vx, st[1] + h * vy, st[2] + h * vphi, vx, vy, vphi)
    ax, ay, aphi = accelerations_auto(p, moved)
    return moved[0], moved[1], moved[2], vx + h2 * ax, vy + h2 * ay, vphi + h2 * aphi


@kernel
def step_rk4(p, h, st):
    """Classical Runge-Kutta, four force evaluations a step."""
    x, y, phi, vx, vy, vphi = st
    a1x, a1y, a1p = accelerations_auto(p, st)
    h2 = 0.5 * h
    x2, y2, p2 = x + h2 * vx, y + h2 * vy, phi + h2 * vphi
    vx2, vy2, vp2 = vx + h2 * a1x, vy + h2 * a1y, vphi + h2 * a1p
    a2x, a2y, a2p = accelerations_auto(p, (x2, y2, p2, vx2, vy2, vp2))
    x3, y3, p3 = x + h2 * vx2, y + h2 * vy2, phi + h2 * vp2
    vx3, vy3, vp3 = vx + h2 * a2x, vy + h2 * a2y, vphi + h2 * a2p
    a3x, a3y, a3p = accelerations_auto(p, (x3, y3, p3, vx3, vy3, vp3))
    x4, y4, p4 = x + h * vx3, y + h * vy3, phi + h * vp3
    vx4, vy4, vp4 = vx + h * a3x, vy + h * a3y, vphi + h * a3p
    a4x, a4y, a4p = accelerations_auto(p, (x4, y4, p4, vx4, vy4, vp4))
    h6 = h / 6.0
    return (x + h6 * (vx + 2.0 * vx2 + 2.0 * vx3 + vx4),
            y + h6 * (vy + 2.0 * vy2 + 2.0 * vy3 + vy4),
            phi + h6 * (vphi + 2.0 * vp2 + 2.0 * vp3 + vp4),
            vx + h6 * (a1x + 2.0 * a2x + 2.0 * a3x + a4x),
            vy + h6 * (a1y + 2.0 * a2y + 2.0 * a3y + a4y),
            vphi + h6 * (a1p + 2.0 * a2p + 2.0 * a3p + a4p))


@kernel
def fixed_step(method, p, h, st):
    if method == Method.SYMPLECTIC_EULER:
        return step_symplectic_euler(p, h, st)
    if method == Method.VERLET:
        return step_verlet(p, h, st)
    return step_rk4(p, h, st)


@kernel
def integrate_fixed(p, settings, state, samples, events, final, control):
    """Integrate from ``state`` with the fixed step ``settings.dt`` until ``settings.t_end`` (or
    until settled, if ``settings.stop_on_settle``). Writes the final state into ``final``; fills
    ``samples`` (one row every ``settings.sample_dt`` of simulated time, first and last state
    included) and ``events`` (contact onsets and lift-offs) while they have room. Stops with
    status BUDGET after ``settings.max_steps`` steps, INTERRUPTED when ``control[0]`` is set
    (looked at every CONTROL_EVERY steps)."""
    if not is_finite_state(state):
        return unstartable(state, final)
    method = settings.method
    dt = settings.dt
    t_end = run_horizon(p, settings.t_end, state)
    stop_on_settle = settings.stop_on_settle
    sample_dt = settings.sample_dt
    st = (state[0], state[1], state[2], state[3], state[4], state[5])
    e_crit = p.e_crit
    n_total = int(math.ceil(t_end / dt - 1e-9))
    n_run = min(n_total, settings.max_steps)
    record = samples.shape[0] > 0 and sample_dt > 0.0
    track_events = events.shape[0] > 0
    n_samples = 0
    n_events = 0
    if record:
        n_samples = record_sample(samples, 0, 0.0, st)
    next_sample = sample_dt
    mask = contact_mask(p, st[1], st[2]) if track_events else 0
    if track_events and mask != 0:
        n_events = record_events(events, 0, 0.0, 0, mask, st)
    status = Status.UNSETTLED
    settle_time = math.nan
    n_well = NO_WELL
    steps = 0
    t = 0.0
    last_change = math.nan
    friction_work = 0.0  # J taken by friction, and J per unit friction coefficient (recorded)
    sliding_work = 0.0
    if total_energy(p, state) < e_crit:
        status = Status.SETTLED
        settle_time = 0.0
        n_well = well_index(p, st[2])
    if not (status == Status.SETTLED and stop_on_settle):
        for steps in range(1, n_run + 1):
            if steps % CONTROL_EVERY == 0 and control[0] != 0:
                status = Status.INTERRUPTED
                steps -= 1
                break
            phi_old = st[2]
            st = fixed_step(method, p, dt, st)
            crossed = last_boundary(p, phi_old, st[2])
            if crossed == crossed:  # not NaN: interpolated within the step
                last_change = t + dt * (crossed - phi_old) / (st[2] - phi_old)
            t = steps * dt
            if not is_finite_state(st):
                status = Status.NONFINITE
                break
            if track_events:
                new_mask = contact_mask(p, st[1], st[2])
                n_events = record_events(events, n_events, t, mask, new_mask, st)
                mask = new_mask
            if record:
                # the sliding, by the rectangle rule over the step (its own error: the step's)
                power, load = sliding(p, contact_mask(p, st[1], st[2]), st, math.cos(st[2]),
                                      math.sin(st[2]))
                friction_work -= dt * power
                sliding_work += dt * load
                if t >= next_sample - 0.5 * dt:
                    n_samples = record_sample(samples, n_samples, t, st)
                    next_sample += sample_dt
            if status != Status.SETTLED:
                if total_energy(p, st) < e_crit:
                    status = Status.SETTLED
                    settle_time = t
                    n_well = well_index(p, st[2])
            if status == Status.SETTLED and stop_on_settle:
                break
        if status == Status.UNSETTLED and steps == n_run < n_total:
            status = Status.BUDGET
    if record and n_samples > 0 and samples[n_samples - 1, 0] < t:
        n_samples = record_sample(samples, n_samples, t, st)
    if status == Status.SETTLED and not total_energy(p, st) < e_crit:
        # Damping only removes energy: a run that fell below E_crit and ends above it has been
        # pumped by an unstable step. Its certificate is void.
        status = Status.UNSETTLED
        n_well = NO_WELL
        settle_time = math.nan
    store_state(final, st)
    return RunResult(t, steps, status, settle_time, n_well, n_samples, n_events, last_change,
                     friction_work, sliding_work)
