"""Adaptive Dormand-Prince 5(4) with contact events, and the event-driven method built on it.

The right-hand side is smooth as long as the set of penetrating corners (the *mode*) does not
change; it jumps when a corner touches (the damping force appears at full strength) or lifts off.
So the integrator keeps the mode fixed during a step (the force law of a corner in the mode is
extended smoothly beyond the surface), and after each accepted step it checks every corner's
height. If a corner left its side of the surface, the crossing is located on the step's
continuous extension (4th order, Hairer's ``contd5``), the state there is taken from it, the mode
is switched, and integration restarts exactly at the event. No step straddles a jump, so the
method keeps its order, and no step is rejected because of one.

Hysteresis of ``EVENT_BAND`` metres keeps a corner that sits exactly on the surface from
toggling back and forth: a contact corner lifts off when it rises above +EVENT_BAND, a free corner
touches down when it sinks below 0.

``exact_flight`` (the ``event`` method) replaces integration while no corner is in contact by
the closed-form parabola and uniform rotation, and finds the next touch-down on that path by
second-order conservative advancement: each corner's height h obeys h'' >= -(g + vphi^2 r), so
h(t + s) >= h + h' s - (g + vphi^2 r) s^2 / 2 and advancing by the first root of that bound can
never step over a contact, however grazing. Near a transversal root the bound is tight to
O(s^2), so convergence is quadratic (3-5 iterations per flight).

Every run stops, if asked, as soon as the total energy falls below E_crit (the count of quarter
turns is then final, NOTES.md).
"""

from __future__ import annotations

import math

import numpy as np

from ..enums import Method, Status
from ..jit import kernel
from ..model import (
    SX,
    SY,
    accelerations,
    contact_mask,
    corner_heights_at,
    total_energy,
    well_index,
)
from .common import NO_WELL, RunResult, is_finite_state, record_events, record_sample

EVENT_BAND = 1e-13  # m, a contact corner lifts off above this height (hysteresis; the state
# error it causes is proportional to it and ~1e-9 of the coin's scale; rounding of y is 1e-18 m)
LANDING_GAP = 1e-14  # m, how close conservative advancement brings a corner before touch-down
ROOT_TIME_TOL = 1e-15  # s, bracket width at which an event time counts as located
H_MIN = 1e-13  # s, a smaller step means the solution blew up
MAX_TURN = 0.1  # rad, largest rotation in one step (a corner's dip lasts ~0.2 rad at most)
SCAN_TURN = math.pi / 64.0  # rad, pieces in which a step is scanned for crossings

# Dormand-Prince 5(4) tableau.
A21 = 1.0 / 5.0
A31, A32 = 3.0 / 40.0, 9.0 / 40.0
A41, A42, A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
A51, A52, A53, A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
A61, A62, A63, A64, A65 = (9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0,
                           -5103.0 / 18656.0)
B1, B3, B4, B5, B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
E1, E3, E4, E5, E6, E7 = (71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0,
                          22.0 / 525.0, -1.0 / 40.0)
D1, D3, D4, D5, D6, D7 = (-12715105075.0 / 11282082432.0, 87487479700.0 / 32700410799.0,
                          -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0,
                          -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0)


@kernel
def rhs(p, s, mode, out):
    """Time derivative of the state with the contact force on the corners in ``mode``."""
    ax, ay, aphi = accelerations(p, s[0], s[1], s[2], s[3], s[4], s[5], mode)
    out[0] = s[3]
    out[1] = s[4]
    out[2] = s[5]
    out[3] = ax
    out[4] = ay
    out[5] = aphi


@kernel
def error_scales(p, rtol, scale):
    """Absolute tolerance per component: rtol times a natural scale of the coin (its half
    diagonal for positions, 1 rad, the speed sqrt(2 g r) gained falling by r)."""
    r = p.r
    v_ref = math.sqrt(2.0 * max(p.g, 1.0) * r)
    scale[0] = rtol * r
    scale[1] = rtol * r
    scale[2] = rtol
    scale[3] = rtol * v_ref
    scale[4] = rtol * v_ref
    scale[5] = rtol * v_ref / r


@kernel
def dense_component(rc, theta, j):
    """Component j of the state at fraction theta of the last step (continuous extension)."""
    one_minus = 1.0 - theta
    return rc[0, j] + theta * (rc[1, j] + one_minus * (
        rc[2, j] + theta * (rc[3, j] + one_minus * rc[4, j])))


@kernel
def dense_state(rc, theta, out):
    for j in range(6):
        out[j] = dense_component(rc, theta, j)


@kernel
def dense_corner_height(p, rc, theta, i):
    phi = dense_component(rc, theta, 2)
    return (dense_component(rc, theta, 1) + SX[i] * p.r_d * math.sin(phi)
            + SY[i] * p.r_t * math.cos(phi))


@kernel
def locate_crossing(p, rc, h, i, level, lo, hi, g0, g1):
    """Fraction theta of the step in [lo, hi] where corner i's height crosses ``level`` (g0, g1:
    height minus level at lo and hi, of opposite signs). Illinois regula falsi on the
    continuous extension."""
    f_lo, f_hi = g0, g1
    side = 0
    theta = hi
    for _ in range(100):
        theta = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        if not (lo < theta < hi):
            theta = 0.5 * (lo + hi)
        f = dense_corner_height(p, rc, theta, i) - level
        if f == 0.0:
            return theta
        if (f > 0.0) == (f_hi > 0.0):
            hi, f_hi = theta, f
            if side == 1:
                f_lo *= 0.5
            side = 1
        else:
            lo, f_lo = theta, f
            if side == -1:
                f_hi *= 0.5
            side = -1
        if (hi - lo) * h < ROOT_TIME_TOL:
            break
    # the upper end of the bracket is on the far side: the event has certainly happened there
    return hi


@kernel
def _corner_heights_at(p, rc, theta, s_start, s_end, out):
    """Corner heights at fraction theta of the step (the exact end states at 0 and 1)."""
    if theta == 0.0:
        corner_heights_at(p, s_start[1], s_start[2], out)
    elif theta == 1.0:
        corner_heights_at(p, s_end[1], s_end[2], out)
    else:
        corner_heights_at(p, dense_component(rc, theta, 1), dense_component(rc, theta, 2), out)


@kernel
def find_event(p, rc, h, mode, s_start, s_end, before, after):
    """Earliest contact event inside the accepted step: (theta, mask of the corners that switch
    there), or (2.0, 0) if none. A rotating coin can dip a corner below the surface and lift it
    again within one long step, so the step is scanned in pieces of at most SCAN_TURN of rotation
    (the centroid's parabola is concave and cannot hide a dip by itself)."""
    turn = abs(s_end[2] - s_start[2])
    pieces = 1 + min(64, int(turn / SCAN_TURN))
    # before/after: work arrays of 4 heights, allocated once per trajectory by the caller
    _corner_heights_at(p, rc, 0.0, s_start, s_end, before)
    lo = 0.0
    for piece in range(1, pieces + 1):
        hi = 1.0 if piece == pieces else piece / pieces
        _corner_heights_at(p, rc, hi, s_start, s_end, after)
        theta_event = 2.0
        event_mask = 0
        for i in range(4):
            in_contact = (mode >> i) & 1
            level = EVENT_BAND if in_contact else 0.0
            crossed = after[i] > level if in_contact else after[i] < level
            if not crossed:
                continue
            g0 = before[i] - level
            g1 = after[i] - level
            if (g0 > 0.0) == (g1 > 0.0):
                theta = lo  # already across at the start (only by rounding)
            else:
                theta = locate_crossing(p, rc, h, i, level, lo, hi, g0, g1)
            if theta < theta_event - 1e-12:
                theta_event = theta
                event_mask = 1 << i
            elif abs(theta - theta_event) <= 1e-12:
                event_mask |= 1 << i
        if event_mask != 0:
            return theta_event, event_mask
        lo = hi
        before[:] = after
    return 2.0, 0


@kernel
def flight_state(p, s, tau, out):
    """Closed-form free flight: a parabola for the centroid, uniform rotation."""
    out[0] = s[0] + s[3] * tau
    out[1] = s[1] + (s[4] - 0.5 * p.g * tau) * tau
    out[2] = s[2] + s[5] * tau
    out[3] = s[3]
    out[4] = s[4] - p.g * tau
    out[5] = s[5]


@kernel
def time_to_touchdown(p, s, t_max):
    """Time until the first corner touches the surface in free flight from ``s`` (or t_max if
    none does before), and the mask of the corners touching then (0 if none): a coin landing
    flat touches with two corners at once, and taking only one would add a spurious torque.
    Conservative advancement with the second-order lower bound
    h(t + sig) >= h + h' sig - A sig^2 / 2, A = g + vphi^2 r."""
    g = p.g
    w = s[5]
    bound = g + w * w * p.r
    tau = 0.0
    for _ in range(10000):
        y = s[1] + (s[4] - 0.5 * g * tau) * tau
        vy = s[4] - g * tau
        phi = s[2] + w * tau
        c = math.cos(phi)
        sn = math.sin(phi)
        step = math.inf
        touching = 0  # corners on the surface (within LANDING_GAP) and not rising
        for i in range(4):
            px = SX[i] * p.r_d
            py = SY[i] * p.r_t
            height = y + px * sn + py * c
            rate = vy + w * (px * c - py * sn)
            if height <= LANDING_GAP and rate <= 0.0:
                touching |= 1 << i
            hpos = max(height, 0.0)
            if bound > 0.0:
                sig = (rate + math.sqrt(rate * rate + 2.0 * bound * hpos)) / bound
            elif rate < 0.0:
                sig = hpos / -rate
            else:
                sig = math.inf
            step = min(step, sig)
        if touching != 0:
            return tau, touching
        if step < 1e-15:
            # resting on the surface with no downward speed: it is a touch-down of the lowest
            return tau, _lowest_corner_mask(p, y, phi)
        tau += step
        if tau >= t_max:
            return t_max, 0
    return tau, _lowest_corner_mask(p, s[1] + (s[4] - 0.5 * g * tau) * tau, s[2] + w * tau)


@kernel
def _lowest_corner_mask(p, y, phi):
    c = math.cos(phi)
    sn = math.sin(phi)
    lowest = 0
    lowest_height = math.inf
    for i in range(4):
        height = y + SX[i] * p.r_d * sn + SY[i] * p.r_t * c
        if height < lowest_height:
            lowest_height = height
            lowest = i
    return 1 << lowest


@kernel
def integrate_adaptive(p, settings, state, samples, events, final):
    """Dormand-Prince 5(4) with located contact events; for the ``event`` method, closed-form
    flight between contacts. Same contract as :func:`coincli.integrators.fixed.integrate_fixed`."""
    rtol = settings.rtol
    h_init = settings.dt
    t_end = settings.t_end
    stop_on_settle = settings.stop_on_settle
    exact_flight = settings.method == Method.EVENT
    sample_dt = settings.sample_dt
    k = np.empty((7, 6))
    rc = np.empty((5, 6))
    s = state.copy()
    s_new = np.empty(6)
    tmp = np.empty(6)
    scale = np.empty(6)
    before = np.empty(4)
    after = np.empty(4)
    error_scales(p, rtol, scale)
    e_crit = p.e_crit
    record = samples.shape[0] > 0 and sample_dt > 0.0
    n_samples = 0
    n_events = 0
    if record:
        n_samples = record_sample(samples, 0, 0.0, s[0], s[1], s[2], s[3], s[4], s[5])
    next_sample = sample_dt
    mode = contact_mask(p, s[1], s[2])
    if events.shape[0] > 0 and mode != 0:
        n_events = record_events(events, 0, 0.0, 0, mode, s[0], s[1], s[2], s[3], s[4], s[5])
    status = Status.UNSETTLED
    settle_time = math.nan
    n_well = NO_WELL
    t = 0.0
    steps = 0
    h = h_init
    need_rhs = True
    if total_energy(p, s) < e_crit:
        status = Status.SETTLED
        settle_time = 0.0
        n_well = well_index(p, s[2])
    while t < t_end and not (status == Status.SETTLED and stop_on_settle):
        if mode == 0 and exact_flight:
            tau, touching = time_to_touchdown(p, s, t_end - t)
            if record:
                while next_sample <= t + tau and n_samples < samples.shape[0]:
                    flight_state(p, s, next_sample - t, tmp)
                    n_samples = record_sample(samples, n_samples, next_sample, tmp[0], tmp[1],
                                              tmp[2], tmp[3], tmp[4], tmp[5])
                    next_sample += sample_dt
            flight_state(p, s, tau, tmp)
            s[:] = tmp
            t = t + tau if touching != 0 else t_end
            steps += 1
            if touching != 0:
                new_mode = mode | touching
                n_events = record_events(events, n_events, t, mode, new_mode,
                                         s[0], s[1], s[2], s[3], s[4], s[5])
                mode = new_mode
            need_rhs = True
            # flight conserves energy, so settling is only checked where contact begins
            if status != Status.SETTLED and total_energy(p, s) < e_crit:
                status = Status.SETTLED
                settle_time = t
                n_well = well_index(p, s[2])
            continue
        if need_rhs:
            rhs(p, s, mode, k[0])
            need_rhs = False
        h = min(h, t_end - t)
        # A long step could carry a corner below the surface and back unseen: bound the turn.
        if abs(s[5]) * h > MAX_TURN:
            h = MAX_TURN / abs(s[5])
        # --- one Dormand-Prince step from s with step h (stages 2..7) ---
        for j in range(6):
            tmp[j] = s[j] + h * A21 * k[0, j]
        rhs(p, tmp, mode, k[1])
        for j in range(6):
            tmp[j] = s[j] + h * (A31 * k[0, j] + A32 * k[1, j])
        rhs(p, tmp, mode, k[2])
        for j in range(6):
            tmp[j] = s[j] + h * (A41 * k[0, j] + A42 * k[1, j] + A43 * k[2, j])
        rhs(p, tmp, mode, k[3])
        for j in range(6):
            tmp[j] = s[j] + h * (A51 * k[0, j] + A52 * k[1, j] + A53 * k[2, j] + A54 * k[3, j])
        rhs(p, tmp, mode, k[4])
        for j in range(6):
            tmp[j] = s[j] + h * (A61 * k[0, j] + A62 * k[1, j] + A63 * k[2, j] + A64 * k[3, j]
                                 + A65 * k[4, j])
        rhs(p, tmp, mode, k[5])
        for j in range(6):
            s_new[j] = s[j] + h * (B1 * k[0, j] + B3 * k[2, j] + B4 * k[3, j] + B5 * k[4, j]
                                   + B6 * k[5, j])
        rhs(p, s_new, mode, k[6])
        err = 0.0
        for j in range(6):
            e = h * (E1 * k[0, j] + E3 * k[2, j] + E4 * k[3, j] + E5 * k[4, j] + E6 * k[5, j]
                     + E7 * k[6, j])
            tol = scale[j] + rtol * max(abs(s[j]), abs(s_new[j]))
            err += (e / tol) ** 2
        err = math.sqrt(err / 6.0)
        if not (err <= 1.0):  # also catches NaN
            if not (err == err) or h < H_MIN:
                status = Status.NONFINITE
                break
            h *= max(0.2, 0.9 * err ** -0.2)
            continue
        steps += 1
        # --- accepted: continuous extension, then look for contact events inside the step ---
        for j in range(6):
            d = s_new[j] - s[j]
            rc[0, j] = s[j]
            rc[1, j] = d
            rc[2, j] = h * k[0, j] - d
            rc[3, j] = d - h * k[6, j] - rc[2, j]
            rc[4, j] = h * (D1 * k[0, j] + D3 * k[2, j] + D4 * k[3, j] + D5 * k[4, j]
                            + D6 * k[5, j] + D7 * k[6, j])
        theta_event, event_mask = find_event(p, rc, h, mode, s, s_new, before, after)
        if event_mask != 0:
            dense_state(rc, theta_event, s_new)
            t_new = t + theta_event * h
        else:
            t_new = t + h
        if record:
            while next_sample <= t_new and n_samples < samples.shape[0]:
                dense_state(rc, (next_sample - t) / h, tmp)
                n_samples = record_sample(samples, n_samples, next_sample, tmp[0], tmp[1],
                                          tmp[2], tmp[3], tmp[4], tmp[5])
                next_sample += sample_dt
        t = t_new
        s[:] = s_new
        if not is_finite_state(s[0], s[1], s[2], s[3], s[4], s[5]):
            status = Status.NONFINITE
            break
        if event_mask != 0:
            new_mode = mode ^ event_mask
            n_events = record_events(events, n_events, t, mode, new_mode,
                                     s[0], s[1], s[2], s[3], s[4], s[5])
            mode = new_mode
            need_rhs = True
        else:
            for j in range(6):
                k[0, j] = k[6, j]  # first same as last
        if status != Status.SETTLED and total_energy(p, s) < e_crit:
            status = Status.SETTLED
            settle_time = t
            n_well = well_index(p, s[2])
        h *= min(5.0, max(0.2, 0.9 * max(err, 1e-10) ** -0.2))
    if record and n_samples > 0 and samples[n_samples - 1, 0] < t:
        n_samples = record_sample(samples, n_samples, t, s[0], s[1], s[2], s[3], s[4], s[5])
    if status == Status.SETTLED and not total_energy(p, s) < e_crit:
        # energy cannot rise again physically: a void certificate (see integrate_fixed)
        status = Status.UNSETTLED
        n_well = NO_WELL
        settle_time = math.nan
    final[:] = s
    return RunResult(t, steps, status, settle_time, n_well, n_samples, n_events)

