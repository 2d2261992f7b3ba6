"""One Dormand-Prince 5(4) step of the coin in a fixed contact mode, its error estimate and its
continuous extension (Hairer's ``contd5``, 4th order).

States and stage derivatives are 6-tuples of floats (x, y, phi, vx, vy, vphi), which numba keeps in
registers: no arrays, no calls in the step (every helper here is inlined). The derivative of the
positions is the stage's velocity; only the accelerations need the model. The cosine and sine of
each stage's angle come from those at the step's start by a small rotation
(:func:`coincli.models.rotation.rotate`), and so are those at its end, which the next step, the
event scan and the energy check start from. The driver takes them from the library once, at the
start of a run, and carries them through flights (:mod:`.flight`) and events (a rotation over the
step, as here): they follow the angle the run computes to within 2e-14 over whole 2 s box throws at
rtol 1e-6 and 1e-10 (measured against the library's cos and sin of that angle at every contact onset
and event), a few of its own rounding units at the tens of radians a throw turns.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import kernel
from ..models.interface import contact_accelerations
from ..models.rotation import rotate

# Dormand-Prince 5(4): rows of the tableau, the 5th-order weights B, the error weights E (5th
# minus 4th order, including the FSAL stage 7) and the dense-output weights D (Hairer, contd5).
A2 = (1.0 / 5.0,)
A3 = (3.0 / 40.0, 9.0 / 40.0)
A4 = (44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0)
A5 = (19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0)
A6 = (9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0)
B = (35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0)
E = (71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0,
     -1.0 / 40.0)
D = (-12715105075.0 / 11282082432.0, 0.0, 87487479700.0 / 32700410799.0,
     -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0,
     -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0)
ORDER = 5
ZERO = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@kernel(inline=True)
def combine(base, h, weights, stages):
    """base + h * sum_i weights[i] * stages[i], on 6-tuples."""
    a0 = a1 = a2 = a3 = a4 = a5 = 0.0
    for i in range(len(weights)):
        w = weights[i]
        k = stages[i]
        a0 += w * k[0]
        a1 += w * k[1]
        a2 += w * k[2]
        a3 += w * k[3]
        a4 += w * k[4]
        a5 += w * k[5]
    return (base[0] + h * a0, base[1] + h * a1, base[2] + h * a2, base[3] + h * a3,
            base[4] + h * a4, base[5] + h * a5)


@kernel(inline=True)
def derivative(p, mode, state, c, s):
    """Time derivative of ``state`` (c, s: cosine and sine of its angle) in contact mode."""
    ax, ay, aphi = contact_accelerations(p, mode, state, c, s)
    return (state[3], state[4], state[5], ax, ay, aphi)


@kernel(inline=True)
def stage(p, mode, start, h, weights, stages, c, s):
    """A stage's state and derivative (the angle's trig by rotation from the start's)."""
    point = combine(start, h, weights, stages)
    cp, sp = rotate(c, s, point[2] - start[2])
    return derivative(p, mode, point, cp, sp)


@kernel(inline=True)
def error_scales(p, rtol):
    """Absolute tolerance per component: rtol times a natural scale of the coin (its half
    diagonal for positions, 1 rad, the speed sqrt(2 g r) gained falling by r)."""
    r = p.r
    v_ref = math.sqrt(2.0 * max(p.g, 1.0) * r)
    return (rtol * r, rtol * r, rtol, rtol * v_ref, rtol * v_ref, rtol * v_ref / r)


@kernel(inline=True)
def step(p, mode, h, start, k1, c, s, scales, rtol):
    """One step of size h from ``start`` (k1 its derivative; c, s the trig of its angle).
    Returns (end state, its derivative k7, cos and sin of its angle, the error norm, the seven
    stage derivatives); the error norm is the RMS of the error estimate over the per-component
    tolerance scales + rtol * |state| (accept when <= 1)."""
    k2 = stage(p, mode, start, h, A2, (k1,), c, s)
    k3 = stage(p, mode, start, h, A3, (k1, k2), c, s)
    k4 = stage(p, mode, start, h, A4, (k1, k2, k3), c, s)
    k5 = stage(p, mode, start, h, A5, (k1, k2, k3, k4), c, s)
    k6 = stage(p, mode, start, h, A6, (k1, k2, k3, k4, k5), c, s)
    end = combine(start, h, B, (k1, k2, k3, k4, k5, k6))
    c7, s7 = rotate(c, s, end[2] - start[2])
    k7 = derivative(p, mode, end, c7, s7)
    stages = (k1, k2, k3, k4, k5, k6, k7)
    error = combine(ZERO, h, E, stages)
    total = 0.0
    for j in range(6):
        tol = scales[j] + rtol * max(abs(start[j]), abs(end[j]))
        total += (error[j] / tol) ** 2
    return end, k7, c7, s7, math.sqrt(total / 6.0), stages


# x^(-1/5) for x = m 2^e: m^(-1/5) on [0.5, 1) from a cubic in m - 3/4 (to 2.5e-4), 2^(-e/5)
# from 2^(-q) and a table of 2^(-r/5), e = 5 q + r
_FIFTH = (-0.24092815, 0.23952843, -0.28218419, 1.059137)
_TWO_FIFTHS = (1.0, 2.0 ** -0.2, 2.0 ** -0.4, 2.0 ** -0.6, 2.0 ** -0.8)
_MANTISSA = (1 << 52) - 1  # the fraction bits of a float64
_HALF = 1022 << 52  # the exponent bits of [0.5, 1)


@kernel(inline=True)
def controller_memory(err):
    """What the step-size controller keeps of an accepted step: nothing. This pair's controller
    looks at the last error only: PI control (as DOP853's, beta 0.01 to 0.04) saved it at most
    0.5 % of its steps on paper box throws at rtol 1e-6, and cost more at beta 0.04."""
    return 1.0


@kernel
def step_factor(err, memory, largest):
    """The factor for the next step, 0.9 err^(-1/ORDER) within [0.2, largest] (err: the error
    norm of the step just tried; memory: unused, see :func:`controller_memory`). err^(-1/5) by
    a short polynomial instead of pow(): it only steers the step size (to 3e-4), and is worth 7 %
    of the run time. The mantissa and exponent (frexp) and the power of two (ldexp) are taken
    from the float's bits, not from libm calls, which were 2 % of a single pass; err is positive
    and normal here (1e-10 <= err, or inf: then the factor is 0.2), so the bits give exactly
    what frexp and ldexp would (tests/test_integrators.py)."""
    if err < 1e-10:
        return largest
    bits = np.float64(err).view(np.int64)
    m = np.int64((bits & _MANTISSA) | _HALF).view(np.float64)  # err = m 2^e, 0.5 <= m < 1
    e = (bits >> 52) - 1022
    q = e // 5
    x = m - 0.75
    root = ((_FIFTH[0] * x + _FIFTH[1]) * x + _FIFTH[2]) * x + _FIFTH[3]
    power = np.int64((1023 - q) << 52).view(np.float64)  # 2^(-q), -7 <= q <= 205
    return min(largest, max(0.2, 0.9 * (root * _TWO_FIFTHS[e - 5 * q]) * power))


@kernel(inline=True)
def dense_coefficients(p, mode, start, end, h, stages, c, s):
    """The five 6-tuples of the continuous extension of an accepted step (p, mode, c, s: unused
    here; a pair whose extension needs more stages takes them, see :mod:`.dop853`)."""
    k1 = stages[0]
    k7 = stages[6]
    r1 = (end[0] - start[0], end[1] - start[1], end[2] - start[2], end[3] - start[3],
          end[4] - start[4], end[5] - start[5])
    r2 = (h * k1[0] - r1[0], h * k1[1] - r1[1], h * k1[2] - r1[2], h * k1[3] - r1[3],
          h * k1[4] - r1[4], h * k1[5] - r1[5])
    r3 = (r1[0] - h * k7[0] - r2[0], r1[1] - h * k7[1] - r2[1], r1[2] - h * k7[2] - r2[2],
          r1[3] - h * k7[3] - r2[3], r1[4] - h * k7[4] - r2[4], r1[5] - h * k7[5] - r2[5])
    return (start, r1, r2, r3, combine(ZERO, h, D, stages))


@kernel
def dense_point(rc, theta):
    """The state at fraction theta of the step, from its dense coefficients."""
    r0, r1, r2, r3, r4 = rc
    u = 1.0 - theta
    return (r0[0] + theta * (r1[0] + u * (r2[0] + theta * (r3[0] + u * r4[0]))),
            r0[1] + theta * (r1[1] + u * (r2[1] + theta * (r3[1] + u * r4[1]))),
            r0[2] + theta * (r1[2] + u * (r2[2] + theta * (r3[2] + u * r4[2]))),
            r0[3] + theta * (r1[3] + u * (r2[3] + theta * (r3[3] + u * r4[3]))),
            r0[4] + theta * (r1[4] + u * (r2[4] + theta * (r3[4] + u * r4[4]))),
            r0[5] + theta * (r1[5] + u * (r2[5] + theta * (r3[5] + u * r4[5]))))


__all__ = ["ORDER", "controller_memory", "dense_coefficients", "dense_point", "derivative",
           "error_scales", "step", "step_factor"]
