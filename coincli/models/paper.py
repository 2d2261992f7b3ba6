"""The paper's contact law: a Winkler spring k and a viscous damper c on each corner below the
surface (eqs. 1-2), the resultant and moment of eq. (6), the energy the foundation stores, and
how long a throw may take to be decided on such a foundation (docs/model.md derives each).

Its parameter tuple :class:`PaperParams` is what the kernels know of a scene's physics: the
coin, the foundation, gravity and the constants that follow from them, computed once from the
scene (:func:`params`), not in every step. The kernels here are written once and apply to
floats (compiled or not) and, as plain Python, to numpy arrays; they reach the cross-section
through the seam (:mod:`.interface`), so another cross-section can reuse this law.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from ..jit import kernel

# law_force: the force on a corner as the model has it (this module's corner_force, or a
# model's that extends the law: coincli.models.friction), so that the sums below serve it too
from .interface import (
    CORNERS,
    below,
    corner_heights,
    corner_offset,
)
from .interface import corner_force as law_force
from .interface import corner_force_gradient as law_force_gradient

FRICTION = False


class PaperParams(NamedTuple):
    """What the kernels know of a scene's physics under the paper's law."""

    mass: float  # kg
    inertia: float  # kg m^2
    r_d: float  # m, half the diameter
    r_t: float  # m, half the thickness
    k: float  # N/m, foundation stiffness per corner
    c: float  # N s/m, damping per corner
    g: float  # m/s^2
    r: float  # m, half diagonal
    e_crit: float  # J, below it the count of quarter turns is final
    phi_cr: float  # rad, the diagonal is vertical
    inv_mass: float  # 1/kg (a product is cheaper than a quotient in every step)
    inv_inertia: float  # 1/(kg m^2)
    omega: float  # rad/s, the stiffest contact mode: rocking on two corners, sqrt(2 k r_d^2 / I)
    bounce_factor: float  # 1 / (1 - e), e the restitution of a corner (decision_time)
    decay_time: float  # s, the damping time of rocking on a corner (I + m r^2) / (c r_d^2)


def constants(scene) -> dict:
    """The fields of :class:`PaperParams` of ``scene`` (a model that extends the law adds its
    own to them)."""
    coin = scene.coin
    k = float(scene.foundation.k)
    return dict(mass=float(coin.mass), inertia=float(coin.inertia), r_d=float(coin.r_d),
                r_t=float(coin.r_t), k=k, c=float(scene.foundation.c), g=float(scene.g),
                r=float(coin.r), e_crit=float(scene.e_crit), phi_cr=float(coin.phi_cr),
                inv_mass=1.0 / coin.mass, inv_inertia=1.0 / coin.inertia,
                omega=math.sqrt(2.0 * k * coin.r_d ** 2 / coin.inertia),
                **_decay(coin, k, float(scene.foundation.c)))


def params(scene) -> PaperParams:
    """The kernels' parameters of ``scene``."""
    return PaperParams(**constants(scene))


def _decay(coin, k: float, c: float) -> dict:
    """The damping constants of :func:`decision_time`: the restitution e of a corner hitting
    the foundation with the whole mass behind it (damping ratio zeta = c / (2 sqrt(k m)), the
    least damped impact) as the sum of its bounces' flight times, 1 / (1 - e), and the damping
    time of rocking on a corner; infinite without damping."""
    if c <= 0 or k <= 0 or coin.mass <= 0:
        return {"bounce_factor": math.inf, "decay_time": math.inf}
    zeta = c / (2.0 * math.sqrt(k * coin.mass))
    # 1 - e, exact for a small zeta (then e rounds to 1); 0 where even that underflows
    loss = -math.expm1(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta)) if zeta < 1 else 1.0
    return {"bounce_factor": 1.0 / loss if loss > 0 else math.inf,
            "decay_time": (coin.inertia + coin.mass * coin.r ** 2) / (c * coin.r_d ** 2)}


def stiffest_frequency(p) -> tuple[float, float]:
    """(omega, zeta) of the stiffest contact mode: rocking on the two corners of a lying coin,
    omega = sqrt(2 k r_d^2 / I), with damping ratio zeta = c r_d^2 / (I omega)."""
    omega = math.sqrt(2.0 * p.k * p.r_d ** 2 / p.inertia)
    zeta = p.c * p.r_d ** 2 / (p.inertia * omega)
    return omega, zeta


def stick_rate(p) -> float:
    """The rate (1/s) of the stiffest decay mode a law adds at rest beside the rocking mode
    (:func:`stiffest_frequency`): none under the paper's law, whose only horizontal force is
    the damper, slower than the rocking (coincli.models.friction has one)."""
    return 0.0


# -- forces -------------------------------------------------------------------------------------
@kernel(inline=True)
def corner_push(p, y, dx, dy, vy, vphi):
    """-k y_i - c v_yi: the vertical force of the spring and damper on a corner in contact at
    offset (dx, dy) (eq. 2), of either sign (a law whose corners never pull takes max(0, it))."""
    return -p.k * (y + dy) - p.c * (vy + vphi * dx)


@kernel(inline=True)
def corner_force(p, y, dx, dy, vx, vy, vphi):
    """Contact force (F_x, F_y) on a corner in contact at offset (dx, dy) (eqs. 1-2): the
    Winkler spring on its height y + dy and the damper on its velocity (vx - vphi dy,
    vy + vphi dx)."""
    return -p.c * (vx - vphi * dy), corner_push(p, y, dx, dy, vy, vphi)


@kernel(inline=True)
def contact_accelerations(p, mode, state, c, s):
    """(a_x, a_y, a_phi) with the contact force acting on the corners whose bit is set in
    ``mode`` (whatever their height: the force law extends smoothly beyond the surface), and
    gravity. The moment is M = sum(d_xi F_yi - d_yi F_xi) (eq. 6)."""
    y, vx, vy, vphi = state[1], state[3], state[4], state[5]
    fx = 0.0
    fy = 0.0
    moment = 0.0
    if mode != 0:
        for i in range(CORNERS):
            if mode & (1 << i):
                dx, dy = corner_offset(p, i, c, s)
                fxi, fyi = law_force(p, y, dx, dy, vx, vy, vphi)
                fx += fxi
                fy += fyi
                moment += dx * fyi - dy * fxi
    return fx * p.inv_mass, fy * p.inv_mass - p.g, moment * p.inv_inertia


@kernel(inline=True)
def corner_force_gradient(p, y, dx, dy, vx, vy, vphi):
    """(F_x, F_y) of :func:`corner_force` and their derivatives along (y, phi, vx, vy, vphi),
    with d d_x / d phi = -d_y and d d_y / d phi = d_x (docs/contact-methods.md)."""
    fx, fy = corner_force(p, y, dx, dy, vx, vy, vphi)
    cc = p.c
    k = p.k
    return (fx, fy, (0.0, cc * vphi * dx, -cc, 0.0, cc * dy),
            (-k, -k * dx + cc * vphi * dy, 0.0, -cc, -cc * dx))


@kernel
def contact_jacobian(p, mode, state, c, s):
    """The derivatives of :func:`contact_accelerations` in the fixed ``mode``: (aq, av), aq =
    d a / d(y, phi) as a 6-tuple by rows (a does not depend on x), av = d a / d(vx, vy, vphi)
    as a 9-tuple by rows; each corner's force and gradient from the law
    (:func:`corner_force_gradient`), its moment d_x F_y - d_y F_x turning with the angle."""
    y, vx, vy, vphi = state[1], state[3], state[4], state[5]
    gx = (0.0, 0.0, 0.0, 0.0, 0.0)
    gy = (0.0, 0.0, 0.0, 0.0, 0.0)
    gm = (0.0, 0.0, 0.0, 0.0, 0.0)
    for i in range(CORNERS):
        if mode & (1 << i):
            dx, dy = corner_offset(p, i, c, s)
            fxi, fyi, ax, ay = law_force_gradient(p, y, dx, dy, vx, vy, vphi)
            gx = (gx[0] + ax[0], gx[1] + ax[1], gx[2] + ax[2], gx[3] + ax[3], gx[4] + ax[4])
            gy = (gy[0] + ay[0], gy[1] + ay[1], gy[2] + ay[2], gy[3] + ay[3], gy[4] + ay[4])
            gm = (gm[0] + dx * ay[0] - dy * ax[0],
                  gm[1] + dx * ay[1] - dy * ax[1] - dy * fyi - dx * fxi,
                  gm[2] + dx * ay[2] - dy * ax[2], gm[3] + dx * ay[3] - dy * ax[3],
                  gm[4] + dx * ay[4] - dy * ax[4])
    im = p.inv_mass
    ii = p.inv_inertia
    aq = (gx[0] * im, gx[1] * im, gy[0] * im, gy[1] * im, gm[0] * ii, gm[1] * ii)
    av = (gx[2] * im, gx[3] * im, gx[4] * im, gy[2] * im, gy[3] * im, gy[4] * im,
          gm[2] * ii, gm[3] * ii, gm[4] * ii)
    return aq, av


@kernel(inline=True)
def stiffness(p, mode, state, c, s):
    """No stiffness beyond the spring's and the damper's, which the explicit pairs follow."""
    return 0.0


@kernel(inline=True)
def step_limit(p, mode, state, k1, c, s, h):
    """No sharp turn of the law ahead of any step: ``h``."""
    return h


@kernel
def sliding(p, mode, state, c, s):
    """(0: no friction, the sliding load sum over the corners in ``mode`` of max(0, N_i)
    |v_xi|, N_i = -k y_i - c v_yi): what a friction coefficient mu would take, about mu times
    it."""
    y, vx, vy, vphi = state[1], state[3], state[4], state[5]
    load = 0.0
    for i in range(CORNERS):
        if mode & (1 << i):
            dx, dy = corner_offset(p, i, c, s)
            normal = corner_push(p, y, dx, dy, vy, vphi)
            if normal > 0.0:
                load += normal * abs(vx - vphi * dy)
    return 0.0, load


@kernel
def accelerations_auto(p, state):
    """Accelerations with the contact set taken from the current penetration (y_i < 0)."""
    c = math.cos(state[2])
    s = math.sin(state[2])
    return contact_accelerations(p, below(corner_heights(p, state[1], c, s)), state, c, s)


@kernel
def contact_forces(p, state, c, s, i):
    """(F_x, F_y, normal, tangential) on corner i: its contact force if it is below the surface
    (zero otherwise); the normal force is F_y, the law has no tangential force but the
    damper's."""
    dx, dy = corner_offset(p, i, c, s)
    if state[1] + dy >= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    fx, fy = law_force(p, state[1], dx, dy, state[3], state[4], state[5])
    return fx, fy, fy, 0.0


@kernel
def damping_split(p, y, phi):
    """The force split as a(q, v) = a0(q) - D(q) v, with D the mass-weighted damping matrix.

    Returns a0 (2 floats: a_y, a_phi; a_x is 0) and n, S_x, S_y, S_rr, the sums over the
    penetrating corners that make C = c sum J_i^T J_i, J_i = [[1, 0, -d_yi], [0, 1, d_xi]]
    (before dividing by the masses)."""
    c = math.cos(phi)
    s = math.sin(phi)
    m = p.mass
    k = p.k
    fy = -m * p.g
    moment = 0.0
    n = 0.0
    sx = 0.0  # sum of d_x over contacts
    sy = 0.0  # sum of d_y
    srr = 0.0  # sum of d_x^2 + d_y^2
    for i in range(CORNERS):
        dx, dy = corner_offset(p, i, c, s)
        yi = y + dy
        if yi < 0.0:
            fyi = -k * yi
            fy += fyi
            moment += dx * fyi
            n += 1.0
            sx += dx
            sy += dy
            srr += dx * dx + dy * dy
    return fy / m, moment / p.inertia, n, sx, sy, srr


@kernel
def solve_damped_velocity(p, h2, ay0, aphi0, n, sx, sy, srr, bx, by, bphi):
    """Solve (M + h2 C) v = M b + h2 M a0 for v, where C = c [[n, 0, -sy], [0, n, sx],
    [-sy, sx, srr]] is the damping matrix of the penetrating corners (linear in v, so the
    implicit half steps of Stormer-Verlet reduce to one 3x3 solve)."""
    m = p.mass
    inertia = p.inertia
    cc = p.c * h2
    # matrix A = M + h2 C
    a11 = m + cc * n
    a22 = m + cc * n
    a33 = inertia + cc * srr
    a13 = -cc * sy
    a23 = cc * sx
    r1 = m * bx
    r2 = m * (by + h2 * ay0)
    r3 = inertia * (bphi + h2 * aphi0)
    # A = [[a11, 0, a13], [0, a22, a23], [a13, a23, a33]]: eliminate by Schur complement.
    s33 = a33 - a13 * a13 / a11 - a23 * a23 / a22
    vphi = (r3 - a13 * r1 / a11 - a23 * r2 / a22) / s33
    vx = (r1 - a13 * vphi) / a11
    vy = (r2 - a23 * vphi) / a22
    return vx, vy, vphi


@kernel(inline=True)
def verlet_half_kick(p, h2, state):
    """v_half = v + h2 (a0(q) - D(q) v_half): implicit in the damping, which is linear in the
    velocity, so one exact 3x3 solve."""
    ay0, aphi0, n, sx, sy, srr = damping_split(p, state[1], state[2])
    return solve_damped_velocity(p, h2, ay0, aphi0, n, sx, sy, srr, state[3], state[4],
                                 state[5])


# -- energy and the horizon ----------------------------------------------------------------------
@kernel(inline=True)
def elastic_energy(p, heights):
    """sum k y_i^2 / 2 over the penetrating corners."""
    total = 0.0
    for i in range(CORNERS):
        if heights[i] < 0.0:
            total += heights[i] * heights[i]
    return 0.5 * p.k * total


@kernel
def energy_with_heights(p, y, vx, vy, vphi, heights):
    """Total energy, the corner heights known (kinetic + m g y + elastic)."""
    kinetic = 0.5 * p.mass * (vx * vx + vy * vy) + 0.5 * p.inertia * vphi * vphi
    return kinetic + p.mass * p.g * y + elastic_energy(p, heights)


@kernel
def energies(p, state):
    """(kinetic, gravitational m g y, elastic sum k y_i^2 / 2 over penetrating corners)."""
    vx, vy, vphi = state[3], state[4], state[5]
    kinetic = 0.5 * p.mass * (vx * vx + vy * vy) + 0.5 * p.inertia * vphi * vphi
    heights = corner_heights(p, state[1], math.cos(state[2]), math.sin(state[2]))
    return kinetic, p.mass * p.g * state[1], elastic_energy(p, heights)


@kernel
def total_energy(p, state):
    """Kinetic + m g y + elastic."""
    heights = corner_heights(p, state[1], math.cos(state[2]), math.sin(state[2]))
    return energy_with_heights(p, state[1], state[3], state[4], state[5], heights)


CAP_FACTOR = 4.0  # the cap of a run without a fixed horizon, in units of decision_time


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


def horizon_rule(p) -> str:
    """The cap of a run without a fixed horizon, as a user reads it."""
    return (f"until decided, capped at {CAP_FACTOR:g} x (the flight its energy allows, "
            f"summed over bounces of restitution {1 - 1 / p.bounce_factor:.3g}"
            f", + {p.decay_time * 1e3:.3g} ms of damping)")


__all__ = ["CAP_FACTOR", "FRICTION", "PaperParams", "accelerations_auto", "constants",
           "contact_accelerations", "contact_forces", "contact_jacobian", "corner_force",
           "corner_force_gradient", "corner_push", "damping_split", "decision_time",
           "elastic_energy", "energies", "energy_with_heights", "horizon_rule", "params",
           "run_horizon", "sliding", "solve_damped_velocity", "step_limit", "stick_rate",
           "stiffest_frequency", "stiffness", "total_energy", "verlet_half_kick"]
