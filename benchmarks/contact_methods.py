"""Fewer steps per contact (issue 34): an exponential Rosenbrock method for the contact phases,
measured side by side with the current single pass (the ``event`` method, Dormand-Prince 5(4)
at rtol 1e-6, the default ladder's first rung) on the throws of ``coin bench`` and on the
robust cells of the stored references.

    python benchmarks/contact_methods.py [--rounds 5] [--out benchmarks/contact-methods.json]

The methods (exponential Rosenbrock, Hochbruck, Ostermann and Schweitzer 2009). Within a contact
phase the mode (the set of corners in contact) is fixed and the right-hand side F(u) is smooth.
With J = F'(u_n), the Jacobian at the step's start (the linearisation about the current angle,
derived in docs/contact-methods.md) and the remainder D(U) = F(U) - F(u_n) - J (U - u_n), a step
of size h is, for ``exprb32`` (order 3, two right-hand sides):

    U2      = u_n + h phi_1(hJ) F(u_n)                      (exponential Rosenbrock-Euler, order 2)
    u_{n+1} = U2 + 2 h phi_3(hJ) D(U2)                      error estimate: 2 h phi_3(hJ) D(U2)

and for ``exprb43`` (order 4, embedded order 3, three right-hand sides):

    U2      = u_n + (h/2) phi_1(hJ/2) F(u_n)
    U3      = u_n + h phi_1(hJ) (F(u_n) + D(U2))
    u_{n+1} = u_n + h phi_1(hJ) F(u_n) + h phi_3(hJ) (16 D2 - 2 D3) + h phi_4(hJ) (12 D3 - 48 D2)
                                                            error estimate: the phi_4 term

with phi_k(z) = sum_j z^j / (j + k)!. Both are exact when F is affine (a frozen angle: a damped
linear oscillator plus gravity): only the remainder, which comes from the rotation of the coin
during the step, is integrated approximately. phi_k(hJ) v is summed as its Taylor series on the
vector (a product with the sparse 6x6 J is 15 multiply-adds), with h limited so that
h rho(J) <= RHO_STEP (the series then loses at most a few digits to cancellation).

What is simpler than in coincli's driver (stated, not hidden): contact events are located by
re-taking the step to a trial fraction theta (safeguarded Newton on the corner's height, its
speed the derivative) rather than on a continuous extension; a corner that may dip across the
surface and back within a step (the same Hermite test as the driver's, ``dips_across``) makes
the step shorter until its end lands past the crossing or the test clears it. Flight is coincli's
closed form (``time_to_touchdown``, ``flight_state``). The settling rule, the label (``well_index``
once E < E_crit), the error scales and the event band are coincli's.

Kernels here are plain Python, calling the plain-Python kernel set of coincli's paper model,
until :func:`compile_kernels` binds the names they call to the model's compiled kernel set and
wraps them in numba too, so tests can run them as Python on a few steps.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from coincli.integrators import adaptive, dopri, flight  # noqa: E402
from coincli.models import PAPER  # noqa: E402

RHO_STEP = 8.0  # largest h times the spectral-radius bound of J (Taylor series of phi_k)
SERIES_TOL = 1e-14  # a term of the phi series below this (relative, scaled max norm) ends it
MAX_TERMS = 80
FIRST_STEP = 0.5  # first step of a contact phase in units of 1 / omega (coincli's)
MIN_DIP_STEP = 1e-9  # s: below this a possible dip no longer shortens the step
NEWTON_OVERSHOOT = 1e-3  # an iterate short of the surface steps this much past Newton's root
BUDGET = 200_000

# the kernels of coincli this module calls, by the name it calls them: those of a kernel set of
# the paper's model (:func:`bind`), plain Python until :func:`compile_kernels`
KERNEL_NAMES = ("contact_accelerations", "corner_offset", "corner_heights", "corner_rates",
                "below", "energy_with_heights", "well_index", "rounded_quarter_turns", "rotate",
                "time_to_touchdown", "flight_state", "may_cross", "error_scales", "dopri_step")


def kernels_of(ks) -> tuple:
    """The kernels of KERNEL_NAMES in the kernel set ``ks``, in that order."""
    return (ks.contact_accelerations, ks.corner_offset, ks.corner_heights, ks.corner_rates,
            ks.below, ks.energy_with_heights, ks.well_index, ks.rounded_quarter_turns, ks.rotate,
            ks[flight.time_to_touchdown], ks[flight.flight_state], ks[adaptive.may_cross],
            ks[dopri.error_scales], ks[dopri.step])


def bind(ks) -> None:
    """Bind the names of coincli's kernels this module calls to those of the kernel set ``ks``
    (numba resolves a global function when it compiles its caller)."""
    globals().update(zip(KERNEL_NAMES, kernels_of(ks), strict=True))


(contact_accelerations, corner_offset, corner_heights, corner_rates, below, energy_with_heights,
 well_index, rounded_quarter_turns, rotate, time_to_touchdown, flight_state, may_cross,
 error_scales, dopri_step) = kernels_of(PAPER.kernels("python"))

# counters of one throw, in this order
COUNTERS = ("accepted", "rejected", "flights", "event_trials", "dip_rejects", "rhs", "matvecs")


def rhs(p, mode, st, c, s):
    """F(u): the time derivative of the state in contact mode ``mode``."""
    ax, ay, aphi = contact_accelerations(p, mode, st, c, s)
    return (st[3], st[4], st[5], ax, ay, aphi)


def jacobian(p, mode, st, c, s):
    """The accelerations' partial derivatives with respect to (y, phi, vx, vy, vphi), row by row
    (a_x, a_y, a_phi): 15 numbers. x enters nothing; the positions' rows of J are the identity
    on the velocities. Per corner i in contact, with offset d = R(phi) p_i
    (dd/dphi = (-d_y, d_x)) and force F_i = (-c (vx - vphi d_y), -k (y + d_y) - c (vy + vphi d_x)):
    dF_x = (0, c vphi d_x, -c, 0, c d_y), dF_y = (-k, -k d_x + c vphi d_y, 0, -c, -c d_x),
    dM = d_x dF_y - d_y dF_x, plus d/dphi of the lever arms: -d_y F_y - d_x F_x."""
    y, vx, vy, vphi = st[1], st[3], st[4], st[5]
    kk = p.k
    cc = p.c
    fx_phi = fx_vx = fx_vphi = 0.0
    fy_y = fy_phi = fy_vy = fy_vphi = 0.0
    m_y = m_phi = m_vx = m_vy = m_vphi = 0.0
    for i in range(4):
        if mode & (1 << i):
            dx, dy = corner_offset(p, i, c, s)
            fxi = -cc * (vx - vphi * dy)
            fyi = -kk * (y + dy) - cc * (vy + vphi * dx)
            fx_phi += cc * vphi * dx
            fx_vx -= cc
            fx_vphi += cc * dy
            fy_y -= kk
            fy_phi += -kk * dx + cc * vphi * dy
            fy_vy -= cc
            fy_vphi -= cc * dx
            m_y -= kk * dx
            m_phi += -kk * dx * dx - dy * fyi - dx * fxi
            m_vx += cc * dy
            m_vy -= cc * dx
            m_vphi -= cc * (dx * dx + dy * dy)
    im = p.inv_mass
    ii = p.inv_inertia
    return (0.0, fx_phi * im, fx_vx * im, 0.0, fx_vphi * im,
            fy_y * im, fy_phi * im, 0.0, fy_vy * im, fy_vphi * im,
            m_y * ii, m_phi * ii, m_vx * ii, m_vy * ii, m_vphi * ii)


def jacobian_times(jac, v):
    """J v for the 6x6 Jacobian whose acceleration rows are ``jac`` (see :func:`jacobian`)."""
    return (v[3], v[4], v[5],
            jac[0] * v[1] + jac[1] * v[2] + jac[2] * v[3] + jac[3] * v[4] + jac[4] * v[5],
            jac[5] * v[1] + jac[6] * v[2] + jac[7] * v[3] + jac[8] * v[4] + jac[9] * v[5],
            jac[10] * v[1] + jac[11] * v[2] + jac[12] * v[3] + jac[13] * v[4] + jac[14] * v[5])


def spectral_bound(p, jac):
    """An upper estimate of |lambda| for J: |C| + sqrt(|K|), a bound on the roots of
    det(lambda^2 - lambda C - K) = 0, with K and C the acceleration rows' position and velocity
    blocks and |.| the row-sum norm after measuring the angle in units of 1 / r (a similarity,
    which leaves the eigenvalues alone but balances the units: a_phi per metre of y is 1e9)."""
    r = p.r
    stiff = max(abs(jac[0]) + abs(jac[1]) / r, abs(jac[5]) + abs(jac[6]) / r,
                r * abs(jac[10]) + abs(jac[11]))
    damp = max(abs(jac[2]) + abs(jac[3]) + abs(jac[4]) / r,
               abs(jac[7]) + abs(jac[8]) + abs(jac[9]) / r,
               r * (abs(jac[12]) + abs(jac[13])) + abs(jac[14]))
    return damp + math.sqrt(stiff)


def phi_times(jac, h, v, k, weights):
    """phi_k(hJ) v = sum_j (hJ)^j v / (j + k)!, summed until a term is below SERIES_TOL of the
    sum in the scaled max norm (``weights``: 1 / each component's scale). Returns (the vector,
    matrix-vector products used)."""
    f = 1.0
    for j in range(2, k + 1):
        f *= j
    term = (v[0] / f, v[1] / f, v[2] / f, v[3] / f, v[4] / f, v[5] / f)
    total = term
    used = 0
    for j in range(1, MAX_TERMS):
        jv = jacobian_times(jac, term)
        scale = h / (j + k)
        term = (jv[0] * scale, jv[1] * scale, jv[2] * scale, jv[3] * scale, jv[4] * scale,
                jv[5] * scale)
        total = (total[0] + term[0], total[1] + term[1], total[2] + term[2], total[3] + term[3],
                 total[4] + term[4], total[5] + term[5])
        used += 1
        size = 0.0
        whole = 0.0
        for i in range(6):
            size = max(size, abs(term[i]) * weights[i])
            whole = max(whole, abs(total[i]) * weights[i])
        if size <= SERIES_TOL * whole or size == 0.0:
            break
    return total, used


def remainder(p, mode, st, f0, jac, u, c, s):
    """D(U) = F(U) - F(u_n) - J (U - u_n): what the frozen linearisation at u_n leaves out."""
    cu, su = rotate(c, s, u[2] - st[2])
    fu = rhs(p, mode, u, cu, su)
    diff = (u[0] - st[0], u[1] - st[1], u[2] - st[2], u[3] - st[3], u[4] - st[4],
            u[5] - st[5])
    jd = jacobian_times(jac, diff)
    return (fu[0] - f0[0] - jd[0], fu[1] - f0[1] - jd[1], fu[2] - f0[2] - jd[2],
            fu[3] - f0[3] - jd[3], fu[4] - f0[4] - jd[4], fu[5] - f0[5] - jd[5])


def exprb32(p, mode, h, st, f0, jac, c, s, weights):
    """One exprb32 step of size h from ``st`` (f0 = F(st), jac its Jacobian; c, s the trig of its
    angle). Returns (end state, the error estimate 2 h phi_3(hJ) D, cos and sin at the end,
    matrix-vector products used)."""
    a, used1 = phi_times(jac, h, f0, 1, weights)
    u2 = (st[0] + h * a[0], st[1] + h * a[1], st[2] + h * a[2], st[3] + h * a[3],
          st[4] + h * a[4], st[5] + h * a[5])
    d = remainder(p, mode, st, f0, jac, u2, c, s)
    b, used3 = phi_times(jac, h, d, 3, weights)
    e = (2.0 * h * b[0], 2.0 * h * b[1], 2.0 * h * b[2], 2.0 * h * b[3], 2.0 * h * b[4],
         2.0 * h * b[5])
    end = (u2[0] + e[0], u2[1] + e[1], u2[2] + e[2], u2[3] + e[3], u2[4] + e[4], u2[5] + e[5])
    c1, s1 = rotate(c, s, end[2] - st[2])
    return end, e, c1, s1, used1 + used3 + 1


def exprb43(p, mode, h, st, f0, jac, c, s, weights):
    """One exprb43 step (order 4, embedded order 3): see the module docstring."""
    a, u1 = phi_times(jac, 0.5 * h, f0, 1, weights)
    u2 = (st[0] + 0.5 * h * a[0], st[1] + 0.5 * h * a[1], st[2] + 0.5 * h * a[2],
          st[3] + 0.5 * h * a[3], st[4] + 0.5 * h * a[4], st[5] + 0.5 * h * a[5])
    d2 = remainder(p, mode, st, f0, jac, u2, c, s)
    g = (f0[0] + d2[0], f0[1] + d2[1], f0[2] + d2[2], f0[3] + d2[3], f0[4] + d2[4],
         f0[5] + d2[5])
    b, u2n = phi_times(jac, h, g, 1, weights)
    u3 = (st[0] + h * b[0], st[1] + h * b[1], st[2] + h * b[2], st[3] + h * b[3],
          st[4] + h * b[4], st[5] + h * b[5])
    d3 = remainder(p, mode, st, f0, jac, u3, c, s)
    # u_{n+1} = u_n + h phi1 F + h phi3 (16 D2 - 2 D3) + h phi4 (-48 D2 + 12 D3)
    # = u3 - h phi1 D2 + ...: phi1 F is recomputed as part of b; keep phi1 F separately instead
    f1, u1b = phi_times(jac, h, f0, 1, weights)
    w3 = (16.0 * d2[0] - 2.0 * d3[0], 16.0 * d2[1] - 2.0 * d3[1], 16.0 * d2[2] - 2.0 * d3[2],
          16.0 * d2[3] - 2.0 * d3[3], 16.0 * d2[4] - 2.0 * d3[4], 16.0 * d2[5] - 2.0 * d3[5])
    w4 = (12.0 * d3[0] - 48.0 * d2[0], 12.0 * d3[1] - 48.0 * d2[1], 12.0 * d3[2] - 48.0 * d2[2],
          12.0 * d3[3] - 48.0 * d2[3], 12.0 * d3[4] - 48.0 * d2[4], 12.0 * d3[5] - 48.0 * d2[5])
    p3, u3n = phi_times(jac, h, w3, 3, weights)
    p4, u4n = phi_times(jac, h, w4, 4, weights)
    e = (h * p4[0], h * p4[1], h * p4[2], h * p4[3], h * p4[4], h * p4[5])
    end = (st[0] + h * (f1[0] + p3[0]) + e[0], st[1] + h * (f1[1] + p3[1]) + e[1],
           st[2] + h * (f1[2] + p3[2]) + e[2], st[3] + h * (f1[3] + p3[3]) + e[3],
           st[4] + h * (f1[4] + p3[4]) + e[4], st[5] + h * (f1[5] + p3[5]) + e[5])
    c1, s1 = rotate(c, s, end[2] - st[2])
    return end, e, c1, s1, u1 + u2n + u1b + u3n + u4n + 2


def error_norm(st, end, e, scales, rtol):
    """RMS of the error over coincli's per-component tolerance (as dopri.step)."""
    total = 0.0
    for j in range(6):
        tol = scales[j] + rtol * max(abs(st[j]), abs(end[j]))
        total += (e[j] / tol) ** 2
    return math.sqrt(total / 6.0)


def crossed_corner(mode, heights):
    """Mask of the corners past their event level (lift-off above the band, touch-down below 0)."""
    mask = 0
    for i in range(4):
        if (mode >> i) & 1:
            if heights[i] > adaptive.EVENT_BAND:
                mask |= 1 << i
        elif heights[i] < 0.0:
            mask |= 1 << i
    return mask


def exp_step(order, p, mode, h, st, f0, jac, c, s, weights):
    """exprb32 (order 3) or exprb43 (order 4)."""
    if order == 4:
        return exprb43(p, mode, h, st, f0, jac, c, s, weights)
    return exprb32(p, mode, h, st, f0, jac, c, s, weights)


def locate(order, p, mode, h, st, f0, jac, c, s, weights, i, g_end):
    """Fraction theta of the step where corner i crosses its level (it has at theta = 1, height
    minus level g_end there): safeguarded Newton on re-taken steps, ending on the crossed side.
    Returns (theta, state there, cos, sin, trials, matrix-vector products)."""
    level = adaptive.EVENT_BAND if (mode >> i) & 1 else 0.0
    heights0 = corner_heights(p, st[1], c, s)
    lo = 0.0
    g_lo = heights0[i] - level
    hi = 1.0
    g_hi = g_end
    theta = lo - g_lo * (hi - lo) / (g_hi - g_lo)
    best_theta = 1.0
    best = st
    best_c = c
    best_s = s
    have_best = False
    trials = 0
    used = 0
    for _ in range(60):
        if not (lo < theta < hi):
            theta = 0.5 * (lo + hi)
        at, _e, ca, sa, u = exp_step(order, p, mode, theta * h, st, f0, jac, c, s, weights)
        trials += 1
        used += u
        g = corner_heights(p, at[1], ca, sa)[i] - level
        rate = corner_rates(p, at[4], at[5], ca, sa)[i]
        crossed = (g > 0.0) == (g_hi > 0.0) and g != 0.0
        if crossed:
            hi = theta
            g_hi = g
            best_theta, best, best_c, best_s, have_best = theta, at, ca, sa, True
            if abs(g) < 1e-15:
                break
        else:
            lo = theta
            g_lo = g
        if (hi - lo) * h < adaptive.ROOT_TIME_TOL:
            break
        slope = rate * h
        nxt = theta - g / slope if slope != 0.0 else -1.0
        if not crossed:
            nxt = theta + (nxt - theta) * (1.0 + NEWTON_OVERSHOOT)
        if not (lo < nxt < hi):
            nxt = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
        theta = nxt
    if not have_best:  # only the step's end is known to be past the level
        best, _e, best_c, best_s, u = exp_step(order, p, mode, h, st, f0, jac, c, s, weights)
        used += u
        trials += 1
    return best_theta, best, best_c, best_s, trials, used


def run_throw(order, p, rtol, t_end, state, counts):
    """One throw with exprb32 contact phases and closed-form flight: (label, status); ``counts``
    (an int64 array of len(COUNTERS)) gets the work done."""
    for j in range(len(COUNTERS)):
        counts[j] = 0
    scales = error_scales(p, rtol)
    weights = (1.0 / scales[0], 1.0 / scales[1], 1.0 / scales[2], 1.0 / scales[3],
               1.0 / scales[4], 1.0 / scales[5])
    first_step = FIRST_STEP / p.omega * (rtol / 1e-6) ** (1.0 / order)
    st = (state[0], state[1], state[2], state[3], state[4], state[5])
    c = math.cos(st[2])
    s = math.sin(st[2])
    heights = corner_heights(p, st[1], c, s)
    rates = corner_rates(p, st[4], st[5], c, s)
    mode = below(heights)
    t = 0.0
    h = first_step
    work = 0
    if energy_with_heights(p, st[1], st[3], st[4], st[5], heights) < p.e_crit:
        return well_index(p, st[2]), 0
    while t < t_end:
        if work >= BUDGET:
            return -32768, 3
        if mode == 0:
            tau, touching, iterations, c_tau, s_tau = time_to_touchdown(
                p, st, c, s, t_end - t, BUDGET - work)
            work += iterations
            counts[2] += 1
            st = flight_state(p, st, tau)
            if touching == 0:
                t = t_end
                break
            c, s = c_tau, s_tau
            t += tau
            heights = corner_heights(p, st[1], c, s)
            rates = corner_rates(p, st[4], st[5], c, s)
            mode = touching
            h = first_step
            if energy_with_heights(p, st[1], st[3], st[4], st[5], heights) < p.e_crit:
                return well_index(p, st[2]), 0
            continue
        f0 = rhs(p, mode, st, c, s)
        jac = jacobian(p, mode, st, c, s)
        counts[5] += 1
        h = min(h, t_end - t, RHO_STEP / spectral_bound(p, jac))
        if abs(st[5]) * h > adaptive.MAX_TURN:
            h = adaptive.MAX_TURN / abs(st[5])
        end, e, c1, s1, used = exp_step(order, p, mode, h, st, f0, jac, c, s, weights)
        work += 1
        counts[5] += 1
        counts[6] += used
        err = error_norm(st, end, e, scales, rtol)
        if not (err <= 1.0):
            if not (err == err) or h < adaptive.H_MIN:
                return -32768, 2
            counts[1] += 1
            h *= max(0.2, 0.9 * err ** (-1.0 / order))
            continue
        heights_end = corner_heights(p, end[1], c1, s1)
        rates_end = corner_rates(p, end[4], end[5], c1, s1)
        mask = crossed_corner(mode, heights_end)
        if mask == 0 and h > MIN_DIP_STEP and may_cross(mode, heights, heights_end, rates,
                                                        rates_end, h):
            counts[4] += 1  # a corner may have crossed and come back: a shorter step
            h *= 0.5
            continue
        counts[0] += 1
        if mask != 0:
            theta = 2.0
            event = 0
            for i in range(4):
                if (mask >> i) & 1:
                    level = adaptive.EVENT_BAND if (mode >> i) & 1 else 0.0
                    th, at, ca, sa, trials, u = locate(order, p, mode, h, st, f0, jac, c, s,
                                                       weights, i, heights_end[i] - level)
                    counts[3] += trials
                    counts[6] += u
                    if th < theta - 1e-12:
                        theta, end, c1, s1, event = th, at, ca, sa, 1 << i
                    elif abs(th - theta) <= 1e-12:
                        event |= 1 << i
            t += theta * h
            st, c, s = end, c1, s1
            heights = corner_heights(p, st[1], c, s)
            rates = corner_rates(p, st[4], st[5], c, s)
            mode ^= event  # h stays: the controller adapts it to the new mode
        else:
            t += h
            st, c, s = end, c1, s1
            heights = heights_end
            rates = rates_end
            h *= min(5.0, max(0.2, 0.9 * (max(err, 1e-10)) ** (-1.0 / order)))
        if not (abs(st[1]) < math.inf and abs(st[5]) < math.inf):
            return -32768, 2
        if energy_with_heights(p, st[1], st[3], st[4], st[5], heights) < p.e_crit:
            return well_index(p, st[2]), 0
    return rounded_quarter_turns(st[2]), 1


def run_throws(order, p, rtol, t_end, states, labels, statuses, counts):
    """Every row of ``states``: labels, statuses and each throw's counters (rows of counts)."""
    for n in range(states.shape[0]):
        labels[n], statuses[n] = run_throw(order, p, rtol, t_end, states[n], counts[n])


KERNELS = ("rhs", "jacobian", "jacobian_times", "spectral_bound", "phi_times", "remainder",
           "exprb32", "exprb43", "exp_step", "error_norm", "crossed_corner", "locate",
           "run_throw", "run_throws")
# (name, order, rtol) of the variants measured against the current single pass
VARIANTS = (("exprb32 rtol 1e-6", 3, 1e-6), ("exprb43 rtol 1e-6", 4, 1e-6),
            ("exprb43 rtol 1e-5", 4, 1e-5), ("exprb43 rtol 1e-4", 4, 1e-4),
            ("exprb43 rtol 1e-3", 4, 1e-3))
CURRENT = "event rtol 1e-6 (current single pass)"
# coincli's event method at other tolerances, for comparisons at equal label accuracy
EVENT_RTOLS = (("event rtol 1e-5", 1e-5), ("event rtol 1e-7", 1e-7))


def compile_kernels():
    """Bind coincli's kernels to the paper model's compiled kernel set, then wrap this module's
    in numba too; returns the compiled run_throws."""
    import numba

    bind(PAPER.kernels())  # every coincli kernel name is a dispatcher from here
    space = globals()
    for name in KERNELS:
        space[name] = numba.njit(fastmath={"contract"})(space[name])
    return space["run_throws"]


# ---------------------------------------------------------------------------------------------
# the measurement


def scene_of(preset):
    import coincli

    return coincli.load_preset(preset)


def label_grid_states(scene, res):
    from coincli.accuracy import vy_vphi_grid

    return vy_vphi_grid(scene, res=(res, res)).states()


def references(scene, states, name, threads):
    """(robust mask, reference labels): coincli's event method at rtol 1e-12 and fixed-step RK4
    at h = 2.5e-7 (benchmarks/rk4-NAME.npz, computed and stored if absent) both settled with the
    same label."""
    import numpy as np

    from coincli.labeller import Labeller

    sys.path.insert(0, str(HERE))
    from ladder_design import reference_labels

    cache = HERE / f"rk4-{name}.npz"
    if cache.exists():
        saved = np.load(cache)
        rk4_q, rk4_st = saved["q"], saved["st"]
    else:
        rk4_q, rk4_st = reference_labels(scene, states, threads)
        np.savez(cache, q=rk4_q, st=rk4_st)
    tight = scene.with_overrides(method="event", rtol=1e-12, stop_on_settle=True, t_end=2.0,
                                 verify=False)
    ref = Labeller.of(tight).label(states)  # a single pass
    robust = (ref.status == 0) & (rk4_st == 0) & (ref.quarter_turns == rk4_q)
    return robust, ref.quarter_turns


def measure(preset, res, rounds, threads, run_exprb):
    import numpy as np

    from coincli.labeller import Labeller

    scene = scene_of(preset)
    name = f"{Path(preset).stem}-{res}"
    states = label_grid_states(scene, res)
    bench_states = label_grid_states(scene, 8)  # coin bench's cost grid (--cost-res 8)
    robust, reference = references(scene, states, name, threads)
    single = scene.with_overrides(method="event", rtol=1e-6, stop_on_settle=True, t_end=2.0,
                                  verify=False)
    labeller = Labeller.of(single)  # a single pass
    p = labeller.params
    labeller.load(states[0])
    # the single pass at each rtol measured
    passes = {rtol: Labeller.of(single.with_overrides(rtol=rtol))
              for rtol in [1e-6] + [r for _, r in EVENT_RTOLS]}

    def ours(order, rtol, batch):
        n = len(batch)
        q, st = np.empty(n, np.int16), np.empty(n, np.uint8)
        counts = np.zeros((n, len(COUNTERS)), np.int64)
        start = time.thread_time()
        run_exprb(order, p, rtol, 2.0, batch, q, st, counts)
        return time.thread_time() - start, q, st, counts

    def current(batch, rtol=1e-6):
        start = time.thread_time()
        out = passes[rtol].label(batch)
        return time.thread_time() - start, out

    for _, order, rtol in VARIANTS:
        ours(order, rtol, states[:2])  # compiled before any clock
    timing = {}
    for grid_name, batch in (("bench 8x8", bench_states), (f"label grid {res}x{res}", states)):
        seconds = {name_: [] for name_ in [CURRENT] + [v[0] for v in EVENT_RTOLS + VARIANTS]}
        for _ in range(rounds):  # alternating, so that all meet the same load
            seconds[CURRENT].append(current(batch)[0] / len(batch))
            for name_, rtol in EVENT_RTOLS:
                seconds[name_].append(current(batch, rtol)[0] / len(batch))
            for name_, order, rtol in VARIANTS:
                seconds[name_].append(ours(order, rtol, batch)[0] / len(batch))
        timing[grid_name] = {
            name_: {"ms": 1e3 * statistics.median(v),
                    "ratio_to_current": statistics.median(
                        [a / b for a, b in zip(v, seconds[CURRENT], strict=True)])}
            for name_, v in seconds.items()}
    _, cur = current(states)
    rows = {CURRENT: {"steps_per_throw": float(np.mean(cur.steps)),
                      "wrong_robust": int(((cur.quarter_turns != reference) & robust).sum()),
                      "not_settled": int((cur.status != 0).sum())}}
    for name_, rtol in EVENT_RTOLS:
        _, other = current(states, rtol)
        rows[name_] = {"steps_per_throw": float(np.mean(other.steps)),
                       "wrong_robust": int(((other.quarter_turns != reference) & robust).sum()),
                       "not_settled": int((other.status != 0).sum())}
    for name_, order, rtol in VARIANTS:
        _, q, st, counts = ours(order, rtol, states)
        rows[name_] = {"steps_per_throw": float(np.mean(counts[:, 0] + counts[:, 2])),
                       "wrong_robust": int(((q != reference) & robust).sum()),
                       "not_settled": int((st != 0).sum()),
                       "labels_differ_from_current": int((q != cur.quarter_turns).sum()),
                       "mean_counters": {c: float(np.mean(counts[:, j]))
                                         for j, c in enumerate(COUNTERS)}}
    return {"preset": preset, "grid": f"{res}x{res}", "throws": len(states),
            "robust_cells": int(robust.sum()), "rows": rows, "timing": timing}


ONE_CORNER = 1 << 1  # the mode of the local-error study: corner 1 alone in contact


def local_errors(preset="paper"):
    """What limits the step: the local error of one step of each method from a coin turning on
    one corner 20 um deep, against scipy's DOP853 at rtol 1e-13, for several spins and steps
    (max over components in units of the error scales at rtol 1). The frozen-angle part is
    exact in exprb43; what is left grows with the spin."""
    import numpy as np
    from scipy.integrate import solve_ivp

    from coincli.models import model_params

    p = model_params(scene_of(preset))

    def one_corner_field(t, u):
        return rhs(p, ONE_CORNER, tuple(u), math.cos(u[2]), math.sin(u[2]))

    scales = error_scales(p, 1.0)
    weights = tuple(1.0 / x for x in scales)
    rows = []
    for vphi in (0.0, 10.0, 30.0, 100.0):
        phi = 0.3
        c, s = math.cos(phi), math.sin(phi)
        dy = corner_offset(p, 1, c, s)[1]
        st = (0.0, -dy - 2e-5, phi, 0.1, -0.3, vphi)
        f0 = rhs(p, ONE_CORNER, st, c, s)
        jac = jacobian(p, ONE_CORNER, st, c, s)

        for h in (2.5e-5, 5e-5, 1e-4, 2e-4, 4e-4):
            ref = solve_ivp(one_corner_field, (0.0, h), st, method="DOP853", rtol=1e-13,
                            atol=1e-17).y[:, -1]
            dp = dopri_step(p, ONE_CORNER, h, st, f0, c, s, scales, 1.0)[0]
            e43 = exprb43(p, ONE_CORNER, h, st, f0, jac, c, s, weights)[0]
            e32 = exprb32(p, ONE_CORNER, h, st, f0, jac, c, s, weights)[0]
            err = [float(np.max(np.abs((np.array(x) - ref) / np.array(scales))))
                   for x in (dp, e32, e43)]
            rows.append({"vphi": vphi, "h": h, "h_omega": h * p.omega, "dopri5": err[0],
                         "exprb32": err[1], "exprb43": err[2]})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2, help="for an RK4 reference not stored")
    parser.add_argument("--out", default=str(HERE / "contact-methods.json"))
    parser.add_argument("--coins", default="paper:64,thick:32,soft:24",
                        help="preset:grid resolution, comma-separated")
    args = parser.parse_args()
    local = local_errors()  # plain Python, before compilation
    run_exprb = compile_kernels()
    load = os.getloadavg()
    results = []
    for item in args.coins.split(","):
        preset, res = item.split(":")
        print(f"{preset} {res}x{res} ...", flush=True)
        results.append(measure(preset, int(res), args.rounds, args.threads, run_exprb))
        print(json.dumps(results[-1], indent=1), flush=True)
    out = {"command": "python benchmarks/contact_methods.py " + " ".join(sys.argv[1:]),
           "load_average_start": load, "load_average_end": os.getloadavg(),
           "cpu": platform.processor() or platform.machine(), "results": results,
           "local_errors_paper": local}
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
