"""Friction at the corners (issue 47): the friction model's kernels against a slow, plainly
correct reference of the same law (tests/reference.py: its forces, and fixed-step RK4 without
events), and against physics known exactly: mu = 0 is the paper's model; a coin resting flat
feels no friction; friction never raises the energy, and the work it records is the energy it
took; a coin pushed along the foundation stops after v^2 / (2 mu g), within the regularization's
error; and the verification ladder converges with friction as without."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import coincli
from coincli.enums import Certainty, Status
from coincli.integrators.batch import new_control, unrecorded
from coincli.integrators.common import SAMPLE_COLUMNS
from coincli.labeller import Labeller
from coincli.models import FRICTION_MODEL, PAPER, model_of
from coincli.params import state_array

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import reference as R  # noqa: E402

MU, V_S = 0.3, 1e-3
MAP_REFERENCE = HERE / "data" / "paper-map-16.npz"  # made by tests/data/make_paper_map.py


@pytest.fixture(scope="module")
def shipped():
    """The paper's scene as shipped (its labels verified)."""
    return coincli.load_preset("paper")


@pytest.fixture(scope="module")
def friction(shipped):
    """The paper's scene with friction, a single pass."""
    return shipped.with_overrides(mu=MU, slip_velocity=V_S, verify=False)


@pytest.fixture(scope="module")
def kernels():
    return FRICTION_MODEL.kernels()


def random_state(rng, P, n_pen, slip=None):
    """A random state with exactly n_pen corners below the surface (heights from the
    reference); ``slip``: the horizontal speed of one of them, drawn at random (a corner
    sliding at about v_s, or sticking), else every speed at the scale of a throw."""
    phi = rng.uniform(-2 * math.pi, 2 * math.pi)
    dy = sorted(R.heights(P, 0.0, phi))
    if n_pen == 0:
        y = -dy[0] + rng.uniform(1e-7, 1e-2)
    elif n_pen == 4:
        y = -dy[3] - rng.uniform(1e-7, 1e-4)
    else:
        lo, hi = -dy[n_pen], -dy[n_pen - 1]
        y = lo + rng.uniform(0.05, 0.95) * (hi - lo)
    vx, vy, vphi = rng.normal(0, 0.3), rng.normal(0, 0.3), rng.normal(0, 20.0)
    if slip is not None and n_pen:
        corner = int(rng.choice(R.penetrating(P, y, phi)))
        vx = slip + vphi * R.offsets(P, phi)[corner][1]  # v_xi = vx - vphi d_yi = slip
    state = (rng.normal(0, 0.01), y, phi, vx, vy, vphi)
    assert len(R.penetrating(P, y, phi)) == n_pen
    return state


def params_of(scene):
    return FRICTION_MODEL.params(scene), R.FrictionParams.from_scene(scene)


def slips(P, state, mask):
    """(v_xi, N-side force -k y_i - c v_yi) of each corner of ``mask``, from the reference's
    kinematics."""
    _, y, phi, vx, vy, vphi = state
    out = []
    for i, (dx, dy) in enumerate(R.offsets(P, phi)):
        if mask >> i & 1:
            out.append((vx - vphi * dy, -P.k * (y + dy) - P.c * (vy + vphi * dx)))
    return out


# -- the reference itself -------------------------------------------------------------------------

def test_reference_friction_law_pins_its_kinematics(shipped):
    """The reference's friction law: at mu = 0 it is the reference's paper law to the bit;
    with friction, each corner's force opposes its slip and is at most mu N (Coulomb), and the
    energy rate its accelerations give is exactly the power of the dampers and of friction,
    -c sum |v_i|^2 + sum F_ti v_xi <= 0 (which pins the moment -d_yi F_ti and its sign)."""
    rng = np.random.default_rng(470)
    scene = shipped.with_overrides(mu=0.6, slip_velocity=V_S)
    P = R.FrictionParams.from_scene(scene)
    P0 = P._replace(mu=0.0)
    paper = R.Params.from_scene(scene)
    worst = 0.0
    for trial in range(400):
        state = random_state(rng, paper, int(rng.integers(0, 5)),
                             slip=rng.normal(0, 3 * V_S) if trial % 2 else None)
        assert R.friction_accelerations(P0, state) == R.accelerations(paper, state)
        _, y, phi, vx, vy, vphi = state
        dissipation = 0.0
        rate = P.m * (vx * R.friction_accelerations(P, state)[0]
                      + vy * (R.friction_accelerations(P, state)[1] + P.g)) \
            + P.inertia * vphi * R.friction_accelerations(P, state)[2]
        for i, (dx, dy) in enumerate(R.offsets(P, phi)):
            yi = y + dy
            if yi >= 0.0:
                assert R.friction_tangential(P, state, i) == 0.0
                continue
            vxi, vyi = vx - vphi * dy, vy + vphi * dx
            tangential = R.friction_tangential(P, state, i)
            normal = max(0.0, -P.k * yi - P.c * vyi)
            assert tangential * vxi <= 0.0 and abs(tangential) <= P.mu * normal
            rate += P.k * yi * vyi  # the spring's energy changes at k y_i v_yi
            dissipation += -P.c * (vxi * vxi + vyi * vyi) + tangential * vxi
        worst = max(worst, abs(rate - dissipation) / (abs(dissipation) + P.m * P.g))
        assert dissipation <= 0.0
    assert worst < 1e-12


# -- the kernels against the reference ------------------------------------------------------------

@pytest.mark.parametrize("n_pen", [0, 1, 2, 3, 4])
def test_accelerations_forces_and_power_match_reference(friction, kernels, n_pen):
    """At random states, sliding and sticking: the compiled friction kernels' accelerations (the
    contact set from the state, and any given mask: the law extended beyond the surface), each
    corner's friction force and the friction power equal the reference's, to rounding: 1e-12
    relative, and where a corner barely slips (v_xi = vx - vphi d_yi, a difference of larger
    numbers) or barely presses (N_i = -k (y + d_yi) - c v_yi likewise) to what the rounding of
    those differences makes of the force (the compiled kernels fuse multiplies and adds)."""
    p, P = params_of(friction)
    rng = np.random.default_rng(4700 + n_pen)
    eps = np.finfo(float).eps
    for trial in range(300):
        slip = (None, rng.normal(0, V_S), rng.normal(0, 0.01 * V_S))[trial % 3]
        state = random_state(rng, P, n_pen, slip)
        _, y, _, vx, vy, vphi = state
        c, s = math.cos(state[2]), math.sin(state[2])
        # each corner's force to rounding: its slip's and its normal force's, through the law
        slip_rounding, normal_rounding, rounding = [], [], []
        for dx, dy in R.offsets(P, state[2]):
            normal = max(0.0, -P.k * (y + dy) - P.c * (vy + vphi * dx))
            slip_rounding.append(4 * eps * (abs(vx) + abs(vphi * dy)))
            normal_rounding.append(4 * eps * (P.k * (abs(y) + P.r)
                                              + P.c * (abs(vy) + abs(vphi) * P.r)))
            rounding.append(P.mu * (normal * slip_rounding[-1] / P.v_s + normal_rounding[-1]))

        here = R.mask(P, state[1], state[2])
        mask = int(rng.integers(0, 16))
        for got, want, on in ((kernels.accelerations_auto(p, state),
                               R.friction_accelerations(P, state), here),
                              (kernels.contact_accelerations(p, mask, state, c, s),
                               R.friction_accelerations(P, state, mask), mask)):
            forces = sum(rounding[i] for i in range(4) if on >> i & 1)
            normals = sum(normal_rounding[i] for i in range(4) if on >> i & 1)
            got, want = np.array(got), np.array(want)
            bound = 1e-12 * (np.abs(want) + np.abs(want).max()) + np.array([
                forces / P.m, normals / P.m, (forces + normals) * P.r / P.inertia])
            assert np.all(np.abs(got - want) <= bound), (state, on, got, want, bound)
        power = power_rounding = 0.0
        for i, (_, dy) in enumerate(R.offsets(P, state[2])):
            tangential = R.friction_tangential(P, state, i)
            assert kernels.contact_forces(p, state, c, s, i)[3] == pytest.approx(
                tangential, rel=1e-12, abs=rounding[i])
            slip_i = vx - vphi * dy
            power += tangential * slip_i
            power_rounding += (rounding[i] + 1e-12 * abs(tangential)) * abs(slip_i) \
                + abs(tangential) * slip_rounding[i]
        assert kernels.sliding(p, here, state, c, s)[0] == pytest.approx(
            power, rel=1e-12, abs=power_rounding)


def jacobian_steps(v_s):
    """The central differences' steps along (y, phi, vx, vy, vphi), as (index in the state,
    step): each moves a corner's slip by at most 1e-4 v_s and its depth by 1e-9 m."""
    return ((1, 1e-9), (2, 1e-7), (3, 1e-4 * v_s), (4, 1e-7), (5, 1e-2 * v_s))


@pytest.mark.parametrize("mu,v_s", [(MU, V_S), (1.0, 1e-4)])
def test_contact_jacobian_matches_central_differences(shipped, kernels, mu, v_s):
    """The friction model's contact_jacobian (what Rodas5P steps with) equals central
    differences of the reference's accelerations in a fixed mode, where friction acts: away
    from the kink of max(0, N) and with every corner of the mode either sliding (|v_xi| >
    30 v_s) or sticking (|v_xi| < v_s / 30), on both sides of the regularization."""
    scene = shipped.with_overrides(mu=mu, slip_velocity=v_s)
    p, P = params_of(scene)
    rng = np.random.default_rng(47_000)
    checked = {"sliding": 0, "sticking": 0}
    while min(checked.values()) < 60:
        n_pen = int(rng.integers(1, 5))
        state = random_state(rng, P, n_pen, slip=rng.normal(0, 0.01 * v_s)
                             if rng.random() < 0.5 else None)
        mask = R.mask(P, state[1], state[2])
        corners = slips(P, state, mask)
        if any(abs(normal) < 1e-2 * P.m * P.g for _, normal in corners):
            continue  # near the kink of max(0, N)
        if any(v_s / 30 < abs(w) < 30 * v_s for w, normal in corners if normal > 0):
            continue  # the bend of the regularization
        pushing = [w for w, normal in corners if normal > 0]
        if not pushing:
            continue  # no friction at all
        kind = "sticking" if min(abs(w) for w in pushing) < v_s else "sliding"
        checked[kind] += 1
        c, s = math.cos(state[2]), math.sin(state[2])
        aq, av = kernels.contact_jacobian(p, mask, state, c, s)
        rows = np.array([1.0, 1.0, P.r])  # (a_x, a_y, r a_phi): accelerations in m/s^2
        analytic = np.zeros((3, 5))
        analytic[:, 0], analytic[:, 1] = aq[0::2], aq[1::2]
        analytic[:, 2:] = np.reshape(av, (3, 3))
        analytic *= rows[:, None]
        numeric = np.zeros((3, 5))
        rounding = np.zeros(5)  # of each column's differences: a few ulps of a over 2 h
        size = np.abs(np.array(R.friction_accelerations(P, state, mask)) * rows).max()
        for col, (index, h) in enumerate(jacobian_steps(v_s)):
            up, down = list(state), list(state)
            up[index] += h
            down[index] -= h
            numeric[:, col] = rows * (np.array(R.friction_accelerations(P, tuple(up), mask))
                                      - np.array(R.friction_accelerations(P, tuple(down),
                                                                          mask))) / (2 * h)
            rounding[col] = 8 * np.finfo(float).eps * size / (2 * h)
        scale = np.linalg.norm(numeric, axis=0)
        for col in range(5):  # each derivative direction on its own scale
            assert np.linalg.norm(analytic[:, col] - numeric[:, col]) <= 1e-6 * scale[col] \
                + rounding[col], (kind, mask, state, col, analytic[:, col], numeric[:, col])


# -- mu = 0 is the paper's model ------------------------------------------------------------------

def test_mu_0_runs_the_papers_model(shipped):
    """A scene without friction (mu = 0, the default, or given) runs the paper's model, with
    the paper's ladder (event, then event_dop853); a scene with friction the friction model,
    whose ladder climbs on event_rodas."""
    assert shipped.foundation.mu == 0.0
    for scene in (shipped, shipped.with_overrides(mu=0.0), shipped.with_overrides(mu=0)):
        assert model_of(scene) is PAPER
        labeller = Labeller.of(scene)
        assert labeller.model == "paper" and type(labeller.params).__name__ == "PaperParams"
        assert [m.label for m in labeller.ladder.methods[:2]] == ["event", "event_dop853"]
    with_friction = shipped.with_overrides(mu=MU)
    assert model_of(with_friction) is FRICTION_MODEL
    labeller = Labeller.of(with_friction)
    assert labeller.model == "friction" and labeller.params.mu == MU
    assert {m.label for m in labeller.ladder.methods} == {"event_rodas"}


def test_mu_0_map_is_unchanged(shipped):
    """The paper's default map at 16 x 16 (labels, statuses, settle times, steps, certainty,
    rungs) is what the paper's kernels computed before friction was added (stored: see
    tests/data/make_paper_map.py), at mu = 0 given or by default. (The whole check against
    0.10.0 is benchmarks/same_numbers.py.)"""
    stored = np.load(MAP_REFERENCE)
    for scene in (shipped, shipped.with_overrides(mu=0.0, slip_velocity=1e-4)):
        ds = coincli.basin(scene, res=16)
        for name in ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung"):
            np.testing.assert_array_equal(ds[name].values, stored[name], err_msg=name)


def test_vanishing_friction_gives_the_papers_labels(shipped):
    """The friction model at mu = 1e-12 (its own kernels, drivers and ladder: event_rodas) gives
    the paper's verified labels, where both are certain, on a few dozen throws of the map."""
    rng = np.random.default_rng(12)
    throws = np.column_stack([rng.uniform(0.05, 2.0, 40), rng.uniform(-20, 20, 40)])
    states = np.array([state_array(shipped.with_overrides(vy=vy, vphi=vphi))
                       for vy, vphi in throws])
    paper = Labeller.of(shipped).label(states)
    tiny = Labeller.of(shipped.with_overrides(mu=1e-12))
    assert tiny.model == "friction"
    faint = tiny.label(states)
    both = (paper.certainty == Certainty.CERTAIN) & (faint.certainty == Certainty.CERTAIN)
    assert both.sum() >= 0.9 * len(states)
    np.testing.assert_array_equal(faint.quarter_turns[both], paper.quarter_turns[both])
    np.testing.assert_allclose(faint.settle_time[both], paper.settle_time[both], atol=1e-2)


# -- whole throws with friction against fixed-step RK4 of the reference ---------------------------

# RK4 of the reference at two steps (each half the other); a throw's reference label is the one
# both settle with, within SETTLE_AGREE seconds of each other (the ladder's own rule), by
# RK4_HORIZON (the long throws, which roll for a second and more, are beyond a test's time)
RK4_STEPS = (4e-7, 2e-7)
RK4_HORIZON = 0.8  # s
SETTLE_AGREE = 1e-2  # s
THROWS, PARTS = 48, 3  # throws of each mu, in parts of a test each


@pytest.fixture(scope="module")
def compiled_reference():
    return R.compiled_friction()


def map_throws(count, seed):
    """``count`` throws drawn over the paper's map: vy0 0.05-2 m/s, vphi0 +-20 rad/s."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(0.05, 2.0, count), rng.uniform(-20.0, 20.0, count)])


@pytest.mark.parametrize("part", range(PARTS))
@pytest.mark.parametrize("mu", [MU, 1.0])
def test_verified_labels_agree_with_rk4_of_the_reference(shipped, compiled_reference, mu,
                                                          part):
    """Whole throws of the paper's map with friction, labelled by the verified ladder: every
    certain label equals the one fixed-step RK4 of the reference law (no events, the contact set
    from the penetration at each stage) settles with, at two steps, wherever those agree."""
    scene = shipped.with_overrides(mu=mu, slip_velocity=V_S)
    P = R.FrictionParams.from_scene(scene)
    throws = map_throws(THROWS, 47 + int(mu * 10))[part::PARTS]
    states = np.array([state_array(scene.with_overrides(vy=vy, vphi=vphi))
                       for vy, vphi in throws])
    verified = Labeller.of(scene).label(states)
    compared = 0
    contradicted = []
    for row, state in enumerate(states):
        runs = [compiled_reference.rk4_friction_throw(P, tuple(state), h, RK4_HORIZON)
                for h in RK4_STEPS]
        (label, status, settle), (label2, status2, settle2) = runs
        converged = (status == status2 == R.SETTLED and label == label2
                     and abs(settle - settle2) <= SETTLE_AGREE)
        if not converged or verified.certainty[row] != Certainty.CERTAIN:
            continue
        compared += 1
        if verified.quarter_turns[row] != label:
            contradicted.append((tuple(throws[row]), int(verified.quarter_turns[row]), runs))
    assert not contradicted, contradicted
    assert compared >= 0.4 * len(throws), f"only {compared} of {len(throws)} throws compared"


# -- physics known exactly ------------------------------------------------------------------------

def resting(scene):
    """A coin lying flat at its equilibrium (y = r_t - m g / 2k, phi = 0), at rest."""
    weight = scene.coin.mass * scene.g
    return (0.0, scene.coin.r_t - weight / (2 * scene.foundation.k), 0.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize("method,setting", [("event", {"rtol": 1e-10}), ("rk4", {"dt": 1e-6})])
def test_coin_resting_flat_feels_no_friction(friction, kernels, method, setting):
    """A coin resting flat at equilibrium feels no friction: its corners' friction forces are
    zero (they do not slip) and its accelerations those of the paper's law; left 0.5 s, it
    stays where it is, to rounding."""
    scene = friction.with_overrides(mu=1.0)  # the most friction there is to feel
    p = FRICTION_MODEL.params(scene)
    state = resting(scene)
    for i in range(4):
        assert kernels.contact_forces(p, state, 1.0, 0.0, i)[3] == 0.0
        assert R.friction_tangential(R.FrictionParams.from_scene(scene), state, i) == 0.0
    assert kernels.accelerations_auto(p, state) == PAPER.kernels().accelerations_auto(
        PAPER.params(scene), state)
    run = scene.with_overrides(method=method, t_end=0.5, stop_on_settle=False, **setting)
    labeller = Labeller.of(run)
    assert labeller.model == "friction"
    final, status = labeller.final_state(np.array(state))
    assert status == Status.SETTLED
    sink = scene.coin.mass * scene.g / (2 * scene.foundation.k)
    assert final[0] == 0.0 and final[3] == 0.0  # no horizontal force, ever
    # the springs balance the weight to rounding (a residue of 1e-13 m/s^2): so does the state
    assert abs(final[1] - state[1]) < 1e-9 * sink and abs(final[4]) < 1e-14
    assert abs(final[2]) < 1e-15 and abs(final[5]) < 1e-13


def recorded_run(scene, state, sample_dt):
    """One run of ``scene``'s first rung from ``state``, recorded: (RunResult, samples)."""
    labeller = Labeller.of(scene, sample_dt=sample_dt)
    samples = np.empty((int(scene.integration.t_end / sample_dt) + 10, SAMPLE_COLUMNS))
    _, events, final = unrecorded()
    result = labeller.run(labeller.rung_settings(0), np.ascontiguousarray(state, dtype=float),
                          samples, events, final, new_control())
    return result, samples[:result.n_samples], final


@pytest.fixture(scope="module")
def undamped_throw(friction):
    """A throw with friction and no damper (c = 0): whatever energy it loses, friction took.
    Bouncing and spinning for 0.5 s (undamped, it never settles)."""
    scene = friction.with_overrides(c=0.0, vy=1.0, vphi=5.0, rtol=1e-10, t_end=0.5,
                                    stop_on_settle=False)
    P = R.FrictionParams.from_scene(scene)
    result, samples, final = recorded_run(scene, state_array(scene), 1e-4)
    energy = np.array([R.friction_energy(P, row[1:]) for row in samples])
    return scene, result, samples, energy


def test_friction_never_raises_the_energy(undamped_throw):
    """With c = 0 and mu > 0 the total energy along a recorded throw never rises (beyond the
    integrator's tolerance), and friction does take a good part of it."""
    scene, result, samples, energy = undamped_throw
    assert result.status == Status.UNSETTLED and samples[-1, 0] == pytest.approx(0.5)
    assert np.diff(energy).max() < 1e-9 * energy[0]
    assert energy[-1] < 0.9 * energy[0]


def test_friction_work_is_the_energy_lost(undamped_throw):
    """With c = 0 the friction work a run records (integrated on each step's continuous
    extension) is the energy the coin lost."""
    scene, result, samples, energy = undamped_throw
    lost = energy[0] - energy[-1]
    assert result.friction_work > 0.0
    assert result.friction_work == pytest.approx(lost, rel=1e-6)
    assert result.sliding_work * MU >= result.friction_work  # |F_t| <= mu N


def stopping_distance(v, mu, g, v_s):
    """Where a flat coin pushed at v stops under the regularized law, its friction -mu m g w /
    sqrt(w^2 + v_s^2) at speed w: x = (1 / (mu g)) int_0^v sqrt(w^2 + v_s^2) dw (dx = w dt and
    dw = -mu g w / sqrt(w^2 + v_s^2) dt). That is Coulomb's v^2 / (2 mu g) times 1 + (v_s / v)^2
    (1/2 + ln(2 v / v_s)) to leading order: the regularization's error. Of it, the coin slides
    the last 1.15 v_s^2 / (mu g) slower than v_s, for ever in principle: below v_s its speed
    falls by e every v_s / (mu g) seconds."""
    return (v * math.sqrt(v * v + v_s * v_s) + v_s * v_s * math.asinh(v / v_s)) / (2 * mu * g)


def test_pushed_coin_stops_after_v2_over_2_mu_g(friction):
    """c = 0: a coin resting flat at equilibrium, pushed along at v = 0.2 m/s, stops after
    v^2 / (2 mu g) within the regularization's error, which shrinks with v_s (1 % at v_s = 1e-2,
    2e-4 at 1e-3, 2e-6 at 1e-4): its x, once it has stopped, is the regularized law's stopping
    distance (above), to within how far the rocking its friction torque starts moves the
    centroid from its corners, r_t |phi| (the torque only tilts a thin coin by micro-radians);
    it stays there, the corners stuck; RK4 of the reference stops it at the same x; and the
    friction work recorded is the kinetic energy it had."""
    v, mu = 0.2, MU
    errors = []
    for v_s in (1e-2, 1e-3, 1e-4):
        scene = friction.with_overrides(c=0.0, slip_velocity=v_s, rtol=1e-10)
        g, r_t = scene.g, scene.coin.r_t
        quiet = v / (mu * g) + 10 * v_s / (mu * g)  # slid, then 10 e-folds below v_s
        t_end = quiet + 20 * v_s / (mu * g)
        state = resting(scene)[:3] + (v, 0.0, 0.0)
        result, samples, final = recorded_run(
            scene.with_overrides(t_end=t_end, stop_on_settle=False), state, t_end / 1000)
        coulomb = v * v / (2 * mu * g)
        regularized = stopping_distance(v, mu, g, v_s)
        tilt = np.abs(samples[:, 3]).max()
        assert tilt < 2e-5  # phi: rocked, not tipped
        rocking = r_t * tilt  # how far the centroid moves about its stuck corners
        assert abs(final[0] - regularized) < rocking
        late = samples[samples[:, 0] >= quiet]
        assert np.abs(late[:, 1] - final[0]).max() < 2 * rocking  # stopped
        assert np.abs(late[:, 4]).max() < 2 * r_t * np.abs(late[:, 6]).max() + 1e-3 * v_s
        error = final[0] / coulomb - 1
        estimate = (v_s / v) ** 2 * (0.5 + math.log(2 * v / v_s))
        assert abs(error - estimate) < 0.01 * estimate + rocking / coulomb
        errors.append(error)
        P = R.FrictionParams.from_scene(scene)
        h = 1e-5
        ref = R.integrate_friction(P, state, h, int(round(t_end / h)))
        assert abs(ref[0] - regularized) < rocking and abs(ref[0] - final[0]) < rocking
        assert result.friction_work == pytest.approx(
            R.friction_energy(P, state) - R.friction_energy(P, final), rel=1e-8)
        assert result.friction_work == pytest.approx(0.5 * P.m * v * v, rel=1e-5)
    assert 0 < errors[2] < errors[1] / 30 and errors[1] < errors[0] / 30 and errors[0] < 0.011


# -- the ladder converges with friction as without -----------------------------------------------

def test_ladder_converges_with_friction(shipped):
    """A few dozen throws of the map at mu = 0.3: the event_rodas ladder makes most labels
    certain (as many as without friction, give or take a few), and its certain labels are
    those of event_rodas at rtol 1e-11 wherever that single pass settles."""
    scene = shipped.with_overrides(mu=MU, slip_velocity=V_S)
    throws = map_throws(48, 4747)
    states = np.array([state_array(scene.with_overrides(vy=vy, vphi=vphi))
                       for vy, vphi in throws])
    verified = Labeller.of(scene).label(states)
    certain = verified.certainty == Certainty.CERTAIN
    without = Labeller.of(shipped).label(states).certainty == Certainty.CERTAIN
    assert certain.mean() >= 0.9 and certain.sum() >= without.sum() - 3
    tight = Labeller.of(scene.with_overrides(method="event_rodas", rtol=1e-11, verify=False))
    single = tight.label(states)
    judged = certain & (single.status == Status.SETTLED)
    assert judged.sum() >= 0.85 * len(states)
    np.testing.assert_array_equal(verified.quarter_turns[judged], single.quarter_turns[judged])


@pytest.mark.parametrize("method", ["symplectic_euler", "verlet", "rk4"])
def test_the_stable_step_sees_the_stick(shipped, method):
    """A fixed step takes friction explicitly: at rest a stick is a decay of the slip at rate
    mu g / v_s (1 + m d_y^2 / I), which bounds the step where it is faster than the rocking.
    The bound for a lying coin is the step linearized at rest under the friction law, and a
    step beyond the standing coin's (the stiffer) is refused in one line, naming the stick."""
    from coincli import accuracy as acc
    from coincli.integrators import METHODS
    from coincli.models import stick_rate
    from coincli.params import ParameterError

    info = METHODS[coincli.Method.parse(method)]
    paper = shipped.with_overrides(method=method)
    assert stick_rate(paper) == 0.0
    scene = paper.with_overrides(mu=1.0, slip_velocity=1e-4)
    coin = scene.coin
    lying = 1.0 * scene.g / 1e-4 * (1 + coin.mass * coin.r_t ** 2 / coin.inertia)
    standing = 1.0 * scene.g / 1e-4 * (1 + coin.mass * coin.r_d ** 2 / coin.inertia)
    assert stick_rate(scene) == pytest.approx(standing, rel=1e-12)
    assert info.stable_step(scene) == pytest.approx(info.decay_limit / standing, rel=1e-12)
    assert acc.linear_limit(scene, method) == pytest.approx(info.decay_limit / lying, rel=0.02)
    with pytest.raises(ParameterError, match="friction's stick at rest"):
        coincli.simulate(scene.with_overrides(dt=1.01 * info.stable_step(scene)))
