"""Adaptive Dormand-Prince 5(4) with contact events (``dopri5``), and the event-driven method built
on it (``event``): closed-form flight between contacts.

The Runge-Kutta pair is whatever the names imported from :mod:`.dopri` below mean (``ORDER``,
``step``, ``step_factor``, ``controller_memory``, ``dense_coefficients``, ``dense_point``, with
``FIRST_STEP`` here): :mod:`.pairs` derives a copy of this driver in which they are DOP853's
(``event_dop853``), so the logic is written once for both pairs.

The right-hand side is smooth as long as the set of penetrating corners (the *mode*) does not
change; it jumps when a corner touches (the damping force appears at full strength) or lifts off.
So the integrator keeps the mode fixed during a step (the force law of a corner in the mode is
extended smoothly beyond the surface), and after each accepted step it checks every corner's
height. If a corner left its side of the surface, the crossing is located on the step's
continuous extension, the state there is taken from it, the mode is switched, and integration
restarts exactly at the event. No step straddles a jump, so the method keeps its order, and no
step is rejected because of one. A corner can also cross and come back within one step (a free
corner grazing the surface for a few microseconds while the coin spins on another corner): both
ends of the step then lie on the same side, and the sign of its height alone would miss the
contact. So the corners' vertical speeds are checked too: a free corner that starts the step (or
a scanned piece of it) going down and ends it going up, and whose height the Hermite cubic of its
ends brings near the surface in between, has its lowest point located on the continuous
extension, and touches there if that point is below the surface (likewise the highest point of
a contact corner, for a lift-off).

Hysteresis of ``EVENT_BAND`` metres keeps a corner that sits exactly on the surface from
toggling back and forth: a contact corner lifts off when it rises above +EVENT_BAND, a free corner
touches down when it sinks below 0.

Each contact phase starts with a step of ``FIRST_STEP / omega`` (omega: the stiffest contact
mode, rocking on two corners) rather than with the step the last phase ended with, which was
sized for other dynamics and would mostly be rejected.

Every run stops, if asked, as soon as the total energy falls below E_crit (the count of quarter
turns is then final, docs/model.md); it also stops, with its own status and no label, when its
step budget is used up or when ``control[0]`` is set (another thread asked it to stop).
"""

from __future__ import annotations

import math

from ..enums import Status
from ..jit import kernel
from ..models.interface import (
    CORNERS,
    below,
    corner_heights,
    corner_rates,
    energy_with_heights,
    last_boundary,
    run_horizon,
    sliding,
    step_limit,
    well_index,
)
from ..models.rotation import rotate
from .common import (
    NO_WELL,
    RunResult,
    is_finite_state,
    record_events,
    record_sample,
    store_state,
    unstartable,
)
from .dopri import (
    ORDER,
    controller_memory,
    dense_coefficients,
    dense_point,
    derivative,
    error_scales,
    step,
    step_factor,
)
from .flight import flight_state, time_to_touchdown
from .registry import CLOSED_FORM_FLIGHT

EVENT_BAND = 1e-13  # m, a contact corner lifts off above this height (hysteresis; the state
# error it causes is proportional to it and ~1e-9 of the coin's scale; rounding of y is 1e-18 m)
ROOT_TIME_TOL = 1e-15  # s, bracket width at which an event time counts as located
H_MIN = 1e-13  # s, a smaller step means the solution blew up
MAX_TURN = 0.1  # rad, largest rotation in one step (a corner's dip lasts ~0.2 rad at most)
SCAN_TURN = math.pi / 64.0  # rad, pieces in which a step is scanned for crossings
FIRST_STEP = 0.5  # the first step of a contact phase, in units of 1 / omega
NO_EVENT = 2.0  # theta of a step without an event


@kernel
def dense_corners(p, rc, theta, c, s):
    """(heights, vertical speeds) of the corners at fraction theta of the step (c, s: trig of
    the angle at its start)."""
    point = dense_point(rc, theta)
    cp, sp = rotate(c, s, point[2] - rc[0][2])
    return corner_heights(p, point[1], cp, sp), corner_rates(p, point[4], point[5], cp, sp)


@kernel
def illinois(p, rc, c, s, i, speed, level, lo, hi, f_lo, f_hi, h, tolerance):
    """Illinois regula falsi on the continuous extension for a sign change, on [lo, hi], of
    corner i's height minus ``level`` (or, if ``speed``, of its vertical speed), whose values
    at lo and hi are f_lo and f_hi, until the bracket is shorter than ``tolerance`` / h.
    Returns (the last point tried, the far end of the final bracket)."""
    side = 0
    theta = 0.5 * (lo + hi)
    for _ in range(100):
        theta = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        if not (lo < theta < hi):
            theta = 0.5 * (lo + hi)
        heights, rates = dense_corners(p, rc, theta, c, s)
        f = rates[i] if speed else heights[i] - level
        if f == 0.0:
            return theta, theta
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
        if (hi - lo) * h < tolerance:
            break
    return theta, hi


@kernel(inline=True)
def locate_turn(p, rc, i, lo, hi, v_lo, v_hi, c, s):
    """Fraction theta in [lo, hi] where corner i's vertical speed changes sign (v_lo, v_hi: its
    speeds at lo and hi, of opposite signs), its extreme height."""
    return illinois(p, rc, c, s, i, True, 0.0, lo, hi, v_lo, v_hi, 1.0, 1e-12)[0]


@kernel(inline=True)
def locate_crossing(p, rc, h, i, level, lo, hi, g0, g1, c, s):
    """Fraction theta of the step in [lo, hi] where corner i's height crosses ``level`` (g0,
    g1: height minus level at lo and hi, of opposite signs). Returns the far end of the final
    bracket, where the event has certainly happened."""
    return illinois(p, rc, c, s, i, False, level, lo, hi, g0, g1, h, ROOT_TIME_TOL)[1]


@kernel(inline=True)
def scan_pieces(start, end):
    """How many pieces a step is scanned in for corners that dip and come back within it: a
    rotating coin can do that in one long step (the centroid's parabola is concave and cannot
    hide a dip by itself)."""
    return 1 + min(64, int(abs(end[2] - start[2]) / SCAN_TURN))


@kernel(inline=True)
def dips_across(in_contact, height_0, height_1, rate_0, rate_1, span):
    """Whether a corner on its side of its event level at both ends of ``span`` seconds may
    have crossed the level and come back in between: its distance from the level falls, then
    rises, and the cubic through the ends' distances and rates (Hermite) comes within half the
    nearer end's distance of the level. The step was accepted, so that cubic follows the true
    curve far closer than that margin (at 245 rad/s and a 50 us step, to about 1e-12 m against a
    height change of 1e-4 m): a dip that reaches the level is not dismissed, and a corner rocking
    well clear of the surface costs no search."""
    if in_contact:  # a contact corner's distance below its lift-off level
        f0 = EVENT_BAND - height_0
        f1 = EVENT_BAND - height_1
        d0 = -rate_0 * span
        d1 = -rate_1 * span
    else:
        f0 = height_0
        f1 = height_1
        d0 = rate_0 * span
        d1 = rate_1 * span
    if not (d0 < 0.0 and d1 > 0.0):
        return False
    # the cubic's slope a u^2 + b u + d0 on [0, 1] goes from d0 < 0 to d1 > 0: one root there
    a = 6.0 * (f0 - f1) + 3.0 * (d0 + d1)
    b = 6.0 * (f1 - f0) - 4.0 * d0 - 2.0 * d1
    q = -0.5 * (b + math.copysign(math.sqrt(max(b * b - 4.0 * a * d0, 0.0)), b))
    u = d0 / q if q != 0.0 else 0.5
    if not (0.0 <= u <= 1.0) and a != 0.0:
        u = q / a
    u = min(max(u, 0.0), 1.0)
    w = 1.0 - u
    lowest = (f0 * (1.0 + 2.0 * u) * w * w + d0 * u * w * w + f1 * u * u * (3.0 - 2.0 * u)
              - d1 * u * u * w)
    return lowest < 0.5 * min(f0, f1)


@kernel(inline=True)
def crossing_in(p, rc, h, mode, lo, hi, before, after, v_before, v_after, c, s):
    """Earliest event in the piece [lo, hi] of the step, whose ends have corner heights
    ``before`` and ``after`` and vertical speeds ``v_before`` and ``v_after``: (theta, mask of
    the corners that switch there), or (NO_EVENT, 0)."""
    theta_event = NO_EVENT
    event_mask = 0
    for i in range(CORNERS):
        in_contact = (mode >> i) & 1
        level = EVENT_BAND if in_contact else 0.0
        crossed = after[i] > level if in_contact else after[i] < level
        g0 = before[i] - level
        if crossed:
            g1 = after[i] - level
            end = hi
        elif dips_across(in_contact, before[i], after[i], v_before[i], v_after[i],
                         (hi - lo) * h):
            # both ends on the same side: does the extreme between them cross?
            end = locate_turn(p, rc, i, lo, hi, v_before[i], v_after[i], c, s)
            g1 = dense_corners(p, rc, end, c, s)[0][i] - level
            if (g1 > 0.0) == (g0 > 0.0) or g1 == 0.0:
                continue
        else:
            continue
        if (g0 > 0.0) == (g1 > 0.0):
            theta = lo  # already across at the start (only by rounding)
        else:
            theta = locate_crossing(p, rc, h, i, level, lo, end, g0, g1, c, s)
        if theta < theta_event - 1e-12:
            theta_event = theta
            event_mask = 1 << i
        elif abs(theta - theta_event) <= 1e-12:
            event_mask |= 1 << i
    return theta_event, event_mask


@kernel
def find_event(p, rc, h, mode, pieces, heights_start, heights_end, rates_start, rates_end, c,
               s):
    """Earliest contact event inside an accepted step, scanned in ``pieces``: (theta, mask of
    the corners that switch there), or (NO_EVENT, 0). The heights and speeds at the step's ends
    are the exact ones; inside, those of the continuous extension."""
    before = heights_start
    v_before = rates_start
    lo = 0.0
    for piece in range(1, pieces + 1):
        if piece == pieces:
            hi = 1.0
            after = heights_end
            v_after = rates_end
        else:
            hi = piece / pieces
            after, v_after = dense_corners(p, rc, hi, c, s)
        theta, mask = crossing_in(p, rc, h, mode, lo, hi, before, after, v_before, v_after, c, s)
        if mask != 0:
            return theta, mask
        lo = hi
        before = after
        v_before = v_after
    return NO_EVENT, 0


@kernel(inline=True)
def may_cross(mode, heights_start, heights_end, rates_start, rates_end, h):
    """Whether any corner ends a step of h seconds on the other side of its event level, or
    may have crossed it and come back within the step."""
    for i in range(CORNERS):
        in_contact = (mode >> i) & 1
        if in_contact:
            if heights_end[i] > EVENT_BAND:
                return True
        elif heights_end[i] < 0.0:
            return True
        if dips_across(in_contact, heights_start[i], heights_end[i], rates_start[i],
                       rates_end[i], h):
            return True
    return False


GAUSS_NODES = (0.5 - 0.5 * math.sqrt(0.6), 0.5, 0.5 + 0.5 * math.sqrt(0.6))
GAUSS_WEIGHTS = (5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0)


@kernel
def slide_over_step(p, mode, rc, theta, span, phi0, c, s, friction_work, sliding_work):
    """The friction work and the sliding work (the seam's ``sliding``: the friction power and
    the sliding load) integrated over the part [0, theta] of an accepted step, ``span``
    seconds, on its continuous extension (Gauss-Legendre, 3 points: exact for polynomials of
    degree 5, as far as the extension follows the run), added to the running totals."""
    if mode == 0:
        return friction_work, sliding_work
    for k in range(3):
        point = dense_point(rc, theta * GAUSS_NODES[k])
        cp, sp = rotate(c, s, point[2] - phi0)
        power, load = sliding(p, mode, point, cp, sp)
        friction_work -= span * GAUSS_WEIGHTS[k] * power
        sliding_work += span * GAUSS_WEIGHTS[k] * load
    return friction_work, sliding_work


@kernel
def integrate_adaptive(p, settings, state, samples, events, final, control):
    """Dormand-Prince 5(4) (or, in the copy of :mod:`.pairs`, DOP853) with located contact
    events; for the event methods, closed-form flight between contacts. Same contract as
    :func:`coincli.integrators.fixed.integrate_fixed`."""
    if not is_finite_state(state):
        return unstartable(state, final)
    rtol = settings.rtol
    t_end = run_horizon(p, settings.t_end, state)
    stop_on_settle = settings.stop_on_settle
    budget = settings.max_steps
    exact_flight = CLOSED_FORM_FLIGHT[settings.method]
    sample_dt = settings.sample_dt
    record = samples.shape[0] > 0 and sample_dt > 0.0
    scales = error_scales(p, rtol)
    first_step = FIRST_STEP / p.omega * (rtol / 1e-6) ** (1.0 / ORDER)
    st = (state[0], state[1], state[2], state[3], state[4], state[5])
    c = math.cos(st[2])
    s = math.sin(st[2])
    heights = corner_heights(p, st[1], c, s)
    rates = corner_rates(p, st[4], st[5], c, s)  # kept with heights: the next step's start
    mode = below(heights)
    n_samples = 0
    n_events = 0
    if record:
        n_samples = record_sample(samples, 0, 0.0, st)
    next_sample = sample_dt
    if events.shape[0] > 0 and mode != 0:
        n_events = record_events(events, 0, 0.0, 0, mode, st)
    status = Status.UNSETTLED
    settle_time = math.nan
    n_well = NO_WELL
    t = 0.0
    steps = 0
    work = 0  # steps tried (accepted and rejected) and flight iterations: the budget's count
    last_change = math.nan
    friction_work = 0.0  # J taken by friction, and J per unit friction coefficient (recorded)
    sliding_work = 0.0
    h = settings.dt if mode == 0 else min(settings.dt, first_step)
    memory = controller_memory(1e-4)  # the step-size controller's, as if the last error was 1e-4
    k1 = derivative(p, mode, st, c, s)
    if energy_with_heights(p, st[1], st[3], st[4], st[5], heights) < p.e_crit:
        status = Status.SETTLED
        settle_time = 0.0
        n_well = well_index(p, st[2])
    while t < t_end and not (status == Status.SETTLED and stop_on_settle):
        if work >= budget:
            status = Status.BUDGET
            break
        if control[0] != 0:
            status = Status.INTERRUPTED
            break
        if mode == 0 and exact_flight:
            tau, touching, iterations, c_tau, s_tau = time_to_touchdown(p, st, c, s, t_end - t,
                                                                        budget - work)
            work += iterations
            if touching == 0 and tau < t_end - t:
                status = Status.BUDGET
                break
            if record:
                while next_sample <= t + tau and n_samples < samples.shape[0]:
                    at = flight_state(p, st, next_sample - t)
                    n_samples = record_sample(samples, n_samples, next_sample, at)
                    next_sample += sample_dt
            crossed = last_boundary(p, st[2], st[2] + st[5] * tau)
            if crossed == crossed:  # not NaN: exact, the flight turns uniformly
                last_change = t + (crossed - st[2]) / st[5]
            st = flight_state(p, st, tau)
            if not is_finite_state(st):
                # a flight that overflows (or a NaN tau) must not end at t_end as if it had
                # landed well: no outcome, and no cosine of an infinite angle below
                t = t + tau if tau < t_end - t else t_end
                status = Status.NONFINITE
                break
            if touching != 0:
                c, s = c_tau, s_tau
            else:  # tau is t_max, short of the search's last angle
                c = math.cos(st[2])
                s = math.sin(st[2])
            heights = corner_heights(p, st[1], c, s)
            rates = corner_rates(p, st[4], st[5], c, s)
            t = t + tau if touching != 0 else t_end
            steps += 1
            if touching != 0:
                n_events = record_events(events, n_events, t, mode, touching, st)
                mode = touching
                h = first_step
                k1 = derivative(p, mode, st, c, s)
            # flight conserves energy, so settling is only checked where contact begins
            if status != Status.SETTLED and (energy_with_heights(p, st[1], st[3], st[4], st[5],
                                                                 heights) < p.e_crit):
                status = Status.SETTLED
                settle_time = t
                n_well = well_index(p, st[2])
            continue
        h = min(h, t_end - t)
        # A long step could carry a corner below the surface and back unseen: bound the turn.
        if abs(st[5]) * h > MAX_TURN:
            h = MAX_TURN / abs(st[5])
        h = step_limit(p, mode, st, k1, c, s, h)  # the law may see a sharp turn ahead
        end, k7, c7, s7, err, stages = step(p, mode, h, st, k1, c, s, scales, rtol)
        work += 1
        if not (err <= 1.0):  # also catches NaN
            if not (err == err) or h < H_MIN:
                status = Status.NONFINITE
                break
            h *= step_factor(err, 1.0, 1.0)
            continue
        steps += 1
        heights_end = corner_heights(p, end[1], c7, s7)
        rates_end = corner_rates(p, end[4], end[5], c7, s7)
        pieces = scan_pieces(st, end)
        theta = NO_EVENT
        event_mask = 0
        # a recorded run takes every step's continuous extension: the sliding is integrated
        # on it (an unrecorded one needs it only for an event or a sample)
        dense = (record or pieces > 1
                 or may_cross(mode, heights, heights_end, rates, rates_end, h))
        if dense:
            rc = dense_coefficients(p, mode, st, end, h, stages, c, s)
            theta, event_mask = find_event(p, rc, h, mode, pieces, heights, heights_end, rates,
                                           rates_end, c, s)
            t_new = t + theta * h if event_mask != 0 else t + h
            if record:
                while next_sample <= t_new and n_samples < samples.shape[0]:
                    at = dense_point(rc, (next_sample - t) / h)
                    n_samples = record_sample(samples, n_samples, next_sample, at)
                    next_sample += sample_dt
                friction_work, sliding_work = slide_over_step(
                    p, mode, rc, (t_new - t) / h, t_new - t, st[2], c, s, friction_work,
                    sliding_work)
            if event_mask != 0:
                end = dense_point(rc, theta)
                c7, s7 = rotate(c, s, end[2] - st[2])
                heights_end = corner_heights(p, end[1], c7, s7)
                rates_end = corner_rates(p, end[4], end[5], c7, s7)
        else:
            t_new = t + h
        crossed = last_boundary(p, st[2], end[2])
        if crossed == crossed:  # within the step: phi is nearly linear over it
            last_change = t + (t_new - t) * (crossed - st[2]) / (end[2] - st[2])
        t = t_new
        st = end
        c = c7
        s = s7
        heights = heights_end
        rates = rates_end
        if not is_finite_state(st):
            status = Status.NONFINITE
            break
        if event_mask != 0:
            new_mode = mode ^ event_mask
            n_events = record_events(events, n_events, t, mode, new_mode, st)
            if mode == 0:
                h = first_step  # a touch-down: the contact's own time scale
            mode = new_mode
            k1 = derivative(p, mode, st, c, s)
        else:
            k1 = k7  # first same as last
        if status != Status.SETTLED and (energy_with_heights(p, st[1], st[3], st[4], st[5],
                                                             heights) < p.e_crit):
            status = Status.SETTLED
            settle_time = t
            n_well = well_index(p, st[2])
        if event_mask == 0 or mode != 0:
            h *= step_factor(err, memory, 5.0)
            memory = controller_memory(err)
    if record and n_samples > 0 and samples[n_samples - 1, 0] < t:
        n_samples = record_sample(samples, n_samples, t, st)
    if status == Status.SETTLED and not (energy_with_heights(p, st[1], st[3], st[4], st[5],
                                                             heights) < p.e_crit):
        # energy cannot rise again physically: a void certificate (see integrate_fixed)
        status = Status.UNSETTLED
        n_well = NO_WELL
        settle_time = math.nan
    store_state(final, st)
    return RunResult(t, steps, status, settle_time, n_well, n_samples, n_events, last_change,
                     friction_work, sliding_work)


__all__ = ["EVENT_BAND", "MAX_TURN", "integrate_adaptive"]
