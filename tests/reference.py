"""A slow, plainly correct pure-Python reference of the plane coin model.

Written from the model's definition (NOTES.md, rigid-body kinematics), not from the kernels:

* corner i sits at body coordinates p_i = (SX[i] r_d, SY[i] r_t) (same corner order as
  coincli.models.rectangle: 0 = (+,-), 1 = (-,-), 2 = (-,+), 3 = (+,+));
* its offset from the centroid is d_i = R(phi) p_i, its height y_i = y + d_yi;
* its velocity is v_i = (vx - vphi d_yi, vy + vphi d_xi);
* a penetrating corner (y_i < 0) carries F_i = (-c v_xi, -k y_i - c v_yi);
* the resultant is sum F_i + (0, -m g), the moment M = sum(d_xi F_yi - d_yi F_xi);
* total energy = kinetic + m g y + sum k y_i^2 / 2 over penetrating corners.

Everything works on plain Python floats and tuples. The steppers follow the same update order as
coincli/integrators/fixed.py so that a fixed-step run can be compared to rounding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

SX = (1.0, -1.0, -1.0, 1.0)
SY = (-1.0, -1.0, 1.0, 1.0)


@dataclass(frozen=True)
class Params:
    m: float
    inertia: float
    r_d: float
    r_t: float
    k: float
    c: float
    g: float

    @property
    def r(self) -> float:
        return math.hypot(self.r_d, self.r_t)

    @property
    def phi_cr(self) -> float:
        return math.atan2(self.r_d, self.r_t)

    @property
    def e_crit(self) -> float:
        w = self.m * self.g
        return w * (self.r - w / (2.0 * self.k))

    @classmethod
    def from_scene(cls, scene) -> Params:
        return cls(m=scene.coin.mass, inertia=scene.coin.inertia, r_d=scene.coin.diameter / 2,
                   r_t=scene.coin.thickness / 2, k=scene.foundation.k, c=scene.foundation.c,
                   g=scene.g)


PAPER = Params(m=math.pi * 1e-3, inertia=7.06e-8, r_d=0.01, r_t=0.001, k=1.0e4, c=0.5, g=9.81)


def offsets(P: Params, phi: float) -> list[tuple[float, float]]:
    """d_i = R(phi) p_i for the four corners."""
    c, s = math.cos(phi), math.sin(phi)
    out = []
    for i in range(4):
        px, py = SX[i] * P.r_d, SY[i] * P.r_t
        out.append((c * px - s * py, s * px + c * py))
    return out


def heights(P: Params, y: float, phi: float) -> list[float]:
    return [y + dy for _, dy in offsets(P, phi)]


def penetrating(P: Params, y: float, phi: float) -> list[int]:
    return [i for i, h in enumerate(heights(P, y, phi)) if h < 0.0]


def mask(P: Params, y: float, phi: float) -> int:
    return sum(1 << i for i in penetrating(P, y, phi))


def forces(P: Params, state, contacts=None) -> tuple[float, float, float]:
    """(F_x, F_y, M) on the coin: gravity plus the contact force of every penetrating corner
    (or, if ``contacts`` is given, of the corners in that collection whatever their height: the
    force law extended beyond the surface, as an event-locating integrator uses it)."""
    _, y, phi, vx, vy, vphi = state
    fx, fy, moment = 0.0, -P.m * P.g, 0.0
    for i, (dx, dy) in enumerate(offsets(P, phi)):
        yi = y + dy
        if (yi < 0.0) if contacts is None else (i in contacts):
            vxi = vx - vphi * dy
            vyi = vy + vphi * dx
            fxi = -P.c * vxi
            fyi = -P.k * yi - P.c * vyi
            fx += fxi
            fy += fyi
            moment += dx * fyi - dy * fxi
    return fx, fy, moment


def accelerations(P: Params, state, contacts=None) -> tuple[float, float, float]:
    fx, fy, moment = forces(P, state, contacts)
    return fx / P.m, fy / P.m, moment / P.inertia


def energies(P: Params, state) -> tuple[float, float, float]:
    """(kinetic, gravitational, elastic)."""
    _, y, phi, vx, vy, vphi = state
    kinetic = 0.5 * P.m * (vx * vx + vy * vy) + 0.5 * P.inertia * vphi * vphi
    elastic = sum(0.5 * P.k * h * h for h in heights(P, y, phi) if h < 0.0)
    return kinetic, P.m * P.g * y, elastic


def total_energy(P: Params, state) -> float:
    return sum(energies(P, state))


def rhs(P: Params, state, contacts=None) -> list[float]:
    ax, ay, aphi = accelerations(P, state, contacts)
    return [state[3], state[4], state[5], ax, ay, aphi]


# -- fixed-step integrators, same update order as coincli/integrators/fixed.py ---------------------

def step_symplectic_euler(P: Params, h: float, state):
    x, y, phi, vx, vy, vphi = state
    ax, ay, aphi = accelerations(P, state)
    vx += h * ax
    vy += h * ay
    vphi += h * aphi
    return (x + h * vx, y + h * vy, phi + h * vphi, vx, vy, vphi)


def rk4_step(P, h: float, state, accelerations_of):
    """One classical RK4 step of the equations of motion whose accelerations (ax, ay, aphi) at a
    state are ``accelerations_of(P, state)`` (this module's laws, in CPython or compiled)."""
    x, y, phi, vx, vy, vphi = state
    h2 = 0.5 * h
    a1 = accelerations_of(P, state)
    s2 = (x + h2 * vx, y + h2 * vy, phi + h2 * vphi,
          vx + h2 * a1[0], vy + h2 * a1[1], vphi + h2 * a1[2])
    a2 = accelerations_of(P, s2)
    s3 = (x + h2 * s2[3], y + h2 * s2[4], phi + h2 * s2[5],
          vx + h2 * a2[0], vy + h2 * a2[1], vphi + h2 * a2[2])
    a3 = accelerations_of(P, s3)
    s4 = (x + h * s3[3], y + h * s3[4], phi + h * s3[5],
          vx + h * a3[0], vy + h * a3[1], vphi + h * a3[2])
    a4 = accelerations_of(P, s4)
    h6 = h / 6.0
    return (x + h6 * (vx + 2.0 * s2[3] + 2.0 * s3[3] + s4[3]),
            y + h6 * (vy + 2.0 * s2[4] + 2.0 * s3[4] + s4[4]),
            phi + h6 * (vphi + 2.0 * s2[5] + 2.0 * s3[5] + s4[5]),
            vx + h6 * (a1[0] + 2.0 * a2[0] + 2.0 * a3[0] + a4[0]),
            vy + h6 * (a1[1] + 2.0 * a2[1] + 2.0 * a3[1] + a4[1]),
            vphi + h6 * (a1[2] + 2.0 * a2[2] + 2.0 * a3[2] + a4[2]))


def step_rk4(P: Params, h: float, state):
    return rk4_step(P, h, state, accelerations)


STEPPERS = {"symplectic_euler": step_symplectic_euler, "rk4": step_rk4}


def integrate(P: Params, method: str, state, h: float, n_steps: int, every: int = 0):
    """n_steps fixed steps; returns the final state (and the list of every ``every``-th state,
    starting with the initial one, if every > 0)."""
    step = STEPPERS[method]
    s = tuple(float(v) for v in state)
    kept = [s]
    for n in range(1, n_steps + 1):
        s = step(P, h, s)
        if every and n % every == 0:
            kept.append(s)
    return (s, kept) if every else s


# -- an independent reference: scipy with located contact events -----------------------------

def _height_event(P: Params, i: int, rising: bool):
    """Terminal event: corner i's height crossing 0 upwards (a lift-off) or downwards."""
    def ev(_t, z):
        return z[1] + offsets(P, z[2])[i][1]
    ev.terminal = True
    ev.direction = 1.0 if rising else -1.0
    return ev


CONTACT_MAX_STEP = 1e-6  # s


def solve_ivp_reference(P: Params, state, t_end: float, t_eval=(), method: str = "DOP853",
                        rtol: float = 1e-12):
    """An independent reference: scipy's solve_ivp with the contact set held fixed between
    events (terminal events on the corner heights: a free corner falling through 0, a contact
    corner rising through 0), restarted at each event, so that no step straddles a jump.

    Event functions are only looked at between steps, so a corner that grazes the surface and
    comes back within one step would be missed: while any corner is in contact, steps are
    capped at ``CONTACT_MAX_STEP`` (a graze of a corner while the coin spins on another lasts
    tens of microseconds). Flight steps are not capped, so a fast-spinning coin could dip a
    corner unseen there; the throws compared with this reference land in clear impacts, and
    flights are checked separately against a brute-force scan (tests/test_integrators.py).

    Returns (samples at the times t_eval as an array len(t_eval) x 6, the final state, the list
    of events (t, corner, +1 onset / -1 lift-off))."""
    import numpy as np
    from scipy.integrate import solve_ivp

    atol = np.array([P.r, P.r, 1.0, 1.0, 1.0, 1.0 / P.r]) * rtol
    t_eval = np.asarray(t_eval, dtype=float)
    out = np.full((t_eval.size, 6), np.nan)
    t, s = 0.0, np.array(state, dtype=float)
    hs = heights(P, s[1], s[2])
    contacts = {i for i in range(4) if hs[i] < 0.0}
    events_found = []
    while t < t_end:
        frozen = frozenset(contacts)
        evs = [_height_event(P, i, rising=i in frozen) for i in range(4)]
        sel = (t_eval >= t) & (t_eval <= t_end)
        sol = solve_ivp(lambda _t, z, c=frozen: rhs(P, z, c), (t, t_end), s, method=method,
                        rtol=rtol, atol=atol, events=evs, dense_output=True,
                        max_step=CONTACT_MAX_STEP if frozen else np.inf)
        if sol.status == 1:
            k = min((j for j in range(4) if len(sol.t_events[j])),
                    key=lambda j: sol.t_events[j][0])
            t_new = float(sol.t_events[k][0])
            s_new = np.array(sol.y_events[k][0])
        else:
            t_new, s_new = t_end, sol.y[:, -1]
        sel &= t_eval <= t_new
        if sel.any():
            out[sel] = sol.sol(t_eval[sel]).T
        if sol.status == 1:
            kind = -1 if k in contacts else 1
            contacts ^= {k}
            events_found.append((t_new, k, kind))
        t, s = t_new, s_new
    return out, s, events_found


# -- friction at the corners ----------------------------------------------------------------------
#
# The law of coincli.models.friction, written from its definition (issue 47), not from the kernels:
# a corner below the surface (y_i < 0) carries the paper's spring and damper and, beside the
# damper's -c v_xi, regularized Coulomb friction
#
#     N_i  = max(0, -k y_i - c v_yi)                   (the normal force: it never pulls)
#     F_ti = -mu N_i v_xi / sqrt(v_xi^2 + v_s^2)
#
# so F_i = (-c v_xi + F_ti, -k y_i - c v_yi) (the vertical force is the paper's, of either sign),
# and the moment gains -d_yi F_ti like that of every horizontal force.
#
# Written in the part of Python that numba compiles as well (floats, tuples, a NamedTuple of
# parameters, loops): CPython runs it for a few states and short runs, and
# :func:`compiled_friction` compiles the same source (with numba alone, none of coincli) for
# whole throws at a small fixed step, which CPython would take hours over.

class FrictionParams(NamedTuple):
    m: float
    inertia: float
    r_d: float
    r_t: float
    k: float
    c: float
    g: float
    mu: float
    v_s: float  # m/s, the slip velocity of the regularization
    e_crit: float  # J, below it the count of quarter turns is final (the energy never rises)
    phi_cr: float  # rad, the diagonal vertical

    @property
    def r(self) -> float:
        return math.hypot(self.r_d, self.r_t)

    @classmethod
    def from_scene(cls, scene) -> FrictionParams:
        P = Params.from_scene(scene)
        return cls(m=P.m, inertia=P.inertia, r_d=P.r_d, r_t=P.r_t, k=P.k, c=P.c, g=P.g,
                   mu=float(scene.foundation.mu), v_s=float(scene.foundation.slip_velocity),
                   e_crit=P.e_crit, phi_cr=P.phi_cr)


NO_LABEL = -32768  # the label of a throw that did not settle
SETTLED, UNSETTLED, NONFINITE = 0, 1, 2


def friction_tangential_force(P, vertical, vxi):
    """F_ti of a corner whose spring and damper push with ``vertical`` (-k y_i - c v_yi) and
    which slips at vxi: N_i = max(0, vertical), no friction where the foundation would pull."""
    if vertical <= 0.0:
        return 0.0
    return -P.mu * vertical * vxi / math.sqrt(vxi * vxi + P.v_s * P.v_s)


def friction_corner_force(P, yi, vxi, vyi):
    """(F_x, F_y) on a corner at height yi (below the surface) moving at (vxi, vyi)."""
    vertical = -P.k * yi - P.c * vyi
    return -P.c * vxi + friction_tangential_force(P, vertical, vxi), vertical


def friction_forces(P, state, mask=-1):
    """(F_x, F_y, M) on the coin: gravity and the forces of the corners below the surface, or
    (``mask`` >= 0) of the corners whose bit is set, whatever their height."""
    y, phi, vx, vy, vphi = state[1], state[2], state[3], state[4], state[5]
    c, s = math.cos(phi), math.sin(phi)
    fx, fy, moment = 0.0, -P.m * P.g, 0.0
    for i in range(4):
        px, py = SX[i] * P.r_d, SY[i] * P.r_t
        dx, dy = c * px - s * py, s * px + c * py
        yi = y + dy
        if (yi < 0.0) if mask < 0 else ((mask >> i) & 1 == 1):
            fxi, fyi = friction_corner_force(P, yi, vx - vphi * dy, vy + vphi * dx)
            fx += fxi
            fy += fyi
            moment += dx * fyi - dy * fxi
    return fx, fy, moment


def friction_accelerations(P, state, mask=-1):
    fx, fy, moment = friction_forces(P, state, mask)
    return fx / P.m, fy / P.m, moment / P.inertia


def friction_tangential(P, state, i):
    """The friction force F_ti on corner i (0 above the surface)."""
    y, phi, vx, vy, vphi = state[1], state[2], state[3], state[4], state[5]
    c, s = math.cos(phi), math.sin(phi)
    px, py = SX[i] * P.r_d, SY[i] * P.r_t
    dx, dy = c * px - s * py, s * px + c * py
    if y + dy >= 0.0:
        return 0.0
    return friction_tangential_force(P, -P.k * (y + dy) - P.c * (vy + vphi * dx), vx - vphi * dy)


def friction_energy(P, state):
    """Kinetic + m g y + sum k y_i^2 / 2 over the corners below the surface (friction stores
    nothing)."""
    y, phi, vx, vy, vphi = state[1], state[2], state[3], state[4], state[5]
    c, s = math.cos(phi), math.sin(phi)
    elastic = 0.0
    for i in range(4):
        yi = y + s * SX[i] * P.r_d + c * SY[i] * P.r_t
        if yi < 0.0:
            elastic += 0.5 * P.k * yi * yi
    return (0.5 * P.m * (vx * vx + vy * vy) + 0.5 * P.inertia * vphi * vphi + P.m * P.g * y
            + elastic)


def friction_well(P, phi):
    """The well that holds phi once the energy is below E_crit (NOTES.md): j = round(2 phi / pi)
    (ties away from zero) if j is even (lying, |phi - j pi/2| < phi_cr) or phi is within
    pi/2 - phi_cr of j pi/2 (standing); else the lying well beside it."""
    q = 2.0 * phi / math.pi
    j = int(math.floor(q + 0.5)) if q >= 0.0 else -int(math.floor(-q + 0.5))
    if j % 2 == 0:
        return j
    offset = phi - j * 0.5 * math.pi
    if abs(offset) < 0.5 * math.pi - P.phi_cr:
        return j
    return j + 1 if offset > 0.0 else j - 1


def step_rk4_friction(P, h, state):
    """Classical RK4 (:func:`rk4_step`), the contact set of each stage the corners below the
    surface at that stage: no events."""
    return rk4_step(P, h, state, friction_accelerations)


def integrate_friction(P, state, h, n_steps):
    """n_steps fixed RK4 steps with friction; the final state."""
    s = (float(state[0]), float(state[1]), float(state[2]), float(state[3]), float(state[4]),
         float(state[5]))
    for _ in range(n_steps):
        s = step_rk4_friction(P, h, s)
    return s


def rk4_friction_throw(P, state, h, t_max):
    """A whole throw by fixed-step RK4 with friction, no events: stepped until its energy falls
    below E_crit (then its well is final: friction and the damper only take energy) or t_max.
    Returns (label, status, settle time): NO_LABEL, UNSETTLED or NONFINITE and NaN if it did
    not settle."""
    s = (float(state[0]), float(state[1]), float(state[2]), float(state[3]), float(state[4]),
         float(state[5]))
    n_max = int(math.ceil(t_max / h))
    if friction_energy(P, s) < P.e_crit:
        return friction_well(P, s[2]), SETTLED, 0.0
    for n in range(1, n_max + 1):
        s = step_rk4_friction(P, h, s)
        energy = friction_energy(P, s)
        if not abs(energy) < 1e30:
            return NO_LABEL, NONFINITE, math.nan
        if energy < P.e_crit:
            return friction_well(P, s[2]), SETTLED, n * h
    return NO_LABEL, UNSETTLED, math.nan


FRICTION_FUNCTIONS = ("friction_tangential_force", "friction_corner_force", "friction_forces",
                      "friction_accelerations", "friction_tangential", "friction_energy",
                      "friction_well",
                      "rk4_step", "step_rk4_friction", "integrate_friction",
                      "rk4_friction_throw")


def compiled_friction():
    """The friction reference compiled by numba: the same source, each function a copy whose
    names look up the other copies (numba needs compiled callees), so nothing of coincli runs.
    Plain numba: no fused multiply-adds, so it agrees with CPython to the last bits."""
    import types

    import numba

    space = dict(globals())
    made = {}
    for name in FRICTION_FUNCTIONS:
        fn = globals()[name]
        copy = types.FunctionType(fn.__code__, space, name, fn.__defaults__)
        space[name] = made[name] = numba.njit(copy)
    return types.SimpleNamespace(**made)
