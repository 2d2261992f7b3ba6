"""Coulomb friction at the corners, regularized: the paper's law (:mod:`.paper`) plus, on each
corner below the surface, a tangential force (docs/friction.md)

    N_i  = max(0, -k y_i - c v_yi)                       (the corner's normal force: it never pulls)
    F_ti = -mu N_i v_xi / sqrt(v_xi^2 + v_s^2)           (beside the damper's -c v_xi)

with v_xi = vx - vphi d_yi the corner's horizontal velocity, mu the friction coefficient and v_s
the slip velocity of the regularization (a corner slipping much slower than v_s feels a force
that falls linearly to zero with its speed). Like every horizontal force it turns the coin: the
moment gains -d_yi F_ti.

Friction only takes energy: its power on corner i is F_ti v_xi = -mu N_i v_xi^2 /
sqrt(v_xi^2 + v_s^2) <= 0, so the energy still never rises, and the certificate of a final label
(total energy below E_crit, docs/model.md) holds unchanged.

Where a corner sticks (|v_xi| of the order of v_s under a load N_i) the law is stiff: its
velocity Jacobian has the rank-one term -sigma_i g_i g_i^T, g_i = (1, 0, -d_yi) the direction of
v_xi in (vx, vy, vphi), sigma_i = mu N_i v_s^2 / (v_xi^2 + v_s^2)^(3/2), whose eigenvalue is about
-sigma_i (1/m + d_yi^2 / I): up to 1e6 /s in a hard impact at mu = 1 and v_s = 1e-3 m/s, where
an explicit pair would be held to steps of a microsecond. :func:`stiffness` is that bound; the
switching pairs (:mod:`coincli.integrators.switching`) step implicitly where it times the step
passes their explicit pair's stability, and :func:`step_limit` shortens a step sliding into a
stick (the regularized force has singularities in complex time about v_s / |dv_xi/dt| from the
moment v_xi = 0: an accurate step covers only a fraction of the time left, whatever the method).

This model is the paper's with these names of the seam given anew (:mod:`.interface`); the rest
is the paper's law and the rectangle's geometry (:data:`coincli.models.FRICTION_MODEL`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from ..jit import kernel
from . import paper

# the paper's kernels by name (a kernel set gives each name its own compiled copy: a kernel
# reached through a module's attribute would not be)
from .interface import CORNERS, corner_offset
from .paper import corner_force as paper_force
from .paper import corner_force_gradient as paper_force_gradient
from .paper import corner_push, damping_split, solve_damped_velocity

FRICTION = True
BETA = 0.4  # a step sliding towards a stick covers at most this fraction of the time to it
LAND = 1.0  # a corner slipping slower than LAND v_s sticks already: no more limit
SHORTEST = 0.05  # a normal force falling to zero is landed on unless nearer than this fraction
# of the step (the step then crosses the kink of max(0, N) near its start, where it costs little)


class FrictionParams(NamedTuple):
    """What the kernels know of a scene's physics under the friction law: the paper's
    (:class:`coincli.models.paper.PaperParams`, its fields first and in its order) and
    friction's two constants."""

    mass: float
    inertia: float
    r_d: float
    r_t: float
    k: float
    c: float
    g: float
    r: float
    e_crit: float
    phi_cr: float
    inv_mass: float
    inv_inertia: float
    omega: float
    bounce_factor: float
    decay_time: float
    mu: float  # friction coefficient
    v_s: float  # m/s, the slip velocity of the regularization


def params(scene) -> FrictionParams:
    """The kernels' parameters of ``scene`` (its foundation's mu and slip_velocity)."""
    foundation = scene.foundation
    return FrictionParams(**paper.constants(scene), mu=float(foundation.mu),
                          v_s=float(foundation.slip_velocity))


def stick_rate(p) -> float:
    """The rate (1/s) at which friction brakes the slip of a coin at rest on two corners, the
    larger of lying and standing: its corners push with m g in all, and each one's friction
    falls to zero over a slip of v_s, so the slip relaxes at mu g / v_s (1 + m d_y^2 / I)
    (d_y: r_t lying, r_d standing), the stiff decay mode a fixed step must resolve (a step
    beyond it chatters: `coin accuracy --stability --mu 1 --slip-velocity 1e-4`)."""
    lever = max(p.r_d, p.r_t)
    return p.mu * p.g / p.v_s * (1.0 + p.mass * lever * lever * p.inv_inertia)


@kernel(inline=True)
def friction_force(p, normal, slip):
    """F_t on a corner whose spring and damper push with ``normal`` (-k y_i - c v_yi, of either
    sign) and whose horizontal velocity is ``slip``."""
    if normal <= 0.0:
        return 0.0
    return -p.mu * normal * slip / math.sqrt(slip * slip + p.v_s * p.v_s)


@kernel(inline=True)
def corner_force(p, y, dx, dy, vx, vy, vphi):
    """(F_x, F_y) on a corner in contact: the paper's spring and damper, and friction."""
    fx, fy = paper_force(p, y, dx, dy, vx, vy, vphi)
    return fx + friction_force(p, fy, vx - vphi * dy), fy


@kernel(inline=True)
def corner_force_gradient(p, y, dx, dy, vx, vy, vphi):
    """:func:`corner_force` and its derivatives along (y, phi, vx, vy, vphi): the paper's, and
    friction's d F_t = -mu (phi(w) dN + N phi'(w) dw) where N > 0, w = vx - vphi d_y,
    phi(w) = w / sqrt(w^2 + v_s^2), phi'(w) = v_s^2 / (w^2 + v_s^2)^(3/2),
    dw = (0, -vphi d_x, 1, 0, -d_y). max(0, N) has a kink at N = 0: there the derivative of the
    side the state is on."""
    fx, fy, gx, gy = paper_force_gradient(p, y, dx, dy, vx, vy, vphi)
    if fy <= 0.0:
        return fx, fy, gx, gy
    w = vx - vphi * dy
    vs2 = p.v_s * p.v_s
    q = 1.0 / math.sqrt(w * w + vs2)
    a = -p.mu * w * q  # d F_t / d N
    b = -p.mu * fy * vs2 * q * q * q  # d F_t / d w
    gx = (gx[0] + a * gy[0], gx[1] + a * gy[1] - b * vphi * dx, gx[2] + b, gx[3] + a * gy[3],
          gx[4] + a * gy[4] - b * dy)
    return fx + a * fy, fy, gx, gy


@kernel
def contact_forces(p, state, c, s, i):
    """(F_x, F_y, the normal force max(0, F_y), the friction force) on corner i if it is below
    the surface (zero otherwise)."""
    dx, dy = corner_offset(p, i, c, s)
    if state[1] + dy >= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    fx, fy = paper_force(p, state[1], dx, dy, state[3], state[4], state[5])
    tangential = friction_force(p, fy, state[3] - state[5] * dy)
    return fx + tangential, fy, max(fy, 0.0), tangential


@kernel(inline=True)
def stiffness(p, mode, state, c, s):
    """A bound of friction's stiffness (1/s): over the corners of the mode, sigma_i (1/m +
    d_yi^2 / I), the eigenvalue of its rank-one velocity Jacobian (module docstring); zero where
    no corner pushes."""
    total = 0.0
    if mode != 0:
        y, vx, vy, vphi = state[1], state[3], state[4], state[5]
        vs2 = p.v_s * p.v_s
        for i in range(CORNERS):
            if mode & (1 << i):
                dx, dy = corner_offset(p, i, c, s)
                normal = corner_push(p, y, dx, dy, vy, vphi)
                if normal > 0.0:
                    w = vx - vphi * dy
                    q = 1.0 / math.sqrt(w * w + vs2)
                    total += p.mu * normal * vs2 * q * q * q * (p.inv_mass
                                                               + dy * dy * p.inv_inertia)
    return total


@kernel(inline=True)
def step_limit(p, mode, state, k1, c, s, h):
    """The longest step to try: ``h``, shortened where friction turns sharply ahead
    - a pushing corner sliding towards a stick (v_xi and its rate of opposite signs, |v_xi| >
      LAND v_s): at most BETA of the time to v_xi = 0 at the step's starting rate (the approach
      is geometric whatever the method: module docstring); the error control alone finds that
      fraction by rejecting a step in two;
    - a pushing corner whose normal force falls: landed on where it reaches 0, the kink of
      max(0, N), unless nearer than SHORTEST h.
    Rates from k1 (the derivative at ``state``): d v_xi / dt = a_x - a_phi d_yi - vphi^2 d_xi,
    dN / dt = -k v_yi - c (a_y + a_phi d_xi - vphi^2 d_yi)."""
    if mode == 0:
        return h
    y, vx, vy, vphi = state[1], state[3], state[4], state[5]
    ax, ay, aphi = k1[3], k1[4], k1[5]
    best = h
    for i in range(CORNERS):
        if mode & (1 << i):
            dx, dy = corner_offset(p, i, c, s)
            normal = corner_push(p, y, dx, dy, vy, vphi)
            if normal <= 0.0:
                continue
            w = vx - vphi * dy
            w_rate = ax - aphi * dy - vphi * vphi * dx
            if abs(w) > LAND * p.v_s and w * w_rate < 0.0:
                tau = BETA * abs(w) / abs(w_rate)
                if tau < best:
                    best = tau
            n_rate = -p.k * (vy + vphi * dx) - p.c * (ay + aphi * dx - vphi * vphi * dy)
            if n_rate < 0.0:
                tau = normal / -n_rate
                if SHORTEST * h < tau < best:
                    best = tau
    return best


@kernel
def sliding(p, mode, state, c, s):
    """(the power of the friction forces, <= 0; the sliding load sum of max(0, N_i) |v_xi|)
    over the corners in ``mode``."""
    y, vx, vy, vphi = state[1], state[3], state[4], state[5]
    power = 0.0
    load = 0.0
    for i in range(CORNERS):
        if mode & (1 << i):
            dx, dy = corner_offset(p, i, c, s)
            normal = corner_push(p, y, dx, dy, vy, vphi)
            if normal > 0.0:
                w = vx - vphi * dy
                power += friction_force(p, normal, w) * w
                load += normal * abs(w)
    return power, load


@kernel(inline=True)
def verlet_half_kick(p, h2, state):
    """v_half = v + h2 (a0(q) - D(q) v_half + a_f(q, v)): implicit in the damper (one exact 3x3
    solve, :func:`coincli.models.paper.solve_damped_velocity`), explicit in friction, taken at
    the step's start (friction is not linear in the velocity)."""
    c = math.cos(state[2])
    s = math.sin(state[2])
    y, vx, vy, vphi = state[1], state[3], state[4], state[5]
    fx = 0.0
    moment = 0.0
    for i in range(CORNERS):
        dx, dy = corner_offset(p, i, c, s)
        if y + dy < 0.0:
            tangential = friction_force(p, corner_push(p, y, dx, dy, vy, vphi), vx - vphi * dy)
            fx += tangential
            moment -= dy * tangential
    ay0, aphi0, n, sx, sy, srr = damping_split(p, y, state[2])
    return solve_damped_velocity(p, h2, ay0, aphi0, n, sx, sy, srr, vx + h2 * fx * p.inv_mass,
                                 vy, vphi + h2 * moment * p.inv_inertia)


__all__ = ["BETA", "FRICTION", "FrictionParams", "LAND", "SHORTEST", "contact_forces",
           "corner_force", "corner_force_gradient", "friction_force", "params",
           "sliding", "step_limit", "stick_rate", "stiffness", "verlet_half_kick"]
