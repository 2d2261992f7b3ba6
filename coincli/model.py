"""The plane coin model: rigid-body kinematics of the four corners, the Winkler + viscous contact
force on each penetrating corner, the resultant of eq. (6), the total energy, and the count of
quarter turns (docs/model.md derives each).

All kernels (:func:`coincli.jit.kernel`) work on plain floats and the named tuple of model
parameters ``p`` (:class:`coincli.params.ModelParams`). The geometry and the force law are
written once, here, as small scalar helpers that numba inlines into the integrators and that
also apply, as plain Python, to numpy arrays (the recordings use them so).

Corner i sits at body coordinates p_i = (SX[i] r_d, SY[i] r_t); its offset from the centroid is
d_i = R(phi) p_i and its velocity v_i = v + vphi z x d_i = (vx - vphi d_yi, vy + vphi d_xi).
"""

from __future__ import annotations

import math

from .jit import kernel
from .params import model_params

# Body-frame signs of the corners: 0 = (+r_d, -r_t), 1 = (-r_d, -r_t), 2 = (-r_d, +r_t),
# 3 = (+r_d, +r_t). With phi = 0 corners 0 and 1 are the lower ones.
SX = (1.0, -1.0, -1.0, 1.0)
SY = (-1.0, -1.0, 1.0, 1.0)

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


@kernel(inline=True)
def corner_offset(p, i, c, s):
    """Offset d_i = R(phi) p_i of corner i from the centroid, given c = cos phi, s = sin phi."""
    px = SX[i] * p.r_d
    py = SY[i] * p.r_t
    return px * c - py * s, px * s + py * c


@kernel(inline=True)
def corner_force(p, y, dx, dy, vx, vy, vphi):
    """Contact force (F_x, F_y) on a corner in contact at offset (dx, dy) (eqs. 1-2): the
    Winkler spring on its height y + dy and the damper on its velocity (vx - vphi dy,
    vy + vphi dx)."""
    return -p.c * (vx - vphi * dy), -p.k * (y + dy) - p.c * (vy + vphi * dx)


@kernel
def corner_heights(p, y, c, s):
    """Heights y_i = y + d_yi of the four corners (negative = penetrating)."""
    return (y + corner_offset(p, 0, c, s)[1], y + corner_offset(p, 1, c, s)[1],
            y + corner_offset(p, 2, c, s)[1], y + corner_offset(p, 3, c, s)[1])


@kernel
def below(heights):
    """Bit mask of the corners whose height is negative (bit i set = corner i penetrates)."""
    mask = 0
    for i in range(4):
        if heights[i] < 0.0:
            mask |= 1 << i
    return mask


@kernel(inline=True)
def contact_accelerations(p, mode, y, vx, vy, vphi, c, s):
    """(a_x, a_y, a_phi) with the contact force acting on the corners whose bit is set in
    ``mode`` (whatever their height: the force law extends smoothly beyond the surface), and
    gravity. The moment is M = sum(d_xi F_yi - d_yi F_xi) (eq. 6)."""
    fx = 0.0
    fy = 0.0
    moment = 0.0
    if mode != 0:
        for i in range(4):
            if mode & (1 << i):
                dx, dy = corner_offset(p, i, c, s)
                fxi, fyi = corner_force(p, y, dx, dy, vx, vy, vphi)
                fx += fxi
                fy += fyi
                moment += dx * fyi - dy * fxi
    return fx * p.inv_mass, fy * p.inv_mass - p.g, moment * p.inv_inertia


@kernel(inline=True)
def elastic_energy(p, heights):
    """sum k y_i^2 / 2 over the penetrating corners."""
    total = 0.0
    for i in range(4):
        if heights[i] < 0.0:
            total += heights[i] * heights[i]
    return 0.5 * p.k * total


@kernel
def energy_with_heights(p, y, vx, vy, vphi, heights):
    """Total energy, the corner heights known (kinetic + m g y + elastic)."""
    kinetic = 0.5 * p.mass * (vx * vx + vy * vy) + 0.5 * p.inertia * vphi * vphi
    return kinetic + p.mass * p.g * y + elastic_energy(p, heights)


@kernel
def contact_mask(p, y, phi):
    """Bit mask of the corners below the surface (bit i set = corner i penetrates)."""
    return below(corner_heights(p, y, math.cos(phi), math.sin(phi)))


@kernel
def accelerations(p, x, y, phi, vx, vy, vphi, mask):
    """(a_x, a_y, a_phi) with the contact force on the corners whose bit is set in mask."""
    return contact_accelerations(p, mask, y, vx, vy, vphi, math.cos(phi), math.sin(phi))


@kernel
def accelerations_auto(p, x, y, phi, vx, vy, vphi):
    """Accelerations with the contact set taken from the current penetration (y_i < 0)."""
    c = math.cos(phi)
    s = math.sin(phi)
    return contact_accelerations(p, below(corner_heights(p, y, c, s)), y, vx, vy, vphi, c, s)


@kernel
def energies_at(p, y, phi, vx, vy, vphi):
    """(kinetic, gravitational m g y, elastic sum k y_i^2 / 2 over penetrating corners)."""
    kinetic = 0.5 * p.mass * (vx * vx + vy * vy) + 0.5 * p.inertia * vphi * vphi
    heights = corner_heights(p, y, math.cos(phi), math.sin(phi))
    return kinetic, p.mass * p.g * y, elastic_energy(p, heights)


@kernel
def energies(p, state):
    return energies_at(p, state[1], state[2], state[3], state[4], state[5])


@kernel
def total_energy_at(p, y, phi, vx, vy, vphi):
    heights = corner_heights(p, y, math.cos(phi), math.sin(phi))
    return energy_with_heights(p, y, vx, vy, vphi, heights)


@kernel
def total_energy(p, state):
    return total_energy_at(p, state[1], state[2], state[3], state[4], state[5])


CAP_FACTOR = 4.0  # the cap of a run without a fixed horizon, in units of decision_time


def scene_horizon(scene) -> float:
    """How long a run of ``scene`` from its initial state may last: its t_end, or without one
    the cap, CAP_FACTOR times :func:`decision_time`."""
    s, t_end = scene.initial, scene.integration.t_end
    state = (s.x0, scene.y0, s.phi0, s.vx, s.vy, s.vphi)  # Python floats: an absurd start's
    # energy overflows to inf (an infinite cap) without numpy's overflow warning
    return float(run_horizon(model_params(scene), math.inf if t_end is None else t_end, state))


def horizon_text(scene) -> str:
    """The horizon of ``scene`` as a user reads it: ``t_end = 2 s`` or the cap's rule."""
    if scene.fixed_horizon:
        return f"t_end = {scene.integration.t_end:g} s"
    p = model_params(scene)
    return (f"until decided, capped at {CAP_FACTOR:g} x (the flight its energy allows, "
            f"summed over bounces of restitution {1 - 1 / p.bounce_factor:.3g}"
            f", + {p.decay_time * 1e3:.3g} ms of damping)")


@kernel
def decision_time(p, state):
    """An upper estimate of how long a throw from ``state`` takes to be decided (its energy below
    E_crit), from its physics alone: the free flight its energy allows, E / (m g) - r_t above a
    lying coin's rest (at least the half diagonal r), with every bounce after it shorter by the
    restitution e of a corner on the foundation (all of them: that flight times 1 / (1 - e),
    ``p.bounce_factor``), plus the damping time of rocking on a corner (``p.decay_time``). On
    the paper's coin, the thick one and a coin with t/d = 0.5, the 32 x 32 default basin
    settles within half of it (docs/thickness.md); infinite for an undamped foundation."""
    kinetic = 0.5 * p.mass * (state[3] * state[3] + state[4] * state[4]) \
        + 0.5 * p.inertia * state[5] * state[5]
    rise = max((kinetic + p.mass * p.g * state[1]) / (p.mass * p.g) - p.r_t, p.r)
    return 2.0 * math.sqrt(2.0 * rise / p.g) * p.bounce_factor + p.decay_time


@kernel
def run_horizon(p, t_end, state):
    """How long a run from ``state`` may last: ``t_end`` if the settings fix a horizon, else
    (t_end infinite: run until decided) CAP_FACTOR times :func:`decision_time`."""
    if t_end < math.inf:
        return t_end
    return CAP_FACTOR * decision_time(p, state)


@kernel
def rounded_quarter_turns(phi):
    """The paper's label n = round(2 phi / pi) (ties away from zero)."""
    q = 2.0 * phi / math.pi
    return int(math.floor(q + 0.5)) if q >= 0 else -int(math.floor(-q + 0.5))


@kernel
def well_index(p, phi):
    """Index j of the potential well that holds phi: |phi - j pi/2| < phi_cr for even j (lying),
    |phi - j pi/2| < pi/2 - phi_cr for odd j (standing). Once E < E_crit, j is the final n."""
    j = rounded_quarter_turns(phi)
    if j % 2 == 0:
        return j
    offset = phi - j * (0.5 * math.pi)
    if abs(offset) < 0.5 * math.pi - p.phi_cr:
        return j
    return j + 1 if offset > 0 else j - 1


@kernel
def last_boundary(p, phi_a, phi_b):
    """The last well boundary passed going monotonically from phi_a to phi_b (NaN if none):
    the boundaries between wells are the angles k pi +- phi_cr."""
    if phi_b == phi_a:
        return math.nan
    best = math.nan
    for c in (p.phi_cr, math.pi - p.phi_cr):
        if phi_b > phi_a:
            value = math.floor((phi_b - c) / math.pi) * math.pi + c
            if value > phi_a and not value <= best:
                best = value
        else:
            value = math.ceil((phi_b - c) / math.pi) * math.pi + c
            if value < phi_a and not value >= best:
                best = value
    return best


def stiffest_frequency(p) -> tuple[float, float]:
    """(omega, zeta) of the stiffest contact mode: rocking on the two corners of a lying coin,
    omega = sqrt(2 k r_d^2 / I), with damping ratio zeta = c r_d^2 / (I omega)."""
    omega = math.sqrt(2.0 * p.k * p.r_d ** 2 / p.inertia)
    zeta = p.c * p.r_d ** 2 / (p.inertia * omega)
    return omega, zeta
