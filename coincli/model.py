"""The plane coin model: rigid-body kinematics of the four corners, the Winkler + viscous contact
force on each penetrating corner, the resultant of eq. (6), the total energy, and the count of
quarter turns.

All kernels are numba functions on plain floats and float64 arrays (the parameter vector of
:func:`coincli.params.param_array`), compiled with ``cache=True``.

Corner i sits at body coordinates p_i = (SX[i] r_d, SY[i] r_t); its offset from the centroid is
d_i = R(phi) p_i and its velocity v_i = v + vphi z x d_i = (vx - vphi d_yi, vy + vphi d_xi).
(Eqs. (3)-(4) as printed are not a rigid rotation; see ../shared/paper/NOTES.md.)
"""

from __future__ import annotations

import math

import numpy as np

from .jit import jit
from .params import P_C, P_G, P_INERTIA, P_K, P_MASS, P_R, P_RD, P_RT

# Body-frame signs of the corners: 0 = (+r_d, -r_t), 1 = (-r_d, -r_t), 2 = (-r_d, +r_t),
# 3 = (+r_d, +r_t). With phi = 0 corners 0 and 1 are the lower ones.
SX = (1.0, -1.0, -1.0, 1.0)
SY = (-1.0, -1.0, 1.0, 1.0)
N_CORNERS = 4

@jit
def corner_heights_at(p, y, phi, out):
    """Heights y_i of the four corners (negative = penetrating) written into out[0:4]."""
    c = math.cos(phi)
    s = math.sin(phi)
    for i in range(4):
        out[i] = y + SX[i] * p[P_RD] * s + SY[i] * p[P_RT] * c


@jit
def contact_mask(p, y, phi):
    """Bit mask of the corners below the surface (bit i set = corner i penetrates)."""
    c = math.cos(phi)
    s = math.sin(phi)
    mask = 0
    for i in range(4):
        if y + SX[i] * p[P_RD] * s + SY[i] * p[P_RT] * c < 0.0:
            mask |= 1 << i
    return mask


@jit
def accelerations(p, x, y, phi, vx, vy, vphi, mask):
    """(a_x, a_y, a_phi) with the contact force acting on the corners whose bit is set in mask.

    Each contact corner carries F = (-c v_xi, -k y_i - c v_yi) (eqs. 1-2); the moment is
    M = sum(d_xi F_yi - d_yi F_xi) (eq. 6).
    """
    m = p[P_MASS]
    k = p[P_K]
    damp = p[P_C]
    fx = 0.0
    fy = -m * p[P_G]
    moment = 0.0
    if mask != 0:
        c = math.cos(phi)
        s = math.sin(phi)
        for i in range(4):
            if mask & (1 << i):
                px = SX[i] * p[P_RD]
                py = SY[i] * p[P_RT]
                dx = px * c - py * s
                dy = px * s + py * c
                fxi = -damp * (vx - vphi * dy)
                fyi = -k * (y + dy) - damp * (vy + vphi * dx)
                fx += fxi
                fy += fyi
                moment += dx * fyi - dy * fxi
    return fx / m, fy / m, moment / p[P_INERTIA]


@jit
def accelerations_auto(p, x, y, phi, vx, vy, vphi):
    """Accelerations with the contact set taken from the current penetration (y_i < 0)."""
    return accelerations(p, x, y, phi, vx, vy, vphi, contact_mask(p, y, phi))


@jit
def energies_at(p, y, phi, vx, vy, vphi):
    """(kinetic, gravitational m g y, elastic sum k y_i^2 / 2 over penetrating corners)."""
    m = p[P_MASS]
    kinetic = 0.5 * m * (vx * vx + vy * vy) + 0.5 * p[P_INERTIA] * vphi * vphi
    gravity = m * p[P_G] * y
    c = math.cos(phi)
    s = math.sin(phi)
    elastic = 0.0
    for i in range(4):
        yi = y + SX[i] * p[P_RD] * s + SY[i] * p[P_RT] * c
        if yi < 0.0:
            elastic += 0.5 * p[P_K] * yi * yi
    return kinetic, gravity, elastic


@jit
def energies(p, state):
    return energies_at(p, state[1], state[2], state[3], state[4], state[5])


@jit
def total_energy_at(p, y, phi, vx, vy, vphi):
    kinetic, gravity, elastic = energies_at(p, y, phi, vx, vy, vphi)
    return kinetic + gravity + elastic


@jit
def total_energy(p, state):
    return total_energy_at(p, state[1], state[2], state[3], state[4], state[5])


@jit
def critical_energy(p):
    """E_crit = m g (r - m g / (2 k)): the least total energy with which the coin can balance
    on a corner, i.e. pass from one resting pose to another (NOTES.md)."""
    weight = p[P_MASS] * p[P_G]
    return weight * (p[P_R] - weight / (2.0 * p[P_K]))


@jit
def rounded_quarter_turns(phi):
    """The paper's label n = round(2 phi / pi) (ties away from zero)."""
    q = 2.0 * phi / math.pi
    return int(math.floor(q + 0.5)) if q >= 0 else -int(math.floor(-q + 0.5))


@jit
def well_index(p, phi):
    """Index j of the potential well that holds phi: |phi - j pi/2| < phi_cr for even j (lying),
    |phi - j pi/2| < pi/2 - phi_cr for odd j (standing). Once E < E_crit, j is the final n."""
    phi_cr = math.atan2(p[P_RD], p[P_RT])
    j = rounded_quarter_turns(phi)
    if j % 2 == 0:
        return j
    offset = phi - j * (0.5 * math.pi)
    if abs(offset) < 0.5 * math.pi - phi_cr:
        return j
    return j + 1 if offset > 0 else j - 1


def stiffest_frequency(p: np.ndarray) -> tuple[float, float]:
    """(omega, zeta) of the stiffest contact mode: rocking on the two corners of a lying coin,
    omega = sqrt(2 k r_d^2 / I), with damping ratio zeta = c r_d^2 / (I omega)."""
    omega = math.sqrt(2.0 * p[P_K] * p[P_RD] ** 2 / p[P_INERTIA])
    zeta = p[P_C] * p[P_RD] ** 2 / (p[P_INERTIA] * omega)
    return omega, zeta
