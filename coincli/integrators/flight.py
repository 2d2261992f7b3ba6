"""Free flight in closed form, and the next touch-down on it.

Between contacts the centroid flies on a parabola and the coin turns uniformly, so the ``event``
method does not integrate flight: it jumps to the next touch-down. That instant is found by
second-order conservative advancement: each corner's height h obeys h'' >= -(g + vphi^2 r) (gravity,
and the centripetal term of a point at distance r turning at vphi), so h(t + s) >= h + h' s - (g +
vphi^2 r) s^2 / 2, and advancing by the first root of that bound can never step over a contact,
however grazing. Near a transversal root the bound is tight to O(s^2), so convergence is quadratic
(3-5 iterations per flight). The angle's cosine and sine are carried from one iteration to the next
by rotation (:func:`coincli.models.rotation.rotate`, exact to rounding) rather than taken from the
library at each: a box throw's flights iterate about 54 times, and libm's sincos at angles of up to
100 rad was a tenth of a single pass.
"""

from __future__ import annotations

import math

from ..jit import kernel
from ..models.interface import CORNERS, corner_offset
from ..models.rotation import rotate

LANDING_GAP = 1e-14  # m, how close conservative advancement brings a corner before touch-down


@kernel(inline=True)
def flight_state(p, state, tau):
    """The state a time tau into free flight from ``state``."""
    return (state[0] + state[3] * tau, state[1] + (state[4] - 0.5 * p.g * tau) * tau,
            state[2] + state[5] * tau, state[3], state[4] - p.g * tau, state[5])


@kernel
def time_to_touchdown(p, state, c, s, t_max, budget):
    """(tau, touching, iterations, cos, sin): the time until the first corner touches the
    surface in free flight from ``state`` (c, s: the trig of its angle) (t_max if none does
    before), the mask of the corners touching then (0 if none), and the trig of the angle at
    tau if a corner touches (the caller's next contact phase starts from them). A coin landing
    flat touches with two corners at once, and taking only one would add a spurious torque.
    ``budget`` bounds the iterations; a flight that needs more returns touching = 0 and
    tau < t_max."""
    g = p.g
    w = state[5]
    bound = g + w * w * p.r
    tau = 0.0
    for iterations in range(1, budget + 1):
        y = state[1] + (state[4] - 0.5 * g * tau) * tau
        vy = state[4] - g * tau
        advance = math.inf
        touching = 0  # corners on the surface (within LANDING_GAP) and not rising
        lowest = 0
        for i in range(CORNERS):
            dx, dy = corner_offset(p, i, c, s)
            height = y + dy
            rate = vy + w * dx
            if height <= LANDING_GAP and rate <= 0.0:
                touching |= 1 << i
            if height < y + corner_offset(p, lowest, c, s)[1]:
                lowest = i
            above = max(height, 0.0)
            if bound > 0.0:
                sigma = (rate + math.sqrt(rate * rate + 2.0 * bound * above)) / bound
            elif rate < 0.0:
                sigma = above / -rate
            else:
                sigma = math.inf
            advance = min(advance, sigma)
        if touching != 0:
            return tau, touching, iterations, c, s
        if advance < 1e-15:
            # resting on the surface with no downward speed: a touch-down of the lowest corner
            return tau, 1 << lowest, iterations, c, s
        tau += advance
        c, s = rotate(c, s, w * advance)  # the angle's trig carried along, no libm call
        if tau >= t_max:
            return t_max, 0, iterations, c, s
    return tau, 0, budget, c, s


__all__ = ["LANDING_GAP", "flight_state", "time_to_touchdown"]
