"""One Rodas5P step of the coin in a fixed contact mode (a Rosenbrock method: linearly implicit,
L-stable, order 5 with an embedded order-4 estimate and an order-4 continuous extension;
Steinebach 2023, the tableau of OrdinaryDiffEq.jl), in the style of :mod:`.dopri`, fitting the
adaptive driver's pair contract (``step``, ``dense_coefficients``, ``dense_point``,
``step_factor``, ``controller_memory``, ``ORDER``, ``FIRST_STEP``). The switching pairs
(:mod:`.switching`) take it where a model's law is stiff.

Why: friction that sticks is stiff (:mod:`coincli.models.friction`), and an explicit pair's step is
then held to its stability bound, not its accuracy. A Rosenbrock method solves one linear system per
stage with the Jacobian J of the right-hand side at the step's start, and is stable for any step on
the negative real axis.

The linear algebra is small. For the state u = (q, v), q = (x, y, phi), J = [[0, I], [A_q, A_v]]
with A_q and A_v the derivatives of the accelerations (the model's ``contact_jacobian``; A_q's x
column is zero). A stage solves (I - h gamma J) U = b, b = (b_q, b_v):
    U_q = b_q + h gamma U_v,   (I - h gamma A_v - (h gamma)^2 A_q) U_v = b_v + h gamma A_q b_q,
one 3 x 3 system, whose inverse is formed once per step (:func:`velocity_inverse`).

Hairer's form of the stages, with U_i the stage increments (no Jacobian-vector products):
    (I - h gamma J) U_i = h gamma f(u_0 + sum_j a_ij U_j) + gamma sum_j C_ij U_j,
stages 6 to 8 are evaluated at u_0 + sum a_6j U_j + U_6 + ... (stiffly accurate), the step's
end is u_0 + sum a_6j U_j + U_6 + U_7 + U_8 and its error estimate U_8. The step's end costs one
more right-hand side (the driver's first-same-as-last k1 of the next step): 8 right-hand sides,
one Jacobian, one 3 x 3 inverse and 8 solves a step.
"""

from __future__ import annotations

import math

from ..jit import kernel
from ..models.interface import contact_accelerations, contact_jacobian
from ..models.rotation import rotate
from .dopri import ZERO, combine, dense_point, step_factor  # noqa: F401 - the pair contract's

GAMMA = 0.21193756319429014
# a_ij: the stage points, u_0 + sum_j a_ij U_j (stages 2 to 6)
A2 = (3.0,)
A3 = (2.849394379747939, 0.45842242204463923)
A4 = (-6.954028509809101, 2.489845061869568, -10.358996098473584)
A5 = (2.8029986275628964, 0.5072464736228206, -0.3988312541770524, -0.04721187230404641)
A6 = (-7.502846399306121, 2.561846144803919, -11.627539656261098, -0.18268767659942256,
      0.030198172008377946)
# C_ij: the coupling of the stage increments, times gamma (see the module docstring)
_C = ((-14.155112264123755,),
      (-17.97296035885952, -2.859693295451294),
      (147.12150275711716, -1.41221402718213, 71.68940251302358),
      (165.43517024871676, -0.4592823456491126, 42.90938336958603, -5.961986721573306),
      (24.854864614690072, -3.0009227002832186, 47.4931110020768, 5.5814197821558125,
       -0.6610691825249471),
      (30.91273214028599, -3.1208243349937974, 77.79954646070892, 34.28646028294783,
       -19.097331116725623, -28.087943162872662),
      (37.80277123390563, -3.2571969029072276, 112.26918849496327, 66.9347231244047,
       -40.06618937091002, -54.66780262877968, -9.48861652309627))
GC2, GC3, GC4, GC5, GC6, GC7, GC8 = (tuple(GAMMA * v for v in row) for row in _C)
# the continuous extension: u(theta) = (1 - theta) u_0 + theta (u_1 + (1 - theta) (K1 + theta
# (K2 + theta K3))), K_r = sum_j H_rj U_j
H1 = (25.948786856663858, -2.5579724845846235, 10.433815404888879, -2.3679251022685204,
      0.524948541321073, 1.1241088310450404, 0.4272876194431874, -0.17202221070155493)
H2 = (-9.91568850695171, -0.9689944594115154, 3.0438037242978453, -24.495224566215796,
      20.176138334709044, 15.98066361424651, -6.789040303419874, -6.710236069923372)
H3 = (11.419903575922262, 2.8879645146136994, 72.92137995996029, 80.12511834622643,
      -52.072871366152654, -59.78993625266729, -0.15582684282751913, 4.883087185713722)
# dense_point and step_factor are Dormand-Prince's: the continuous extension is written in its
# polynomial form (dense_coefficients), and the step-size rule err^(-1/5) suits an order-5(4) pair
ORDER = 5
FIRST_STEP = 0.5  # the first step of a contact phase at rtol 1e-6, in units of 1 / omega


@kernel(inline=True)
def velocity_inverse(p, mode, start, c, s, hg):
    """(inverse of I - hg A_v - hg^2 A_q as a 9-tuple by rows, A_q's (y, phi) columns as a
    6-tuple): what every stage's solve needs, from the Jacobian at ``start``."""
    aq, av = contact_jacobian(p, mode, start, c, s)
    hg2 = hg * hg
    m00 = 1.0 - hg * av[0]
    m01 = -hg * av[1] - hg2 * aq[0]
    m02 = -hg * av[2] - hg2 * aq[1]
    m10 = -hg * av[3]
    m11 = 1.0 - hg * av[4] - hg2 * aq[2]
    m12 = -hg * av[5] - hg2 * aq[3]
    m20 = -hg * av[6]
    m21 = -hg * av[7] - hg2 * aq[4]
    m22 = 1.0 - hg * av[8] - hg2 * aq[5]
    c00 = m11 * m22 - m12 * m21
    c01 = m12 * m20 - m10 * m22
    c02 = m10 * m21 - m11 * m20
    inv_det = 1.0 / (m00 * c00 + m01 * c01 + m02 * c02)
    inverse = (c00 * inv_det, (m02 * m21 - m01 * m22) * inv_det, (m01 * m12 - m02 * m11) * inv_det,
               c01 * inv_det, (m00 * m22 - m02 * m20) * inv_det, (m02 * m10 - m00 * m12) * inv_det,
               c02 * inv_det, (m01 * m20 - m00 * m21) * inv_det, (m00 * m11 - m01 * m10) * inv_det)
    return inverse, aq


@kernel(inline=True)
def solve(lin, hg, b):
    """U with (I - hg J) U = b (b a 6-tuple; lin from :func:`velocity_inverse`)."""
    inverse, aq = lin
    r0 = b[3] + hg * (aq[0] * b[1] + aq[1] * b[2])
    r1 = b[4] + hg * (aq[2] * b[1] + aq[3] * b[2])
    r2 = b[5] + hg * (aq[4] * b[1] + aq[5] * b[2])
    u0 = inverse[0] * r0 + inverse[1] * r1 + inverse[2] * r2
    u1 = inverse[3] * r0 + inverse[4] * r1 + inverse[5] * r2
    u2 = inverse[6] * r0 + inverse[7] * r1 + inverse[8] * r2
    return (b[0] + hg * u0, b[1] + hg * u1, b[2] + hg * u2, u0, u1, u2)


@kernel(inline=True)
def slope(p, mode, point, start, c, s):
    """The right-hand side at ``point`` (its angle's trig by rotation from ``start``'s)."""
    cp, sp = rotate(c, s, point[2] - start[2])
    ax, ay, aphi = contact_accelerations(p, mode, point, cp, sp)
    return (point[3], point[4], point[5], ax, ay, aphi)


@kernel(inline=True)
def rosenbrock_stage(p, mode, lin, hg, point, start, c, s, weights, increments):
    """U_i: solve (I - hg J) U_i = hg f(point) + sum_j weights[j] increments[j]."""
    return solve(lin, hg, _rhs(hg, slope(p, mode, point, start, c, s), weights, increments))


@kernel(inline=True)
def _rhs(hg, f, weights, increments):
    """hg f + sum_j weights[j] increments[j] (6-tuples)."""
    return combine((hg * f[0], hg * f[1], hg * f[2], hg * f[3], hg * f[4], hg * f[5]), 1.0,
                   weights, increments)


@kernel(inline=True)
def rodas_increments(p, mode, h, start, k1, c, s):
    """The eight stage increments of a step of size h from ``start`` (k1: f there), and the
    step's end before its last increment (u_0 + sum a_6j U_j + U_6 + U_7)."""
    hg = h * GAMMA
    lin = velocity_inverse(p, mode, start, c, s, hg)
    u1 = solve(lin, hg, (hg * k1[0], hg * k1[1], hg * k1[2], hg * k1[3], hg * k1[4],
                         hg * k1[5]))
    u2 = rosenbrock_stage(p, mode, lin, hg, combine(start, 1.0, A2, (u1,)), start, c, s, GC2,
                          (u1,))
    u3 = rosenbrock_stage(p, mode, lin, hg, combine(start, 1.0, A3, (u1, u2)), start, c, s,
                          GC3, (u1, u2))
    u4 = rosenbrock_stage(p, mode, lin, hg, combine(start, 1.0, A4, (u1, u2, u3)), start, c, s,
                          GC4, (u1, u2, u3))
    u5 = rosenbrock_stage(p, mode, lin, hg, combine(start, 1.0, A5, (u1, u2, u3, u4)), start, c,
                          s, GC5, (u1, u2, u3, u4))
    point = combine(start, 1.0, A6, (u1, u2, u3, u4, u5))
    u6 = rosenbrock_stage(p, mode, lin, hg, point, start, c, s, GC6, (u1, u2, u3, u4, u5))
    point = combine(point, 1.0, (1.0,), (u6,))
    u7 = rosenbrock_stage(p, mode, lin, hg, point, start, c, s, GC7, (u1, u2, u3, u4, u5, u6))
    point = combine(point, 1.0, (1.0,), (u7,))
    u8 = rosenbrock_stage(p, mode, lin, hg, point, start, c, s, GC8,
                          (u1, u2, u3, u4, u5, u6, u7))
    return point, (u1, u2, u3, u4, u5, u6, u7, u8)


@kernel(inline=True)
def error_norm(start, end, error, scales, rtol):
    """RMS of ``error`` over the tolerance scales + rtol |state| (as the Dormand-Prince pair)."""
    total = 0.0
    for j in range(6):
        tol = scales[j] + rtol * max(abs(start[j]), abs(end[j]))
        total += (error[j] / tol) ** 2
    return math.sqrt(total / 6.0)


@kernel  # a function of its own, called: a stiff step is rare, and inlined into every
# switching driver it would compile anew in each (minutes of compilation)
def step(p, mode, h, start, k1, c, s, scales, rtol):
    """One Rodas5P step of size h; the contract of :func:`coincli.integrators.dopri.step`
    (end, its derivative, its angle's cos and sin, the error norm, the stages: here the eight
    increments, which the continuous extension combines)."""
    before, increments = rodas_increments(p, mode, h, start, k1, c, s)
    u8 = increments[7]
    end = combine(before, 1.0, (1.0,), (u8,))
    c1, s1 = rotate(c, s, end[2] - start[2])
    ax, ay, aphi = contact_accelerations(p, mode, end, c1, s1)
    k_end = (end[3], end[4], end[5], ax, ay, aphi)
    return end, k_end, c1, s1, error_norm(start, end, u8, scales, rtol), increments


@kernel(inline=True)
def controller_memory(err):
    """Nothing: the next step is sized from the last error alone (as Dormand-Prince 5(4))."""
    return 1.0


@kernel
def dense_coefficients(p, mode, start, end, h, stages, c, s):
    """The continuous extension in Dormand-Prince's form (:func:`dense_point`): with
    K_r = sum H_rj U_j, u(theta) = u_0 + theta (u_1 - u_0 + (1 - theta) (K1 + theta (K2 +
    theta K3))) = r0 + theta (r1 + (1 - theta) (r2 + theta (r3 + (1 - theta) r4))) for
    r2 = K1, r3 = K2 + K3, r4 = -K3."""
    k1 = combine(ZERO, 1.0, H1, stages)
    k2 = combine(ZERO, 1.0, H2, stages)
    k3 = combine(ZERO, 1.0, H3, stages)
    r1 = (end[0] - start[0], end[1] - start[1], end[2] - start[2], end[3] - start[3],
          end[4] - start[4], end[5] - start[5])
    return (start, r1, k1, combine(k2, 1.0, (1.0,), (k3,)),
            (-k3[0], -k3[1], -k3[2], -k3[3], -k3[4], -k3[5]))


__all__ = ["FIRST_STEP", "ORDER", "controller_memory", "dense_coefficients", "dense_point", "step",
           "step_factor"]
