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
from ..model import (
    accelerations_auto,
    contact_mask,
    corner_offset,
    last_boundary,
    run_horizon,
    total_energy,
    total_energy_at,
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
def step_symplectic_euler(p, h, x, y, phi, vx, vy, vphi):
    """The paper's scheme: velocities from the force at the old state, positions from the new
    velocities."""
    ax, ay, aphi = accelerations_auto(p, x, y, phi, vx, vy, vphi)
    vx += h * ax
    vy += h * ay
    vphi += h * aphi
    return x + h * vx, y + h * vy, phi + h * vphi, vx, vy, vphi


@kernel
def _split_accelerations(p, y, phi):
    """The force split as a(q, v) = a0(q) - D(q) v, with D the mass-weighted damping matrix.

    Returns a0 (3 floats) and the 6 distinct entries of the symmetric C = c sum J_i^T J_i over
    penetrating corners, J_i = [[1, 0, -d_yi], [0, 1, d_xi]] (before dividing by the masses)."""
    c = math.cos(phi)
    s = math.sin(phi)
    m = p.mass
    k = p.k
    fy = -m * p.g
    moment = 0.0
    n = 0.0
    sx = 0.0  # sum of d_x over contacts
    sy = 0.0  # sum of d_y
    srr = 0.0  # sum of d_x^2 + d_y^2
    for i in range(4):
        dx, dy = corner_offset(p, i, c, s)
        yi = y + dy
        if yi < 0.0:
            fyi = -k * yi
            fy += fyi
            moment += dx * fyi
            n += 1.0
            sx += dx
            sy += dy
            srr += dx * dx + dy * dy
    return fy / m, moment / p.inertia, n, sx, sy, srr



@kernel
def _solve_damped_velocity(p, h2, ay0, aphi0, n, sx, sy, srr, bx, by, bphi):
    """Solve (M + h2 C) v = M b + h2 M a0 for v, where C = c [[n, 0, -sy], [0, n, sx],
    [-sy, sx, srr]] is the damping matrix of the penetrating corners (linear in v, so the
    implicit half steps of Stormer-Verlet reduce to one 3x3 solve)."""
    m = p.mass
    inertia = p.inertia
    cc = p.c * h2
    # matrix A = M + h2 C
    a11 = m + cc * n
    a22 = m + cc * n
    a33 = inertia + cc * srr
    a13 = -cc * sy
    a23 = cc * sx
    r1 = m * bx
    r2 = m * (by + h2 * ay0)
    r3 = inertia * (bphi + h2 * aphi0)
    # A = [[a11, 0, a13], [0, a22, a23], [a13, a23, a33]]: eliminate by Schur complement.
    s33 = a33 - a13 * a13 / a11 - a23 * a23 / a22
    vphi = (r3 - a13 * r1 / a11 - a23 * r2 / a22) / s33
    vx = (r1 - a13 * vphi) / a11
    vy = (r2 - a23 * vphi) / a22
    return vx, vy, vphi


@kernel
def step_verlet(p, h, x, y, phi, vx, vy, vphi):
    """Generalised Stormer-Verlet (Lobatto IIIA-IIIB) for q'' = a0(q) - D(q) q':
    v_half = v + h/2 (a0(q) - D(q) v_half)           (implicit: one exact 3x3 solve, the
                                                       damping is linear in the velocity)
    q1 = q + h v_half
    v1 = v_half + h/2 (a0(q1) - D(q1) v_half)         (explicit)
    Second order with damping, symplectic when c = 0."""
    h2 = 0.5 * h
    ay0, aphi0, n, sx, sy, srr = _split_accelerations(p, y, phi)
    vx, vy, vphi = _solve_damped_velocity(p, h2, ay0, aphi0, n, sx, sy, srr, vx, vy, vphi)
    x += h * vx
    y += h * vy
    phi += h * vphi
    ax, ay, aphi = accelerations_auto(p, x, y, phi, vx, vy, vphi)
    return x, y, phi, vx + h2 * ax, vy + h2 * ay, vphi + h2 * aphi


@kernel
def step_rk4(p, h, x, y, phi, vx, vy, vphi):
    a1x, a1y, a1p = accelerations_auto(p, x, y, phi, vx, vy, vphi)
    h2 = 0.5 * h
    x2, y2, p2 = x + h2 * vx, y + h2 * vy, phi + h2 * vphi
    vx2, vy2, vp2 = vx + h2 * a1x, vy + h2 * a1y, vphi + h2 * a1p
    a2x, a2y, a2p = accelerations_auto(p, x2, y2, p2, vx2, vy2, vp2)
    x3, y3, p3 = x + h2 * vx2, y + h2 * vy2, phi + h2 * vp2
    vx3, vy3, vp3 = vx + h2 * a2x, vy + h2 * a2y, vphi + h2 * a2p
    a3x, a3y, a3p = accelerations_auto(p, x3, y3, p3, vx3, vy3, vp3)
    x4, y4, p4 = x + h * vx3, y + h * vy3, phi + h * vp3
    vx4, vy4, vp4 = vx + h * a3x, vy + h * a3y, vphi + h * a3p
    a4x, a4y, a4p = accelerations_auto(p, x4, y4, p4, vx4, vy4, vp4)
    h6 = h / 6.0
    return (x + h6 * (vx + 2.0 * vx2 + 2.0 * vx3 + vx4),
            y + h6 * (vy + 2.0 * vy2 + 2.0 * vy3 + vy4),
            phi + h6 * (vphi + 2.0 * vp2 + 2.0 * vp3 + vp4),
            vx + h6 * (a1x + 2.0 * a2x + 2.0 * a3x + a4x),
            vy + h6 * (a1y + 2.0 * a2y + 2.0 * a3y + a4y),
            vphi + h6 * (a1p + 2.0 * a2p + 2.0 * a3p + a4p))


@kernel
def fixed_step(method, p, h, x, y, phi, vx, vy, vphi):
    if method == Method.SYMPLECTIC_EULER:
        return step_symplectic_euler(p, h, x, y, phi, vx, vy, vphi)
    if method == Method.VERLET:
        return step_verlet(p, h, x, y, phi, vx, vy, vphi)
    return step_rk4(p, h, x, y, phi, vx, vy, vphi)


@kernel
def integrate_fixed(p, settings, state, samples, events, final, control):
    """Integrate from ``state`` with the fixed step ``settings.dt`` until ``settings.t_end`` (or
    until settled, if ``settings.stop_on_settle``). Writes the final state into ``final``; fills
    ``samples`` (one row every ``settings.sample_dt`` of simulated time, first and last state
    included) and ``events`` (contact onsets and lift-offs) while they have room. Stops with
    status BUDGET after ``settings.max_steps`` steps, INTERRUPTED when ``control[0]`` is set
    (looked at every CONTROL_EVERY steps)."""
    if not is_finite_state(state[0], state[1], state[2], state[3], state[4], state[5]):
        return unstartable(state, final)
    method = settings.method
    dt = settings.dt
    t_end = run_horizon(p, settings.t_end, state)
    stop_on_settle = settings.stop_on_settle
    sample_dt = settings.sample_dt
    x, y, phi, vx, vy, vphi = state[0], state[1], state[2], state[3], state[4], state[5]
    e_crit = p.e_crit
    n_total = int(math.ceil(t_end / dt - 1e-9))
    n_run = min(n_total, settings.max_steps)
    record = samples.shape[0] > 0 and sample_dt > 0.0
    track_events = events.shape[0] > 0
    n_samples = 0
    n_events = 0
    if record:
        n_samples = record_sample(samples, 0, 0.0, x, y, phi, vx, vy, vphi)
    next_sample = sample_dt
    mask = contact_mask(p, y, phi) if track_events else 0
    if track_events and mask != 0:
        n_events = record_events(events, 0, 0.0, 0, mask, x, y, phi, vx, vy, vphi)
    status = Status.UNSETTLED
    settle_time = math.nan
    n_well = NO_WELL
    steps = 0
    t = 0.0
    last_change = math.nan
    if total_energy(p, state) < e_crit:
        status = Status.SETTLED
        settle_time = 0.0
        n_well = well_index(p, phi)
    if not (status == Status.SETTLED and stop_on_settle):
        for steps in range(1, n_run + 1):
            if steps % CONTROL_EVERY == 0 and control[0] != 0:
                status = Status.INTERRUPTED
                steps -= 1
                break
            phi_old = phi
            x, y, phi, vx, vy, vphi = fixed_step(method, p, dt, x, y, phi, vx, vy, vphi)
            crossed = last_boundary(p, phi_old, phi)
            if crossed == crossed:  # not NaN: interpolated within the step
                last_change = t + dt * (crossed - phi_old) / (phi - phi_old)
            t = steps * dt
            if not is_finite_state(x, y, phi, vx, vy, vphi):
                status = Status.NONFINITE
                break
            if track_events:
                new_mask = contact_mask(p, y, phi)
                n_events = record_events(events, n_events, t, mask, new_mask,
                                         x, y, phi, vx, vy, vphi)
                mask = new_mask
            if record and t >= next_sample - 0.5 * dt:
                n_samples = record_sample(samples, n_samples, t, x, y, phi, vx, vy, vphi)
                next_sample += sample_dt
            if status != Status.SETTLED:
                if total_energy_at(p, y, phi, vx, vy, vphi) < e_crit:
                    status = Status.SETTLED
                    settle_time = t
                    n_well = well_index(p, phi)
            if status == Status.SETTLED and stop_on_settle:
                break
        if status == Status.UNSETTLED and steps == n_run < n_total:
            status = Status.BUDGET
    if record and n_samples > 0 and samples[n_samples - 1, 0] < t:
        n_samples = record_sample(samples, n_samples, t, x, y, phi, vx, vy, vphi)
    if status == Status.SETTLED and not total_energy_at(p, y, phi, vx, vy, vphi) < e_crit:
        # Damping only removes energy: a run that fell below E_crit and ends above it has been
        # pumped by an unstable step. Its certificate is void.
        status = Status.UNSETTLED
        n_well = NO_WELL
        settle_time = math.nan
    store_state(final, x, y, phi, vx, vy, vphi)
    return RunResult(t, steps, status, settle_time, n_well, n_samples, n_events, last_change)
