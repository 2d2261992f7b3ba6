"""The plane coin model: rigid-body kinematics of the four corners, the Winkler + viscous contact
force on each penetrating corner, the resultant of eq. (6), the total energy, and the count of
quarter turns.

All kernels (:func:`coincli.jit.kernel`) work on plain floats, float64 arrays and the named
tuple of model parameters ``p`` (:class:`coincli.params.ModelParams`).

Corner i sits at body coordinates p_i = (SX[i] r_d, SY[i] r_t); its offset from the centroid is
d_i = R(phi) p_i and its velocity v_i = v + vphi z x d_i = (vx - vphi d_yi, vy + vphi d_xi).
(Eqs. (3)-(4) as printed are not a rigid rotation; see docs/model.md.)
"""

from __future__ import annotations

import math

from .jit import kernel

# Body-frame signs of the corners: 0 = (+r_d, -r_t), 1 = (-r_d, -r_t), 2 = (-r_d, +r_t),
# 3 = (+r_d, +r_t). With phi = 0 corners 0 and 1 are the lower ones.
SX = (1.0, -1.0, -1.0, 1.0)
SY = (-1.0, -1.0, 1.0, 1.0)
N_CORNERS = 4

@kernel
def corner_heights_at(p, y, phi, out):
    """Heights y_i of the four corners (negative = penetrating) written into out[0:4]."""
    c = math.cos(phi)
    s = math.sin(phi)
    for i in range(4):
        out[i] = y + SX[i] * p.r_d * s + SY[i] * p.r_t * c


@kernel
def corner_offset(p, i, c, s):
    """Offset d_i = R(phi) p_i of corner i from the centroid, given c = cos phi, s = sin phi
    (plain Python on numpy arrays as well: see coincli.jit.python)."""
    px = SX[i] * p.r_d
    py = SY[i] * p.r_t
    return px * c - py * s, px * s + py * c


@kernel
def corner_force(p, y, dx, dy, vx, vy, vphi):
    """Contact force (F_x, F_y) on a corner in contact at offset (dx, dy) (eqs. 1-2): the
    Winkler spring on its height y + dy and the damper on its velocity (vx - vphi dy,
    vy + vphi dx)."""
    return -p.c * (vx - vphi * dy), -p.k * (y + dy) - p.c * (vy + vphi * dx)


@kernel
def contact_mask(p, y, phi):
    """Bit mask of the corners below the surface (bit i set = corner i penetrates)."""
    c = math.cos(phi)
    s = math.sin(phi)
    mask = 0
    for i in range(4):
        if y + SX[i] * p.r_d * s + SY[i] * p.r_t * c < 0.0:
            mask |= 1 << i
    return mask


@kernel
def accelerations(p, x, y, phi, vx, vy, vphi, mask):
    """(a_x, a_y, a_phi) with the contact force acting on the corners whose bit is set in mask.

    Each contact corner carries F = (-c v_xi, -k y_i - c v_yi) (eqs. 1-2); the moment is
    M = sum(d_xi F_yi - d_yi F_xi) (eq. 6).
    """
    m = p.mass
    fx = 0.0
    fy = -m * p.g
    moment = 0.0
    if mask != 0:
        c = math.cos(phi)
        s = math.sin(phi)
        for i in range(4):
            if mask & (1 << i):
                dx, dy = corner_offset(p, i, c, s)
                fxi, fyi = corner_force(p, y, dx, dy, vx, vy, vphi)
                fx += fxi
                fy += fyi
                moment += dx * fyi - dy * fxi
    return fx / m, fy / m, moment / p.inertia


@kernel
def accelerations_auto(p, x, y, phi, vx, vy, vphi):
    """Accelerations with the contact set taken from the current penetration (y_i < 0)."""
    return accelerations(p, x, y, phi, vx, vy, vphi, contact_mask(p, y, phi))


@kernel
def energies_at(p, y, phi, vx, vy, vphi):
    """(kinetic, gravitational m g y, elastic sum k y_i^2 / 2 over penetrating corners)."""
    m = p.mass
    kinetic = 0.5 * m * (vx * vx + vy * vy) + 0.5 * p.inertia * vphi * vphi
    gravity = m * p.g * y
    c = math.cos(phi)
    s = math.sin(phi)
    elastic = 0.0
    for i in range(4):
        yi = y + SX[i] * p.r_d * s + SY[i] * p.r_t * c
        if yi < 0.0:
            elastic += 0.5 * p.k * yi * yi
    return kinetic, gravity, elastic


@kernel
def energies(p, state):
    return energies_at(p, state[1], state[2], state[3], state[4], state[5])


@kernel
def total_energy_at(p, y, phi, vx, vy, vphi):
    kinetic, gravity, elastic = energies_at(p, y, phi, vx, vy, vphi)
    return kinetic + gravity + elastic


@kernel
def total_energy(p, state):
    return total_energy_at(p, state[1], state[2], state[3], state[4], state[5])


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


def stiffest_frequency(p) -> tuple[float, float]:
    """(omega, zeta) of the stiffest contact mode: rocking on the two corners of a lying coin,
    omega = sqrt(2 k r_d^2 / I), with damping ratio zeta = c r_d^2 / (I omega)."""
    omega = math.sqrt(2.0 * p.k * p.r_d ** 2 / p.inertia)
    zeta = p.c * p.r_d ** 2 / (p.inertia * omega)
    return omega, zeta
