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


def step_rk4(P: Params, h: float, state):
    x, y, phi, vx, vy, vphi = state
    h2 = 0.5 * h
    a1 = accelerations(P, state)
    s2 = (x + h2 * vx, y + h2 * vy, phi + h2 * vphi,
          vx + h2 * a1[0], vy + h2 * a1[1], vphi + h2 * a1[2])
    a2 = accelerations(P, s2)
    s3 = (x + h2 * s2[3], y + h2 * s2[4], phi + h2 * s2[5],
          vx + h2 * a2[0], vy + h2 * a2[1], vphi + h2 * a2[2])
    a3 = accelerations(P, s3)
    s4 = (x + h * s3[3], y + h * s3[4], phi + h * s3[5],
          vx + h * a3[0], vy + h * a3[1], vphi + h * a3[2])
    a4 = accelerations(P, s4)
    h6 = h / 6.0
    return (x + h6 * (vx + 2.0 * s2[3] + 2.0 * s3[3] + s4[3]),
            y + h6 * (vy + 2.0 * s2[4] + 2.0 * s3[4] + s4[4]),
            phi + h6 * (vphi + 2.0 * s2[5] + 2.0 * s3[5] + s4[5]),
            vx + h6 * (a1[0] + 2.0 * a2[0] + 2.0 * a3[0] + a4[0]),
            vy + h6 * (a1[1] + 2.0 * a2[1] + 2.0 * a3[1] + a4[1]),
            vphi + h6 * (a1[2] + 2.0 * a2[2] + 2.0 * a3[2] + a4[2]))


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
