"""The closed forms of a contact phase (docs/contact-methods.md) against fine references: the
Jacobian of the contact accelerations, the frozen-angle linear system and its exact solution
over a step, the decoupled blocks of a coin resting flat, and the exponential Rosenbrock steps of
benchmarks/contact_methods.py (their order, and whole throws against the event method). The
prototype runs as plain Python here (no compilation)."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from coincli import load_preset as load
from coincli.accuracy import vy_vphi_grid
from coincli.labeller import Labeller
from coincli.models import PAPER, model_params

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import contact_methods as cm  # noqa: E402

# natural scales of the state (x, y, phi, vx, vy, vphi), as the integrators' error scales
SCALES = np.array([1e-2, 1e-2, 1.0, 0.44, 0.44, 44.0])
WEIGHTS = tuple(1.0 / SCALES)


@pytest.fixture(scope="module")
def p():
    return model_params(load("paper"))


def trig(phi):
    return math.cos(phi), math.sin(phi)


def full_rhs(p, mode):
    """The model's right-hand side with the mode fixed (the angle's trig from the library)."""
    return lambda t, u: cm.rhs(p, mode, tuple(u), *trig(u[2]))


def one_corner_state(p, corner=1, phi=0.3, depth=2e-5, vphi=30.0):
    """A coin turning on one corner that is ``depth`` below the surface."""
    dy = PAPER.kernels("python").corner_offset(p, corner, *trig(phi))[1]
    return (0.0, -dy - depth, phi, 0.1, -0.3, vphi), 1 << corner


def jacobian_matrix(jac):
    """The 6x6 J of the acceleration rows (see cm.jacobian)."""
    out = np.zeros((6, 6))
    out[0, 3] = out[1, 4] = out[2, 5] = 1.0
    for row in range(3):
        out[3 + row, 1:] = jac[5 * row:5 * row + 5]
    return out


@pytest.mark.parametrize("mode", range(1, 16))
def test_jacobian_is_the_derivative_of_the_accelerations(p, mode):
    rng = np.random.default_rng(mode)
    for _ in range(5):
        st = np.array([0.0, rng.uniform(-0.01, 0.01), rng.uniform(-3, 3), rng.uniform(-1, 1),
                       rng.uniform(-1, 1), rng.uniform(-50, 50)])
        jac = jacobian_matrix(cm.jacobian(p, mode, tuple(st), *trig(st[2])))
        numeric = np.zeros((6, 6))
        for j in range(6):
            step = 1e-6 * SCALES[j]
            up, down = st.copy(), st.copy()
            up[j] += step
            down[j] -= step
            numeric[:, j] = (np.array(full_rhs(p, mode)(0, up))
                             - np.array(full_rhs(p, mode)(0, down))) / (2 * step)
        # compare in the state's natural units (J maps scale_j to scale_i / time)
        scaled = (jac - numeric) * SCALES[None, :] / SCALES[:, None]
        size = np.abs(jac * SCALES[None, :] / SCALES[:, None]).max()
        assert np.abs(scaled).max() < 1e-6 * size


def test_frozen_angle_forces_are_affine_in_the_state(p):
    """At a fixed angle the contact force is linear in (y, vx, vy, vphi): the second difference
    of the accelerations along any such direction vanishes (to rounding)."""
    st, mode = one_corner_state(p)
    c, s = trig(st[2])
    rng = np.random.default_rng(1)
    for _ in range(20):
        d = rng.normal(size=6) * SCALES * 0.1
        d[0] = d[2] = 0.0  # x enters nothing; the angle is frozen
        a = [np.array(cm.rhs(p, mode, tuple(np.array(st) + k * d), c, s)) for k in (-1, 0, 1)]
        assert np.abs(a[0] - 2 * a[1] + a[2]).max() < 1e-9 * np.abs(a[1]).max()


@pytest.mark.parametrize("h", [1e-5, 2e-4, 1e-3])
def test_linear_step_is_the_matrix_exponential(p, h):
    """u(h) = u0 + h phi_1(hJ) F(u0) solves u' = F(u0) + J (u - u0) exactly: the same as the
    7x7 augmented matrix exponential and as DOP853 at rtol 1e-12 on that linear system, over up
    to a whole contact (1 ms, h omega ~ 5)."""
    st, mode = one_corner_state(p)
    c, s = trig(st[2])
    f0 = np.array(cm.rhs(p, mode, st, c, s))
    jac = cm.jacobian(p, mode, st, c, s)
    big_j = jacobian_matrix(jac)
    series, _ = cm.phi_times(jac, h, tuple(f0), 1, WEIGHTS)
    ours = np.array(st) + h * np.array(series)
    augmented = np.zeros((7, 7))
    augmented[:6, :6] = big_j * h
    augmented[:6, 6] = f0 * h
    exact = np.array(st) + expm(augmented)[:6, 6]
    ode = solve_ivp(lambda t, u: f0 + big_j @ (u - np.array(st)), (0, h), st, method="DOP853",
                    rtol=1e-12, atol=1e-14 * SCALES).y[:, -1]
    assert np.abs((ours - exact) / SCALES).max() < 1e-12
    assert np.abs((ours - ode) / SCALES).max() < 1e-9


def test_flat_coin_decouples_into_a_vertical_oscillator_and_rocking(p):
    """Lying flat on its two lower corners at rest, the frozen-angle system splits: y is a damped
    oscillator of omega_y^2 = 2k/m (no coupling to phi), and phi rocks with stiffness
    (2 k r_d^2 - m g r_t) / I (the second term: the weight's lever as the coin tilts)."""
    mode = 0b0011
    y_rest = p.r_t - p.mass * p.g / (2 * p.k)
    st = (0.0, y_rest, 0.0, 0.0, 0.0, 0.0)
    jac = cm.jacobian(p, mode, st, 1.0, 0.0)
    ay_y, ay_phi, aphi_y, aphi_phi = jac[5], jac[6], jac[10], jac[11]
    assert ay_y == pytest.approx(-2 * p.k / p.mass, rel=1e-14)
    assert abs(ay_phi) < 1e-9 * abs(ay_y) * p.r and abs(aphi_y) * p.r < 1e-9 * abs(aphi_phi)
    rocking = (2 * p.k * p.r_d ** 2 - p.mass * p.g * p.r_t) / p.inertia
    assert aphi_phi == pytest.approx(-rocking, rel=1e-12)
    assert np.abs(cm.rhs(p, mode, st, 1.0, 0.0)[3:]).max() < 1e-9  # it is a rest state


def test_vertical_bounce_closed_form(p):
    """A flat coin pushed straight down moves in y only, as the closed-form damped oscillator
    y = y_eq + exp(-zeta w t) (A cos w_d t + B sin w_d t); the model (DOP853 at rtol 1e-12) and
    one exponential step of any length give it, since the motion stays at phi = 0 where the
    frozen-angle system is the exact one."""
    mode = 0b0011
    w0 = math.sqrt(2 * p.k / p.mass)
    zeta = p.c / (p.mass * w0)
    wd = w0 * math.sqrt(1 - zeta ** 2)
    y_eq = p.r_t - p.mass * p.g / (2 * p.k)
    y0, v0 = y_eq - 1e-5, -0.2
    a, b = y0 - y_eq, (v0 + zeta * w0 * (y0 - y_eq)) / wd
    st = (0.0, y0, 0.0, 0.0, v0, 0.0)
    for t in (1e-4, 5e-4, 1.5e-3):
        closed = y_eq + math.exp(-zeta * w0 * t) * (a * math.cos(wd * t) + b * math.sin(wd * t))
        model_y = solve_ivp(full_rhs(p, mode), (0, t), st, method="DOP853", rtol=1e-12,
                            atol=1e-16).y[1, -1]
        f0 = cm.rhs(p, mode, st, 1.0, 0.0)
        jac = cm.jacobian(p, mode, st, 1.0, 0.0)
        for order in (3, 4):
            end, err, *_ = cm.exp_step(order, p, mode, t, st, f0, jac, 1.0, 0.0, WEIGHTS)
            assert abs(end[1] - closed) < 1e-13
            assert np.abs(err).max() < 1e-13  # the remainder is zero: nothing to estimate
        assert abs(model_y - closed) < 1e-12


@pytest.mark.parametrize("order, least_ratio", [(3, 12.0), (4, 18.0)])
def test_exponential_rosenbrock_local_order(p, order, least_ratio):
    """exprb32's local error falls like h^4 (ratio 16 when h halves), exprb43's like h^5 (32);
    measured against DOP853 at rtol 1e-13 on a coin turning on one corner at 30 rad/s."""
    st, mode = one_corner_state(p)
    c, s = trig(st[2])
    f0 = cm.rhs(p, mode, st, c, s)
    jac = cm.jacobian(p, mode, st, c, s)
    errors = []
    for h in (1e-4, 5e-5, 2.5e-5):
        end = cm.exp_step(order, p, mode, h, st, f0, jac, c, s, WEIGHTS)[0]
        ref = solve_ivp(full_rhs(p, mode), (0, h), st, method="DOP853", rtol=1e-13,
                        atol=1e-16).y[:, -1]
        errors.append(np.abs((np.array(end) - ref) / SCALES).max())
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert min(ratios) > least_ratio, ratios


def test_whole_throws_agree_with_the_event_method(p):
    """The prototype (exprb43 at rtol 1e-6, located events, closed-form flight) labels whole
    throws as coincli's event method does, and counts its work."""
    scene = load("paper")
    states = vy_vphi_grid(scene, vy=(0.05, 0.8), res=(3, 3)).states()
    single = scene.with_overrides(method="event", rtol=1e-6, stop_on_settle=True, t_end=2.0,
                                  verify=False)
    ref = Labeller.of(single).label(states)  # a single pass
    counts = np.zeros(len(cm.COUNTERS), np.int64)
    for state, label, status in zip(states, ref.quarter_turns, ref.status, strict=True):
        q, st = cm.run_throw(4, p, 1e-6, 2.0, state, counts)
        assert (q, st) == (label, status)
        assert counts[cm.COUNTERS.index("accepted")] + counts[cm.COUNTERS.index("flights")] > 0
