"""The coin model written the way a user of scipy or diffrax would write it, independently of
coincli's numba kernels (nothing here imports coincli).

Model (README.md, "The model as implemented"): state s = (x, y, phi, vx, vy, vphi). Corner i sits
at body coordinates p_i = (SX[i] r_d, SY[i] r_t); its offset is d_i = R(phi) p_i and its velocity
v_i = (vx - vphi d_yi, vy + vphi d_xi). A corner with y_i = y + d_yi < 0 carries
F_i = (-c v_xi, -k y_i - c v_yi); F = sum F_i + (0, -m g), M = sum(d_xi F_yi - d_yi F_xi).
E = m (vx^2 + vy^2) / 2 + I vphi^2 / 2 + m g y + sum over penetrating corners k y_i^2 / 2.
A run stops when E < E_crit = m g (r - m g / (2 k)); its label is the well index of phi.

As a user would, the contact force is switched on and off by the sign of y_i *inside* the
right-hand side: the solvers see a vector field that is only piecewise smooth, with no help
locating contact onsets and lift-offs.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

SX = (1.0, -1.0, -1.0, 1.0)
SY = (-1.0, -1.0, 1.0, 1.0)

# label conventions shared by every peer and by ours (see peers.py)
NO_LABEL = -32768  # a run that did not settle (or failed): counts as wrong
STATUS_SETTLED, STATUS_UNSETTLED, STATUS_FAILED, STATUS_TIMEOUT = 0, 1, 2, 3
STATUS_NAMES = {0: "settled", 1: "unsettled", 2: "failed", 3: "timeout"}


@dataclass(frozen=True)
class Coin:
    """The paper preset's numbers (presets/paper.toml), as plain floats."""

    d: float = 0.02
    t: float = 0.002
    m: float = math.pi * 1e-3
    inertia: float = 7.06e-8
    k: float = 1.0e4
    c: float = 0.5
    g: float = 9.81

    @property
    def rd(self) -> float:
        return self.d / 2

    @property
    def rt(self) -> float:
        return self.t / 2

    @property
    def r(self) -> float:
        return math.hypot(self.rd, self.rt)

    @property
    def phi_cr(self) -> float:
        return math.atan2(self.rd, self.rt)

    @property
    def e_crit(self) -> float:
        w = self.m * self.g
        return w * (self.r - w / (2 * self.k))

    def atol(self, rtol: float) -> np.ndarray:
        """Absolute tolerances: rtol times the coin's natural scales, as coincli does (r for
        positions, 1 rad for phi, sqrt(2 g r) for speeds, sqrt(2 g r) / r for the spin)."""
        v_ref = math.sqrt(2 * self.g * self.r)
        return rtol * np.array([self.r, self.r, 1.0, v_ref, v_ref, v_ref / self.r])

    def initial_states(self, vy: np.ndarray, vphi: np.ndarray) -> np.ndarray:
        """x0 = 0, y0 = r, phi0 = 0, vx0 = 0 and the throw (vy0, vphi0), one row per throw."""
        vy = np.asarray(vy, float).ravel()
        vphi = np.asarray(vphi, float).ravel()
        out = np.zeros((vy.size, 6))
        out[:, 1] = self.r
        out[:, 4] = vy
        out[:, 5] = vphi
        return out


def well_index(coin: Coin, phi: float) -> int:
    """Index j of the potential well that holds phi: round(2 phi / pi) (ties away from zero),
    moved to the neighbouring even well when j is odd and |phi - j pi/2| >= pi/2 - phi_cr."""
    q = 2.0 * phi / math.pi
    j = int(math.floor(q + 0.5)) if q >= 0 else -int(math.floor(-q + 0.5))
    if j % 2 == 0:
        return j
    offset = phi - j * (0.5 * math.pi)
    if abs(offset) < 0.5 * math.pi - coin.phi_cr:
        return j
    return j + 1 if offset > 0 else j - 1


# -- scipy: plain Python floats (the fastest way to write a 6-component RHS for solve_ivp) ------
class Timeout(Exception):
    pass


def scipy_functions(coin: Coin, deadline: list[float]):
    """(rhs, energy_event) for solve_ivp. ``deadline[0]`` is a perf_counter() time after which
    the RHS raises Timeout (solve_ivp has no time limit of its own)."""
    m, inertia, k, c, g = coin.m, coin.inertia, coin.k, coin.c, coin.g
    corners = [(sx * coin.rd, sy * coin.rt) for sx, sy in zip(SX, SY, strict=True)]
    e_crit = coin.e_crit
    clock = time.perf_counter

    def rhs(t, s):
        if clock() > deadline[0]:
            raise Timeout
        x, y, phi, vx, vy, vphi = s.tolist()
        cs, sn = math.cos(phi), math.sin(phi)
        fx = 0.0
        fy = -m * g
        moment = 0.0
        for px, py in corners:
            dx = px * cs - py * sn
            dy = px * sn + py * cs
            yi = y + dy
            if yi < 0.0:  # the contact switches on and off with penetration
                fxi = -c * (vx - vphi * dy)
                fyi = -k * yi - c * (vy + vphi * dx)
                fx += fxi
                fy += fyi
                moment += dx * fyi - dy * fxi
        return [vx, vy, vphi, fx / m, fy / m, moment / inertia]

    def energy_event(t, s):
        x, y, phi, vx, vy, vphi = s.tolist()
        cs, sn = math.cos(phi), math.sin(phi)
        e = 0.5 * m * (vx * vx + vy * vy) + 0.5 * inertia * vphi * vphi + m * g * y
        for px, py in corners:
            yi = y + px * sn + py * cs
            if yi < 0.0:
                e += 0.5 * k * yi * yi
        return e - e_crit

    energy_event.terminal = True
    energy_event.direction = -1
    return rhs, energy_event


# -- JAX / diffrax -----------------------------------------------------------------------------
def jax_functions(coin: Coin):
    """(vector_field, cond_fn) for diffrax: f(t, y, args) and the event's E - E_crit."""
    import jax.numpy as jnp

    px = jnp.array(SX) * coin.rd
    py = jnp.array(SY) * coin.rt
    m, inertia, k, c, g = coin.m, coin.inertia, coin.k, coin.c, coin.g
    e_crit = coin.e_crit

    def vector_field(t, s, args):
        x, y, phi, vx, vy, vphi = s
        cs, sn = jnp.cos(phi), jnp.sin(phi)
        dx = px * cs - py * sn
        dy = px * sn + py * cs
        yi = y + dy
        on = yi < 0.0  # the contact switches on and off with penetration
        fxi = jnp.where(on, -c * (vx - vphi * dy), 0.0)
        fyi = jnp.where(on, -k * yi - c * (vy + vphi * dx), 0.0)
        fx = jnp.sum(fxi)
        fy = jnp.sum(fyi) - m * g
        moment = jnp.sum(dx * fyi - dy * fxi)
        return jnp.stack([vx, vy, vphi, fx / m, fy / m, moment / inertia])

    def energy(s):
        x, y, phi, vx, vy, vphi = s
        yi = y + px * jnp.sin(phi) + py * jnp.cos(phi)
        elastic = jnp.sum(jnp.where(yi < 0.0, 0.5 * k * yi * yi, 0.0))
        return (0.5 * m * (vx * vx + vy * vy) + 0.5 * inertia * vphi * vphi + m * g * y
                + elastic)

    def cond_fn(t, y, args, **kwargs):  # diffrax passes t=, y=, args= by keyword
        return energy(y) - e_crit

    return vector_field, cond_fn
