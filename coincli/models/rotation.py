"""The cosine and sine of an angle carried along by small rotations (:func:`rotate`): what the
integrators use instead of the library's cos and sin at every stage of a step and every
iteration of a flight. Pure trigonometry, the same for every model."""

from __future__ import annotations

import math

from ..jit import kernel

# Taylor coefficients of cos and sin for a small turn (see rotate)
_C2, _C4, _C6, _C8, _C10, _C12 = (1.0 / 2, 1.0 / 24, 1.0 / 720, 1.0 / 40320, 1.0 / 3628800,
                                  1.0 / 479001600)
_S3, _S5, _S7, _S9, _S11, _S13 = (1.0 / 6, 1.0 / 120, 1.0 / 5040, 1.0 / 362880, 1.0 / 39916800,
                                  1.0 / 6227020800)
TINY_TURN = 0.03  # rad: below it the series to d^6 and d^7 is exact to rounding (next term 2e-17)
SMALL_TURN = 0.3  # rad: below it the series to d^12 and d^13 is (next term 2e-21)


@kernel
def rotate(c, s, d):
    """(cos(phi + d), sin(phi + d)) from c = cos phi, s = sin phi: a rotation by the small turn
    d, its cosine and sine from their Taylor series, evaluated in parallel pieces (Estrin)
    rather than one long chain, since the integrator waits for the result. A few times cheaper
    than the library's cos and sin, and as exact to rounding."""
    a = abs(d)
    d2 = d * d
    d4 = d2 * d2
    if a < TINY_TURN:
        cd = (1.0 - d2 * _C2) + d4 * (_C4 - d2 * _C6)
        sd = d * ((1.0 - d2 * _S3) + d4 * (_S5 - d2 * _S7))
    elif a < SMALL_TURN:
        d8 = d4 * d4
        cd = ((1.0 - d2 * _C2) + d4 * (_C4 - d2 * _C6)
              + d8 * ((_C8 - d2 * _C10) + d4 * _C12))
        sd = d * ((1.0 - d2 * _S3) + d4 * (_S5 - d2 * _S7)
                  + d8 * ((_S9 - d2 * _S11) + d4 * _S13))
    elif a < math.inf:
        cd = math.cos(d)
        sd = math.sin(d)
    else:  # an infinite turn (or NaN): NaN, as compiled code gives, not Python's domain error
        cd = math.nan
        sd = math.nan
    return c * cd - s * sd, s * cd + c * sd


__all__ = ["SMALL_TURN", "TINY_TURN", "rotate"]
