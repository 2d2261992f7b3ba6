"""Per-method properties: convergence order on a smooth problem, the stable step, contact events
landing on the surface, exact flight, the first contact found is the first one, and the
certified early stop."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import run_kernel

from coincli import simulate
from coincli.enums import Certainty, Status
from coincli.integrators import METHODS, info
from coincli.integrators.batch import rungs_agree
from coincli.integrators.ladder import CHANGE_TOLERANCE, SETTLE_TOLERANCE
from coincli.models import PAPER, model_params
from coincli.params import ParameterError, state_array
from coincli.presets import load

sys.path.insert(0, str(Path(__file__).resolve().parent))
import reference as R  # noqa: E402

PY = PAPER.kernels("python")  # the model's kernels as plain Python

FIXED = [m.name for m in METHODS.values() if not m.adaptive]
ADAPTIVE = [m.name for m in METHODS.values() if m.adaptive]


# -- convergence order on a smooth problem -------------------------------------------------------

T_SMOOTH = 0.01
SCALE = np.array([1e-6, 1e-6, 1e-4, 1e-3, 1e-3, 0.3])  # amplitudes of the perturbation


def smooth_start(scene):
    """A lying coin at its equilibrium, kicked a little: it rocks and bobs on its two lower
    corners (1.5 um deep at rest), which stay in contact, while the upper ones stay clear."""
    sink = scene.coin.mass * scene.g / (2 * scene.foundation.k)
    return np.array([0.0, scene.coin.r_t - sink, 0.0, 0.01, 0.001, 0.3])


def run_smooth(scene, name, dt=1e-6, rtol=1e-7):
    run = run_kernel(scene, smooth_start(scene), method=name, dt=dt, rtol=rtol, t_end=T_SMOOTH,
                     max_events=50)
    final, events, n_events, steps = run.final, run.events, run.result.n_events, run.result.steps
    # only the two initial onsets (corners 0 and 1, at t = 0): the contact set never changes
    assert n_events == 2, events[:n_events]
    assert np.all(events[:2, 0] == 0.0) and set(events[:2, 1]) == {0.0, 1.0}
    return final, steps


@pytest.fixture(scope="module")
def smooth_reference(paper):
    final, _ = run_smooth(paper, "rk4", dt=1e-7)
    return final


def smooth_error(final, ref):
    return float(np.max(np.abs(final - ref) / SCALE))


@pytest.mark.parametrize("name", FIXED)
def test_fixed_step_convergence_order(paper, smooth_reference, name):
    order = info(name).order
    steps = [4e-5, 2e-5, 1e-5] if order >= 4 else [2e-5, 1e-5, 5e-6]
    errors = [smooth_error(run_smooth(paper, name, dt=h)[0], smooth_reference) for h in steps]
    observed = [math.log2(errors[i] / errors[i + 1]) for i in range(len(errors) - 1)]
    assert errors[-1] > 1e-10, "errors must stay above the reference's own error"
    for q in observed:
        assert abs(q - order) < 0.3, f"{name}: observed orders {observed}, declared {order}"


def test_verlet_is_second_order_without_damping():
    """With c = 0 Stormer-Verlet shows its second order on the same problem (isolates the
    damping treatment if the damped test fails)."""
    scene = load("undamped").scene.with_overrides(verify=False)
    ref, _ = run_smooth(scene, "rk4", dt=1e-7)
    errors = [smooth_error(run_smooth(scene, "verlet", dt=h)[0], ref)
              for h in (2e-5, 1e-5, 5e-6)]
    observed = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert all(abs(q - 2) < 0.3 for q in observed), observed


# DOP853 reaches its order only below rtol 1e-8: tested in test_dop853.py, on a tighter reference
# (its switching pair, without friction, is DOP853 itself)
@pytest.mark.parametrize("name", [m for m in ADAPTIVE
                                  if m not in ("event_dop853", "event_dop853_rodas")])
def test_adaptive_convergence_order(paper, smooth_reference, name):
    """Error against work: an order-5 method's error falls like steps^-5, and each decade of
    rtol buys about a decade of error."""
    rtols = [1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
    errors, steps = [], []
    for rtol in rtols:
        final, n = run_smooth(paper, name, rtol=rtol)
        errors.append(smooth_error(final, smooth_reference))
        steps.append(n)
    assert all(errors[i + 1] < errors[i] for i in range(len(errors) - 1)), errors
    for i in range(len(errors) - 1):
        assert 2.0 < errors[i] / errors[i + 1] < 50.0, errors
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert abs(-slope - info(name).order) < 0.7, f"{name}: error ~ steps^{slope:.2f}"


# -- stable step ---------------------------------------------------------------------------------

STABILITY_THROWS = [dict(vy=1.197, vphi=3.508),                       # the paper's fig. 2
                    dict(y0=0.002, phi0=0.05)]                        # a tilted coin dropped 1 mm


def at_rest_at_end(scene, name, dt, throw):
    scene = scene.with_overrides(method=name, dt=dt, t_end=2.0, stop_on_settle=False, **throw)
    tr = simulate(scene, force=True)
    if tr.status == Status.NONFINITE:
        return False, "non-finite"
    kinetic, gravity, elastic = PY.energies(model_params(scene), tr.final_state)
    total = kinetic + gravity + elastic
    ok = total < scene.e_crit and kinetic < 1e-12 * scene.e_crit
    return ok, (f"E/E_crit = {total / scene.e_crit:.3g}, "
                f"kinetic/E_crit = {kinetic / scene.e_crit:.2g}")


@pytest.mark.parametrize("name", FIXED)
def test_stable_below_and_unstable_above_predicted_step(paper, name):
    limit = info(name).stable_step(paper)
    omega = math.sqrt(2 * paper.foundation.k * paper.coin.r_d ** 2 / paper.coin.inertia)
    assert 1.0 / omega < limit < 3.0 / omega
    for throw in STABILITY_THROWS:
        ok, why = at_rest_at_end(paper, name, 0.8 * limit, throw)
        assert ok, f"{name} at 0.8 x {limit:.4g} s, {throw}: not at rest at 2 s ({why})"
        ok, why = at_rest_at_end(paper, name, 1.25 * limit, throw)
        assert not ok, f"{name} at 1.25 x {limit:.4g} s, {throw}: at rest at 2 s ({why})"


def test_stable_step_predictions(paper):
    """The predicted limits for the paper's parameters: symplectic Euler a little below
    2 / omega_max because of damping (NOTES.md: unstable near 3.8e-4 s without it)."""
    omega = math.sqrt(2 * paper.foundation.k * paper.coin.r_d ** 2 / paper.coin.inertia)
    assert omega == pytest.approx(5322.4, rel=1e-4)
    se = info("symplectic_euler").stable_step(paper)
    assert se < 2 / omega
    assert se == pytest.approx(3.29e-4, rel=0.01)
    undamped = info("symplectic_euler").stable_step(load("undamped").scene)
    assert undamped == pytest.approx(2 / omega, rel=1e-3)
    assert info("rk4").stable_step(load("undamped").scene) == pytest.approx(
        2 * math.sqrt(2) / omega, rel=1e-3)
    for name in ADAPTIVE:
        assert info(name).stable_step(paper) is None


@pytest.mark.parametrize("name", FIXED)
def test_simulate_refuses_a_step_beyond_the_limit(paper, name):
    limit = info(name).stable_step(paper)
    scene = paper.with_overrides(method=name, dt=1.25 * limit, vy=0.3, t_end=0.01)
    with pytest.raises(ParameterError, match="stable step"):
        simulate(scene)
    simulate(scene.with_overrides(dt=0.8 * limit))


# -- contact events ------------------------------------------------------------------------------

EVENT_THROWS = [dict(vy=1.197, vphi=3.508), dict(vy=0.5, vphi=-12.0),
                dict(vy=1.9, vphi=17.0, vx=0.2)]


@pytest.mark.parametrize("name", ADAPTIVE)
@pytest.mark.parametrize("throw", EVENT_THROWS)
def test_adaptive_lands_on_contact_events(paper, name, throw):
    scene = paper.with_overrides(method=name, stop_on_settle=False, t_end=0.6, **throw)
    tr = simulate(scene, record_events=True)
    P = R.Params.from_scene(scene)
    ev = tr.events
    assert (ev[:, 2] > 0).sum() >= 5
    assert np.all(np.diff(ev[:, 0]) >= 0)
    for row in ev:
        corner = int(row[1])
        height = R.heights(P, row[4], row[5])[corner]
        assert abs(height) < 1e-9, f"event at t = {row[0]}: corner {corner} at {height:.3g} m"
    # onsets and lift-offs alternate corner by corner
    for corner in range(4):
        kinds = ev[ev[:, 1] == corner, 2]
        assert np.all(kinds[1:] != kinds[:-1])


@pytest.mark.parametrize("name", ADAPTIVE)
def test_adaptive_events_and_state_match_independent_reference(paper, name):
    """scipy's DOP853 at rtol 1e-12, restarted at each contact event (tests/reference.py):
    same events, same times, same states after the first impacts."""
    throw = dict(vy=1.197, vphi=3.508)
    T = 0.3
    scene = paper.with_overrides(method=name, rtol=1e-9, stop_on_settle=False, t_end=T, **throw)
    P = R.Params.from_scene(scene)
    t_eval = np.linspace(0.0, T, 7)
    ref_samples, ref_final, ref_events = R.solve_ivp_reference(P, state_array(scene), T, t_eval)
    assert len(ref_events) == 4
    tr = simulate(scene, record_events=True, sample_dt=T / 6)
    assert len(tr.events) == len(ref_events)
    for row, (t, corner, kind) in zip(tr.events, ref_events, strict=True):
        assert int(row[1]) == corner and int(row[2]) == kind
        assert abs(row[0] - t) < 2e-10
    scale = np.array([P.r, P.r, 1.0, 1.0, 1.0, 1.0 / P.r])
    np.testing.assert_allclose(tr.final_state / scale, ref_final / scale, rtol=0, atol=5e-7)
    np.testing.assert_allclose(tr.samples[:7, 1:] / scale, ref_samples / scale, rtol=0,
                               atol=5e-7)


@pytest.mark.parametrize("name", ADAPTIVE)
def test_no_impact_is_skipped_in_flight(name):
    """A fast-spinning coin in flight dips a corner 1.6 mm into the ground for about 5 ms
    between two steps; an integrator that checks corner heights only at step ends may step over
    the whole impact. Every adaptive method must see the same impacts as the closed-form flight
    of the event method."""
    scene = load("undamped").scene.with_overrides(verify=False, vy=1.0, vphi=5.0, t_end=0.5,
                                                  rtol=1e-10, stop_on_settle=False)
    ref = simulate(scene.with_overrides(method="event"), record_events=True)
    tr = simulate(scene.with_overrides(method=name), record_events=True)
    n = 6
    assert len(ref.events) >= n
    assert len(tr.events) >= n
    np.testing.assert_array_equal(tr.events[:n, 1:3], ref.events[:n, 1:3])
    np.testing.assert_allclose(tr.events[:n, 0], ref.events[:n, 0], rtol=0, atol=1e-9)


# A throw of the five-dimensional box (benchmarks/ladder_design.py --box 2048, throw 946): the
# coin lands on corner 0 spinning up to 245 rad/s, and corner 3 touches the surface for 38 us
# in between. Both ends of a step at rtol 1e-6 or 1e-7 have corner 3 above the surface; missing
# the touch made the two rungs agree, to 50 us, on the wrong well (8 instead of 4).
GRAZING_IN_CONTACT = dict(y0=0.018554951274944127, phi0=-0.897847025567009,
                          vx=-0.13035263419955745, vy=1.7992228603238984,
                          vphi=-17.64445816765122)


@pytest.fixture(scope="module")
def grazing_reference(paper):
    scene = paper.with_overrides(stop_on_settle=False, t_end=0.38, **GRAZING_IN_CONTACT)
    P = R.Params.from_scene(scene)
    return R.solve_ivp_reference(P, state_array(scene), 0.38)[2]


@pytest.mark.parametrize("name", ADAPTIVE)
@pytest.mark.parametrize("rtol", [1e-6, 1e-7])
def test_a_corner_grazing_in_contact_is_not_skipped(paper, grazing_reference, name, rtol):
    """A corner that touches and leaves within one step, while another is in contact, is seen
    (its lowest point located on the step's continuous extension): the same events, at the same
    times, as the independent reference (which caps its contact steps at 1 us)."""
    assert [e[1:] for e in grazing_reference] == [(0, 1), (3, 1), (3, -1), (0, -1)]
    scene = paper.with_overrides(method=name, rtol=rtol, verify=False, stop_on_settle=False,
                                 t_end=0.38, **GRAZING_IN_CONTACT)
    events = simulate(scene, record_events=True).events
    assert [(int(e[1]), int(e[2])) for e in events] == [e[1:] for e in grazing_reference]
    np.testing.assert_allclose(events[:, 0], [e[0] for e in grazing_reference], rtol=0,
                               atol=1e-7)


def test_the_grazing_throw_gets_its_converged_label(paper):
    """The verified label of that throw is the one every run from rtol 1e-8 to 1e-12 and RK4 at
    h = 2.5e-7 give."""
    tr = simulate(paper.with_overrides(verify=True, **GRAZING_IN_CONTACT))
    assert tr.certainty == Certainty.CERTAIN and tr.quarter_turns == 4


# Throw 1898 of the same box: the runs at rtol 1e-6 and 1e-7 enter well 10 within 0.12 ms of
# each other, then bounce apart (settling 64 ms apart); every run from 1e-8 on leaves well 10
# for well 8 at 0.89-0.90 s, as RK4 at h = 2.5e-7 does.
ENTERED_TOGETHER_SETTLED_APART = dict(y0=0.012656838324757513, phi0=-1.694657607369702,
                                      vx=-0.14947430007277496, vy=1.9266072205995137,
                                      vphi=6.577372584738768)


def test_rungs_that_settle_apart_do_not_agree(paper):
    """Agreeing on the well and the moment of entering it is not enough while the coin can
    still leave it: the two rungs must also settle at the same moment (within 10 ms)."""
    scene = paper.with_overrides(**ENTERED_TOGETHER_SETTLED_APART)
    first, second = (simulate(scene.with_overrides(verify=False, rtol=rtol)).rungs[0]
                     for rtol in (1e-6, 1e-7))  # the former ladder's first two rungs
    assert first.quarter_turns == second.quarter_turns == 10
    assert abs(first.last_change - second.last_change) < 1e-3
    assert abs(first.settle_time - second.settle_time) > 1e-2
    assert not PY[rungs_agree](first.quarter_turns, first, second.quarter_turns, second,
                               CHANGE_TOLERANCE, SETTLE_TOLERANCE)
    tr = simulate(scene.with_overrides(verify=True))  # DOP853 at 1e-8 gets it at once
    assert tr.certainty == Certainty.CERTAIN and tr.quarter_turns == 8


# -- exact flight --------------------------------------------------------------------------------

SX = np.array(R.SX)
SY = np.array(R.SY)


def min_corner_height(P, t, y0, vy, phi0, vphi):
    t = np.asarray(t, dtype=float)[..., None]
    y = y0 + vy * t - 0.5 * P.g * t * t
    phi = phi0 + vphi * t
    return (y + SX * P.r_d * np.sin(phi) + SY * P.r_t * np.cos(phi)).min(axis=-1)


def first_touchdown(P, y0, vy, phi0, vphi, t_max, dt):
    """Brute force: a dense scan of the closed-form corner heights (in chunks), refined by
    bisection. Returns (time, corner) of the first touch-down."""
    chunk = 200_000
    start = 0.0
    while start < t_max:
        t = start + dt * np.arange(chunk + 1)
        m = min_corner_height(P, t, y0, vy, phi0, vphi)
        below = np.nonzero(m < 0.0)[0]
        if below.size:
            break
        start = t[-1]
    else:
        raise AssertionError("no touch-down in the scanned window")
    idx = below[0]
    assert idx > 0 or start > 0.0
    lo, hi = t[idx] - dt, t[idx]
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if min_corner_height(P, mid, y0, vy, phi0, vphi) < 0.0:
            hi = mid
        else:
            lo = mid
    t_hit = hi
    y = y0 + vy * t_hit - 0.5 * P.g * t_hit ** 2
    corner = int(np.argmin(R.heights(P, y, phi0 + vphi * t_hit)))
    return t_hit, corner


def test_exact_flight_matches_fine_rk4(paper):
    throw = dict(y0=0.2, vy=1.0, vphi=7.0, vx=0.3)
    P = R.Params.from_scene(paper)
    t_touch, _ = first_touchdown(P, 0.2, 1.0, 0.0, 7.0, t_max=0.5, dt=1e-5)
    t_end = 0.95 * t_touch
    scene = paper.with_overrides(method="event", t_end=t_end, **throw)
    tr = simulate(scene, sample_dt=0.01, record_events=True)
    assert len(tr.events) == 0
    assert tr.status == Status.UNSETTLED and tr.t_final == pytest.approx(t_end, rel=1e-12)
    assert tr.steps <= 2  # closed-form flight: no stepping
    s = tuple(state_array(scene))
    t_prev = 0.0
    for row in tr.samples:
        n = max(1, int(round((row[0] - t_prev) / 1e-4)))
        s = R.integrate(P, "rk4", s, (row[0] - t_prev) / n, n)
        t_prev = row[0]
        np.testing.assert_allclose(row[1:], s, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(tr.final_state, s, rtol=1e-9, atol=1e-12)
    assert tr.samples[-1, 0] == pytest.approx(t_end)


def grazing_throw(paper, vphi, t1, depth):
    """Falling from its apex and spinning at vphi, the coin brings its corner 1 straight down
    near t1, and y0 is chosen so that this corner dips only `depth` below the surface (for a
    few microseconds or less); later corners go clearly below. Returns the scene and the first
    touch-down (time, corner) found by a dense brute-force scan of the closed-form flight."""
    P = R.Params.from_scene(paper)
    p1 = (SX[1] * P.r_d, SY[1] * P.r_t)
    phi0 = -math.pi / 2 - math.atan2(p1[1], p1[0]) - vphi * t1  # corner 1 straight down at t1

    def corner1(t):  # its height for y0 = 0, vy0 = 0
        phi = phi0 + vphi * t
        return -0.5 * P.g * t * t + p1[0] * math.sin(phi) + p1[1] * math.cos(phi)

    # golden-section search for corner 1's lowest point near t1
    span = min(1e-3, 0.3 / abs(vphi))
    a, b = t1 - span, t1 + 1.5 * span
    gr = (math.sqrt(5) - 1) / 2
    for _ in range(200):
        c, d = b - gr * (b - a), a + gr * (b - a)
        if corner1(c) < corner1(d):
            b = d
        else:
            a = c
    t_low = 0.5 * (a + b)
    y0 = -corner1(t_low) - depth
    # the shortest dip lasts 2 sqrt(2 depth / (r vphi^2)): scan at a fifth of that
    dt = min(1e-8, 0.4 * math.sqrt(2 * depth / (P.r * vphi ** 2)))
    t_touch, corner = first_touchdown(P, y0, 0.0, phi0, vphi, t_max=t1 + 3 * span, dt=dt)
    assert t_touch <= t_low + 1e-9
    scene = paper.with_overrides(y0=y0, phi0=phi0, vphi=vphi, vy=0.0, t_end=t1 + 0.01,
                                 stop_on_settle=False)
    return scene, t_touch, corner


def check_first_contact(scene, t_touch, corner, time_tol, height_tol):
    P = R.Params.from_scene(scene)
    tr = simulate(scene, record_events=True)
    first = tr.events[0]
    assert int(first[2]) == 1
    assert int(first[1]) == corner and abs(first[0] - t_touch) < time_tol, \
        f"first onset: corner {int(first[1])} at {first[0]!r}; brute force: corner {corner} " \
        f"at {t_touch!r}"
    height = R.heights(P, first[4], first[5])[corner]
    assert abs(height) < height_tol


@pytest.mark.parametrize("depth", [1e-9, 1e-11])
@pytest.mark.parametrize("vphi,t1", [(100.0, 0.005), (-100.0, 0.005), (300.0, 0.02),
                                     (1000.0, 0.005), (1000.0, 0.02)])
def test_grazing_contact_is_not_skipped(paper, depth, vphi, t1):
    """The event method's first contact is the first one, however grazing."""
    scene, t_touch, corner = grazing_throw(paper, vphi, t1, depth)
    check_first_contact(scene.with_overrides(method="event"), t_touch, corner, 2e-9, 1e-12)


@pytest.mark.parametrize("vphi,t1,depth", [(300.0, 0.02, 1e-6), (481.46, 0.02756, 1.07e-6)])
def test_where_dopri5_fails_event_does_not(paper, vphi, t1, depth):
    """A documented failure of plain dopri5 (it integrates flight and only samples each step
    every pi/64 of rotation): a 1 um dip of a fast-spinning coin -- a real impact, the coin at
    rest sinks 1.5 um -- slips between its checks. The event method's conservative advancement
    finds it, and dopri5 never reports a contact *before* the true first one."""
    scene, t_touch, corner = grazing_throw(paper, vphi, t1, depth)
    check_first_contact(scene.with_overrides(method="event"), t_touch, corner, 2e-9, 1e-12)
    first = simulate(scene.with_overrides(method="dopri5"), record_events=True).events[0]
    assert first[0] >= t_touch - 1e-9


# -- certified early stop ------------------------------------------------------------------------

# cells where round(2 phi / pi) at the moment of settling differs from the well that holds phi
# (the coin rocks past 45 degrees and falls back)
ROCKING_CELLS = [(0.55, 8.0), (0.55, -8.0), (0.65, 4.0), (0.65, -4.0), (0.7, 16.0),
                 (0.8, 10.0), (0.8, -10.0), (0.15, 20.0)]


def early_stop_cells():
    grid = [(float(vy), float(vphi)) for vy in np.linspace(0.1, 0.8, 6)
            for vphi in np.linspace(-15.0, 15.0, 6)]
    return grid + ROCKING_CELLS


def check_early_stop(paper, name, vy, vphi):
    p = model_params(paper)
    scene = paper.with_overrides(method=name, vy=vy, vphi=vphi)
    early = simulate(scene)
    full = simulate(scene.with_overrides(stop_on_settle=False, t_end=2.0))
    assert early.settled and early.t_final < 2.0 and early.t_final == early.settle_time
    assert early.energy_final < paper.e_crit
    assert full.settled and full.t_final == pytest.approx(2.0)
    kinetic = PY.energies(p, full.final_state)[0]
    # at rest an adaptive step hovers at the contact mode's stability limit: the kinetic energy
    # fluctuates between 1e-15 and 4e-12 J (1e-11 to 1e-8 of E_crit), a numerical floor
    assert kinetic < 1e-7 * paper.e_crit, "the full run must end at rest"
    at_rest = PY.rounded_quarter_turns(full.final_state[2])
    assert PY.well_index(p, full.final_state[2]) == at_rest
    assert early.quarter_turns == at_rest, (vy, vphi)
    assert full.quarter_turns == at_rest  # the well at the settle time, reported at t_end
    return early


def test_early_stop_label_equals_label_at_rest(paper):
    mismatched_rounding = 0
    for vy, vphi in early_stop_cells():
        early = check_early_stop(paper, "event", vy, vphi)
        if early.rounded_quarter_turns != early.quarter_turns:
            mismatched_rounding += 1
    # the test is not vacuous: at the moment of settling, round(2 phi / pi) is wrong here
    assert mismatched_rounding >= 4


@pytest.mark.parametrize("vy,vphi", [(0.65, 4.0), (0.8, -10.0)])
def test_early_stop_label_fixed_step(paper, vy, vphi):
    check_early_stop(paper, "symplectic_euler", vy, vphi)


@pytest.mark.parametrize("name", [m.label for m in METHODS])
def test_unsettled_run_is_reported_unsettled(paper, name):
    scene = paper.with_overrides(method=name, vy=1.5, vphi=10.0, t_end=0.05)
    tr = simulate(scene)
    assert tr.status == Status.UNSETTLED and not tr.settled
    assert math.isnan(tr.settle_time)
    assert tr.t_final == pytest.approx(0.05)
    assert tr.energy_final > tr.e_crit
    assert tr.quarter_turns == PY.rounded_quarter_turns(tr.final_state[2])
    summary = tr.summary()
    assert summary["settled"] is False and summary["settle_time"] is None
    assert any("E_crit" in note for note in tr.notes)


def test_the_step_factor_reads_frexp_and_ldexp_from_the_bits():
    """Dormand-Prince 5(4)'s step-size factor takes err's mantissa and exponent, and the power of
    two it scales by, from the float's bits: the same factor, bit for bit, as the plainly
    written frexp and ldexp below, over the whole range of errors it meets (1e-10 up, and inf)."""
    from coincli.integrators import dopri

    fifth, two_fifths = dopri._FIFTH, dopri._TWO_FIFTHS

    def reference(err, largest):
        if err < 1e-10:
            return largest
        m, e = math.frexp(err)
        q = e // 5
        x = m - 0.75
        root = ((fifth[0] * x + fifth[1]) * x + fifth[2]) * x + fifth[3]
        return min(largest, max(0.2, 0.9 * math.ldexp(root * two_fifths[e - 5 * q], -q)))

    factor = PY[dopri.step_factor]
    rng = np.random.default_rng(0)
    errors = np.concatenate([np.geomspace(1e-11, 1e6, 4000), 10.0 ** rng.uniform(-10, 6, 4000),
                             [1e-10, 0.5, 1.0, 2.0 ** -33, 2.0 ** 20, 1e300, math.inf]])
    for err in errors:
        for largest in (1.0, 5.0):
            assert factor(float(err), 1.0, largest) == reference(float(err), largest), err
