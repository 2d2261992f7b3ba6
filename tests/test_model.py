"""The model kernels against the plain-Python reference (tests/reference.py), and the physics
every integrator must respect: static equilibrium, energy conservation without damping, energy
loss with damping, mirror symmetry."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import run_kernel

from coincli import simulate
from coincli.enums import Status
from coincli.integrators import METHODS, info
from coincli.models import PAPER, model_params
from coincli.params import state_array
from coincli.statics import analyse

sys.path.insert(0, str(Path(__file__).resolve().parent))
import reference as R  # noqa: E402

NO_EVENTS = np.empty((0, 9))


def random_state(rng, P, n_pen):
    """A random state with exactly n_pen corners below the surface."""
    phi = rng.uniform(-2 * math.pi, 2 * math.pi)
    dy = sorted(R.heights(P, 0.0, phi))  # corner heights for a centroid at y = 0
    if n_pen == 0:
        y = -dy[0] + rng.uniform(1e-7, 1e-2)
    elif n_pen == 4:
        y = -dy[3] - rng.uniform(1e-7, 1e-4)
    else:
        lo, hi = -dy[n_pen], -dy[n_pen - 1]  # y + dy[n_pen - 1] < 0 <= y + dy[n_pen]
        y = lo + rng.uniform(0.05, 0.95) * (hi - lo)
    state = (rng.normal(0, 0.01), y, phi, rng.normal(0, 1.0), rng.normal(0, 1.0),
             rng.normal(0, 30.0))
    assert len(R.penetrating(P, y, phi)) == n_pen
    return state


# -- the reference itself: forces are minus the gradient of the potential (c = 0) ----------------

def test_reference_force_is_gradient_of_potential():
    """With c = 0 the contact force and moment are -dV/dy and -dV/dphi of
    V = m g y + sum k y_i^2 / 2: this pins the kinematics and the moment's sign in the reference
    (and so in every kernel compared to it)."""
    P = R.Params(**{**R.PAPER.__dict__, "c": 0.0})
    rng = np.random.default_rng(7)

    def potential(y, phi):
        _, grav, elastic = R.energies(P, (0.0, y, phi, 0.0, 0.0, 0.0))
        return grav + elastic

    for n_pen in (1, 2, 3, 4):
        for _ in range(10):
            _, y, phi, *_ = random_state(rng, P, n_pen)
            fx, fy, moment = R.forces(P, (0.0, y, phi, 0.0, 0.0, 0.0))
            hy, hp = 1e-9, 1e-7
            dv_dy = (potential(y + hy, phi) - potential(y - hy, phi)) / (2 * hy)
            dv_dphi = (potential(y, phi + hp) - potential(y, phi - hp)) / (2 * hp)
            assert fx == 0.0
            assert fy == pytest.approx(-dv_dy, rel=1e-5, abs=1e-9)
            assert moment == pytest.approx(-dv_dphi, rel=1e-5, abs=1e-11)


def test_reference_signs():
    """A lying coin pressed in on its +x corner only is pushed up and turned counterclockwise;
    damping opposes the corner's velocity."""
    P = R.PAPER
    # phi = 0: corner 0 at (+r_d, -r_t); tilt slightly so only corner 0 penetrates
    phi = -1e-3
    y = P.r_t * math.cos(phi) - P.r_d * math.sin(phi) - 1e-6  # corner 0 is 1e-6 m deep
    assert R.penetrating(P, y, phi) == [0]
    fx, fy, moment = R.forces(P, (0, y, phi, 0, 0, 0))
    assert fy > -P.m * P.g and moment > 0 and fx == 0
    # the corner moving right and down: damping pushes left and up
    fx2, fy2, _ = R.forces(P, (0, y, phi, 0.1, -0.1, 0))
    assert fx2 < 0 and fy2 > fy


# -- kernels vs reference ---------------------------------------------------------------------

@pytest.mark.parametrize("n_pen", [0, 1, 2, 3, 4])
def test_accelerations_and_energies_match_reference(paper, n_pen):
    p = model_params(paper)
    P = R.Params.from_scene(paper)
    rng = np.random.default_rng(100 + n_pen)
    for _ in range(200):
        st = random_state(rng, P, n_pen)
        K = PAPER.kernels()
        assert K.contact_mask(p, st[1], st[2]) == R.mask(P, st[1], st[2])
        got = K.accelerations_auto(p, st)
        want = R.accelerations(P, st)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * max(map(abs, want)))
        got_e = K.energies(p, np.array(st))
        want_e = R.energies(P, st)
        np.testing.assert_allclose(got_e, want_e, rtol=1e-12, atol=1e-15 * sum(want_e))
        total = K.total_energy(p, np.array(st))
        assert total == pytest.approx(sum(want_e), rel=1e-12)


def test_accelerations_with_given_mask_extend_the_force_law(paper):
    """The adaptive integrators evaluate the force of a fixed set of corners whatever their
    height (the force law extended beyond the surface)."""
    p = model_params(paper)
    P = R.Params.from_scene(paper)
    rng = np.random.default_rng(3)
    for _ in range(100):
        st = random_state(rng, P, int(rng.integers(0, 5)))
        m = int(rng.integers(0, 16))
        got = PAPER.kernels().contact_accelerations(p, m, st, math.cos(st[2]),
                                                    math.sin(st[2]))
        want = R.accelerations(P, st, {i for i in range(4) if m >> i & 1})
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * max(map(abs, want)))


def impact_state(P):
    """A tilted coin 50 um above the surface falling at 0.5 m/s, spinning: its first corner
    touches after 0.1 ms and is in contact for the rest of a 2 ms run."""
    phi = 0.3
    lowest = min(R.heights(P, 0.0, phi))
    return (0.0, -lowest + 5e-5, phi, 0.2, -0.5, 3.0)


@pytest.mark.parametrize("method", ["symplectic_euler", "rk4"])
def test_fixed_step_run_matches_reference_to_rounding(paper, method):
    P = R.Params.from_scene(paper)
    s0 = impact_state(P)
    h, n = 1e-6, 2000
    want, kept = R.integrate(P, method, s0, h, n, every=1)
    masks = {R.mask(P, s[1], s[2]) for s in kept}
    assert len(masks) >= 2, "the run must go through a contact onset"
    run = run_kernel(paper, s0, method=method, dt=h, t_end=n * h, max_events=100)
    t, steps, n_events, final = run.result.t, run.result.steps, run.result.n_events, run.final
    assert steps == n and t == pytest.approx(n * h)
    assert n_events >= 1
    scale = np.array([P.r, P.r, 1.0, 1.0, 1.0, 1.0 / P.r])
    np.testing.assert_allclose(final / scale, np.array(want) / scale, rtol=0, atol=1e-12)


# -- well index, E_crit --------------------------------------------------------------------------

@pytest.mark.parametrize("phi_deg,well", [
    (0.0, 0), (44.0, 0), (46.0, 0), (80.0, 0), (84.0, 0), (-46.0, 0), (-84.0, 0),
    (84.6, 1), (90.0, 1), (95.5, 1), (-85.0, -1), (-95.0, -1),
    (96.0, 2), (134.0, 2), (180.0, 2), (263.0, 2),
    (265.0, 3), (-265.0, -3), (275.0, 3), (360.0 + 46.0, 4),
])
def test_well_index(paper, phi_deg, well):
    """phi_cr = atan(r_d / r_t) = 84.29 deg: a lying well reaches out to +-84.29 deg, a standing
    one only +-5.71 deg; so 46 deg is still lying (round(2 phi / pi) would say 1)."""
    p = model_params(paper)
    phi = math.radians(phi_deg)
    assert PAPER.kernels().well_index(p, phi) == well


def test_well_index_edges(paper):
    p = model_params(paper)
    phi_cr = paper.coin.phi_cr
    eps = 1e-9
    assert PAPER.kernels().well_index(p, phi_cr - eps) == 0
    assert PAPER.kernels().well_index(p, phi_cr + eps) == 1
    assert PAPER.kernels().well_index(p, math.pi - phi_cr - eps) == 1
    assert PAPER.kernels().well_index(p, math.pi - phi_cr + eps) == 2
    assert PAPER.kernels().well_index(p, -phi_cr - eps) == -1
    assert PAPER.kernels().rounded_quarter_turns(math.radians(46.0)) == 1


def test_e_crit_formula(paper):
    m, g, k = math.pi * 1e-3, 9.81, 1.0e4
    r = math.hypot(0.01, 0.001)
    want = m * g * (r - m * g / (2 * k))
    assert want == pytest.approx(3.09680e-4, abs=1e-9)
    assert paper.e_crit == pytest.approx(want, rel=1e-14)
    assert model_params(paper).e_crit == pytest.approx(want, rel=1e-14)
    assert analyse(paper).e_crit == pytest.approx(want, rel=1e-14)
    # E_crit is the potential energy balanced on a corner with the foundation's energy counted:
    # centroid at r - mg/k, one corner pressed in by mg/k
    P = R.Params.from_scene(paper)
    sink = P.m * P.g / P.k
    on_corner = (0.0, P.r - sink, P.phi_cr, 0.0, 0.0, 0.0)
    assert R.total_energy(P, on_corner) == pytest.approx(want, rel=1e-12)
    assert R.forces(P, on_corner)[1] == pytest.approx(0.0, abs=1e-12)


# -- static equilibrium --------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["symplectic_euler", "event"])
def test_coin_at_equilibrium_stays(paper, method):
    sink = paper.coin.mass * paper.g / (2 * paper.foundation.k)
    y_eq = paper.coin.r_t - sink
    scene = paper.with_overrides(method=method, y0=y_eq, t_end=0.2, stop_on_settle=False)
    tr = simulate(scene, sample_dt=1e-3)
    assert tr.status == Status.SETTLED and tr.settle_time == 0.0
    dev = np.abs(tr.samples[:, 2] - y_eq).max()
    # a fixed step keeps the equilibrium to rounding; an adaptive one to its tolerance (it walks
    # at the stability limit of the rocking mode, its error estimate holding that noise at
    # about rtol times the coin's size)
    bound = 1e-9 * sink if method == "symplectic_euler" else 1e-3 * sink
    if info(method).adaptive:
        bound = max(bound, 10 * scene.integration.rtol * paper.coin.r)
    assert dev < bound
    assert np.abs(tr.samples[:, 3]).max() < 1e-9  # phi
    assert tr.quarter_turns == 0


@pytest.mark.parametrize("method", ["symplectic_euler", "verlet", "rk4", "dopri5", "event"])
def test_coin_laid_flat_sinks_by_mg_over_2k(paper, method):
    sink = paper.coin.mass * paper.g / (2 * paper.foundation.k)
    y_eq = paper.coin.r_t - sink
    scene = paper.with_overrides(method=method, y0=paper.coin.r_t, t_end=0.5,
                                 stop_on_settle=False)
    tr = simulate(scene, sample_dt=1e-3)
    assert tr.status == Status.SETTLED
    late = tr.samples[tr.samples[:, 0] >= 0.3]
    # fixed steps settle to rounding; adaptive ones hold rest to their tolerance (rtol * r)
    bound = 1e-3 * sink
    if info(method).adaptive:
        bound = max(bound, 10 * scene.integration.rtol * paper.coin.r)
    assert np.abs(late[:, 2] - y_eq).max() < bound
    assert abs(tr.final_state[1] - y_eq) < bound
    # it does sink: the lowest point reached is below y_eq, never below y_eq - sink (one overshoot
    # of an underdamped oscillator started at rest at y_eq + sink), and it never tips
    assert tr.samples[:, 2].min() < y_eq
    assert tr.samples[:, 2].min() > y_eq - sink * (1 + 1e-6)
    assert np.abs(tr.samples[:, 3]).max() < 1e-6
    assert tr.quarter_turns == 0


# -- energy: conserved with c = 0, only lost with c > 0 ------------------------------------------

# measured relative drift (max over 1 s, throw vy 1.0, vphi 5.0, 9 impacts):
# symplectic Euler 6.9e-4, Verlet 2.3e-6, RK4 4.4e-7 (h = 1e-6); event 3.3e-9 (rtol 1e-10)
ENERGY_BOUNDS = {
    "symplectic_euler": ({"dt": 1e-6}, 1e-3),
    "verlet": ({"dt": 1e-6}, 1e-5),
    "rk4": ({"dt": 1e-6}, 2e-6),
    "dopri5": ({"rtol": 1e-10}, 3e-8),
    "event": ({"rtol": 1e-10}, 3e-8),
}


@pytest.mark.parametrize("method", list(ENERGY_BOUNDS))
def test_energy_conserved_without_damping(undamped, method):
    settings, bound = ENERGY_BOUNDS[method]
    assert undamped.foundation.c == 0.0
    scene = undamped.with_overrides(method=method, vy=1.0, vphi=5.0, t_end=1.0,
                                    stop_on_settle=False, **settings)
    tr = simulate(scene, sample_dt=1e-3, record_events=True)
    assert tr.status == Status.UNSETTLED and tr.t_final == pytest.approx(1.0)
    onsets = tr.events[tr.events[:, 2] > 0]
    assert len(onsets) >= 6, "the throw must go through several impacts"
    P = R.Params.from_scene(scene)
    energy = np.array([R.total_energy(P, row[1:]) for row in tr.samples])
    drift = np.abs(energy - energy[0]).max() / energy[0]
    assert drift < bound, f"{method}: relative energy drift {drift:.3g}"
    assert abs(tr.energy_final - tr.energy_initial) / tr.energy_initial < bound


def test_symplectic_euler_energy_error_is_first_order(undamped):
    """Halving the step halves symplectic Euler's energy error (and it does not grow with time)."""
    drifts = []
    for dt in (2e-6, 1e-6):
        scene = undamped.with_overrides(method="symplectic_euler", dt=dt, vy=1.0, vphi=5.0,
                                        t_end=0.5, stop_on_settle=False)
        tr = simulate(scene, sample_dt=1e-3)
        P = R.Params.from_scene(scene)
        energy = np.array([R.total_energy(P, row[1:]) for row in tr.samples])
        drifts.append(np.abs(energy - energy[0]).max() / energy[0])
    assert 1.6 < drifts[0] / drifts[1] < 2.5


@pytest.mark.parametrize("method,settings,tol", [
    ("event", {"rtol": 1e-10}, 1e-8),
    ("rk4", {"dt": 1e-6}, 1e-6),
])
def test_damping_only_removes_energy(paper, method, settings, tol):
    scene = paper.with_overrides(method=method, vy=1.197, vphi=3.508, t_end=0.5,
                                 stop_on_settle=False, **settings)
    tr = simulate(scene, sample_dt=2e-4)
    P = R.Params.from_scene(scene)
    energy = np.array([R.total_energy(P, row[1:]) for row in tr.samples])
    rises = np.diff(energy)
    assert rises.max() < tol * energy[0]
    assert energy[-1] < 0.2 * energy[0]  # and it does remove some


# -- mirror symmetry -----------------------------------------------------------------------------

MIRROR_THROWS = [(0.3, 5.0), (0.55, 8.0), (0.65, 4.0), (0.7, 16.0), (0.8, 10.0), (0.45, -13.0),
                 (1.197, 3.508)]


@pytest.mark.parametrize("method", [m.label for m in METHODS])
def test_mirror_symmetry(paper, method):
    """(vy, -vphi) is the mirror image of (vy, vphi): it must end with -n quarter turns."""
    labels = []
    for vy, vphi in MIRROR_THROWS:
        a = simulate(paper.with_overrides(method=method, vy=vy, vphi=vphi))
        b = simulate(paper.with_overrides(method=method, vy=vy, vphi=-vphi))
        assert a.settled and b.settled
        assert b.quarter_turns == -a.quarter_turns, (vy, vphi)
        labels.append(a.quarter_turns)
    assert any(n != 0 for n in labels)


@pytest.mark.parametrize("method", [m.label for m in METHODS])
def test_mirror_symmetry_of_the_state(paper, method):
    """Over a short run through two impacts the mirrored state is the mirror image to near
    rounding: x, phi, vx, vphi change sign, y and vy do not."""
    kw = dict(method=method, vy=0.5, t_end=0.12, stop_on_settle=False)
    a = simulate(paper.with_overrides(vx=0.05, vphi=-12.0, **kw))
    b = simulate(paper.with_overrides(vx=-0.05, vphi=12.0, **kw))
    sign = np.array([-1, 1, -1, -1, 1, -1])
    scale = np.array([paper.coin.r, paper.coin.r, 1.0, 1.0, 1.0, 1.0 / paper.coin.r])
    np.testing.assert_allclose(b.final_state / scale, sign * a.final_state / scale, rtol=0,
                               atol=1e-8)


def test_state_array_default_y0_is_r(paper):
    assert state_array(paper)[1] == pytest.approx(paper.coin.r)
