"""Switching pairs: an explicit Runge-Kutta pair (:mod:`.dopri` or :mod:`.dop853`) where the
model's law is not stiff, a Rodas5P step (:mod:`.rodas`) where it is. Each fits the adaptive
driver's pair contract, so the driver's events, closed-form flight and settling come with it;
:mod:`.pairs` derives the drivers (``event_rodas`` and ``event_dop853_rodas``).

Why switch per step: a stiff step is needed only where a corner sticks under load (friction,
:mod:`coincli.models.friction`), a small part of a throw. Elsewhere the explicit pair's step is
cheaper (6 or 12 right-hand sides and no Jacobian against 8, a Jacobian and 8 solves) and, for
DOP853, of higher order, which the verification rungs at rtol 1e-8 to 1e-12 need. For a law
without stiffness (the paper's: its ``stiffness`` is 0) a switching pair is its explicit pair.

The test, before each step: h times the law's stiffness bound (the seam's ``stiffness``, at the
step's start) above STIFF5 (Dormand-Prince 5(4)) or STIFF8 (DOP853) takes the Rosenbrock step.
The explicit pairs are stable on the negative real axis up to h lambda = 3.31 and 6.39; near that
bound their error estimate stops seeing the error and their step size oscillates, so the switch
comes before it. A step that fails its error test is retried smaller, and tested again: a corner
that begins to stick inside a step shows at the next one's start.

The stages tuple carries which step was taken (its first element, IMPLICIT or EXPLICIT), so that
the continuous extension is the right one; both are written in the explicit pair's polynomial
form, so one ``dense_point`` serves both. The Rosenbrock step's error norm, of order 5 like
Dormand-Prince's, is handed to DOP853's controller as err^(8/5) (the same test err <= 1, and the
step factor err^(-1/8) of DOP853's controller is then err^(-1/5)).

Measured on the paper's coin with friction (docs/friction.md): a verified throw costs 1.9 (mu
0.1) to 14 (mu 1, v_s 1e-4) times less than with the explicit pairs alone, its certain labels as
often right as without friction.
"""

from __future__ import annotations

from ..jit import kernel
from ..models.interface import stiffness
from . import dop853, dopri
from .dop853 import dense_coefficients as dop853_dense
from .dop853 import step as dop853_step
from .dopri import ZERO
from .dopri import dense_coefficients as dopri_dense
from .dopri import step as dopri_step
from .rodas import dense_coefficients as rodas_dense
from .rodas import step as rodas_step

STIFF5 = 2.0  # h lambda above which the Dormand-Prince 5(4) switching pair steps implicitly
STIFF8 = 4.0  # and the DOP853 one
EXPLICIT = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
IMPLICIT = (1.0, 0.0, 0.0, 0.0, 0.0, 0.0)

ORDER5 = dopri.ORDER
ORDER8 = dop853.ORDER


@kernel(inline=True)
def stiff(p, mode, h, start, c, s, limit):
    """Whether a step of h from ``start`` is past the explicit pair's ``limit`` of h lambda."""
    return h * stiffness(p, mode, start, c, s) > limit


@kernel(inline=True)
def step5(p, mode, h, start, k1, c, s, scales, rtol):
    """Dormand-Prince 5(4), or Rodas5P where the law is stiff; the contract of
    :func:`coincli.integrators.dopri.step`, the stages tagged (module docstring)."""
    if stiff(p, mode, h, start, c, s, STIFF5):
        end, k_end, c1, s1, err, u = rodas_step(p, mode, h, start, k1, c, s, scales, rtol)
        return end, k_end, c1, s1, err, (IMPLICIT, u[0], u[1], u[2], u[3], u[4], u[5], u[6],
                                         u[7])
    end, k_end, c1, s1, err, k = dopri_step(p, mode, h, start, k1, c, s, scales, rtol)
    return end, k_end, c1, s1, err, (EXPLICIT, k[0], k[1], k[2], k[3], k[4], k[5], k[6], ZERO)


@kernel(inline=True)
def dense_coefficients5(p, mode, start, end, h, stages, c, s):
    """The continuous extension of whichever step was taken, in Dormand-Prince's form."""
    if stages[0][0] == 1.0:
        return rodas_dense(p, mode, start, end, h, (
            stages[1], stages[2], stages[3], stages[4], stages[5], stages[6], stages[7],
            stages[8]), c, s)
    return dopri_dense(p, mode, start, end, h, (
        stages[1], stages[2], stages[3], stages[4], stages[5], stages[6], stages[7]), c, s)


@kernel(inline=True)
def step8(p, mode, h, start, k1, c, s, scales, rtol):
    """DOP853, or Rodas5P where the law is stiff (its error norm as err^(8/5), module
    docstring); the contract of :func:`coincli.integrators.dop853.step`."""
    if stiff(p, mode, h, start, c, s, STIFF8):
        end, k_end, c1, s1, err, u = rodas_step(p, mode, h, start, k1, c, s, scales, rtol)
        return end, k_end, c1, s1, err ** 1.6, (IMPLICIT, u[0], u[1], u[2], u[3], u[4], u[5],
                                                u[6], u[7], ZERO)
    end, k_end, c1, s1, err, k = dop853_step(p, mode, h, start, k1, c, s, scales, rtol)
    return end, k_end, c1, s1, err, (EXPLICIT, k[0], k[1], k[2], k[3], k[4], k[5], k[6], k[7],
                                     k[8])


@kernel(inline=True)
def dense_coefficients8(p, mode, start, end, h, stages, c, s):
    """The continuous extension of whichever step was taken, in DOP853's form (Rodas5P's cubic
    in theta (1 - theta) fills its first five terms, the rest zero)."""
    if stages[0][0] == 1.0:
        r0, r1, r2, r3, r4 = rodas_dense(p, mode, start, end, h, (
            stages[1], stages[2], stages[3], stages[4], stages[5], stages[6], stages[7],
            stages[8]), c, s)
        return (r0, r1, r2, r3, r4, ZERO, ZERO, ZERO)
    return dop853_dense(p, mode, start, end, h, (
        stages[1], stages[2], stages[3], stages[4], stages[5], stages[6], stages[7], stages[8],
        stages[9]), c, s)


__all__ = ["IMPLICIT", "EXPLICIT", "ORDER5", "ORDER8", "STIFF5", "STIFF8", "dense_coefficients5",
           "dense_coefficients8", "step5", "step8"]
