"""The claims of docs/model.md that no other test checks: the slips of the paper's printed
equations, which mass its printed figures need, E_crit as the least potential energy on the
boundaries of the wells, the wells themselves, the standing-well thresholds, the flight bound of
conservative advancement, and what the throw of the paper's fig. 2 gives.

Most checks recompute from the raw numbers with plain formulas (and scipy), independent of the
kernels; where a claim is about the implementation the kernel is compared with them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from coincli import simulate
from coincli.enums import Status
from coincli.models import PAPER, model_params
from coincli.presets import load
from coincli.statics import analyse

G = 9.81
R_D, R_T = 0.01, 0.001  # m, half diameter and half thickness of the paper's coin
R = math.hypot(R_D, R_T)
PHI_CR = math.atan2(R_D, R_T)
M_PI_G = math.pi * 1e-3  # kg
K = 1.0e4  # N/m
C = 0.5  # N s/m
INERTIA = 7.06e-8  # kg m^2
PY = PAPER.kernels("python")  # the model's kernels as plain Python

# body coordinates of the corners in the order of coincli.models.rectangle (paper's corners 1..4)
BODY = [(R_D, -R_T), (-R_D, -R_T), (-R_D, R_T), (R_D, R_T)]


def rotate(phi, p):
    """R(phi) p, counter-clockwise."""
    c, s = math.cos(phi), math.sin(phi)
    return (c * p[0] - s * p[1], s * p[0] + c * p[1])


def printed_eq3(phi):
    """Corner offsets (d_xi, d_yi) exactly as printed in the paper's eq. (3)."""
    c, s = math.cos(phi), math.sin(phi)
    return [(R_D * c - R_T * s, R_D * s - R_T * c), (-R_D * c - R_T * s, -R_D * s - R_T * c),
            (-R_D * c + R_T * s, -R_D * s + R_T * c), (R_D * c + R_T * s, R_D * s + R_T * c)]


def printed_eq4(phi, vphi):
    """Corner velocities relative to the centroid, v_i - v, exactly as printed in eq. (4),
    with v_c = r vphi, sin(alpha) = r_t / r, cos(alpha) = r_d / r (eq. 5)."""
    c, s = math.cos(phi), math.sin(phi)
    sa, ca = R_T / R, R_D / R
    vc = R * vphi
    return [(-vc * (s * ca + c * sa), vc * (s * sa - c * ca)),
            (vc * (s * ca - c * sa), -vc * (s * sa + c * ca)),
            (vc * (s * ca - c * sa), -vc * (s * sa - c * ca)),
            (-vc * (s * ca - c * sa), vc * (s * sa + c * ca))]


def potential(y, phi, m, k):
    """U = m g y + sum over penetrating corners of k y_i^2 / 2 (rigid-body corners)."""
    u = m * G * y
    for p in BODY:
        yi = y + rotate(phi, p)[1]
        if yi < 0.0:
            u += 0.5 * k * yi * yi
    return u


def least_potential_at(phi, m, k):
    """min over y of U(y, phi), in closed form: U is convex and piecewise quadratic in y; with
    the j lowest corners in contact its minimum is at y = -(m g / k + sum of their d_yi) / j."""
    d = sorted(rotate(phi, p)[1] for p in BODY)
    for j in range(1, 5):
        y = -(m * G / k + sum(d[:j])) / j
        if y + d[j - 1] <= 0.0 and (j == 4 or y + d[j] >= 0.0):
            return m * G * y + 0.5 * k * sum((y + dy) ** 2 for dy in d[:j])
    raise AssertionError("no active set")


# -- eq. (3): as printed, not a rigid rotation ----------------------------------------------------

def test_printed_eq3_is_not_a_rigid_rotation():
    for phi in np.linspace(-4.0, 4.0, 41):
        d = printed_eq3(phi)
        c, s = math.cos(phi), math.sin(phi)
        for i, p in enumerate(BODY):
            # printed d_i = [[cos, sin], [sin, cos]] p_i, whose determinant is cos 2 phi
            assert d[i][0] == pytest.approx(c * p[0] + s * p[1], abs=1e-18)
            assert d[i][1] == pytest.approx(s * p[0] + c * p[1], abs=1e-18)
        d1_sq = d[0][0] ** 2 + d[0][1] ** 2
        assert d1_sq == pytest.approx(R**2 - 2 * R_D * R_T * math.sin(2 * phi), rel=1e-12)
    # at 45 degrees the printed corners all lie on the line d_x = d_y
    for dx, dy in printed_eq3(math.pi / 4):
        assert dx == pytest.approx(dy, abs=1e-17)
    # the largest deviation of |d_1| from r: sqrt(r^2 -+ 2 r_d r_t) at phi = -+45 deg
    assert math.sqrt(R**2 + 2 * R_D * R_T) == pytest.approx(R_D + R_T, rel=1e-12)
    assert math.sqrt(R**2 - 2 * R_D * R_T) == pytest.approx(R_D - R_T, rel=1e-12)
    # at phi = 0 printed and rigid agree
    for i, p in enumerate(BODY):
        assert printed_eq3(0.0)[i] == pytest.approx(p, abs=1e-18)


def test_implemented_corners_are_a_rigid_rotation():
    """The kernel's corner heights are y + (R(phi) p_i)_y, and |R(phi) p_i| = r."""
    p = model_params(load("paper").scene)
    heights = PAPER.kernels().corner_heights
    for phi in np.linspace(-7.0, 7.0, 57):
        out = heights(p, 0.003, math.cos(phi), math.sin(phi))
        for i, b in enumerate(BODY):
            d = rotate(phi, b)
            assert math.hypot(*d) == pytest.approx(R, rel=1e-14)
            assert out[i] == pytest.approx(0.003 + d[1], abs=1e-17)


# -- eq. (4): matches neither eq. (3) nor, for every corner, a rigid body --------------------------

def rigid_velocity(phi, vphi, p, sense=1.0):
    """d/dt R(sense * phi) p at angular velocity vphi: sense * vphi * (-d_y, d_x)."""
    dx, dy = rotate(sense * phi, p)
    return (-sense * vphi * dy, sense * vphi * dx)


def test_printed_eq4_is_not_the_derivative_of_eq3():
    vphi, h = 2.7, 1e-6
    for phi in (0.3, 1.1, 2.5, -0.8):
        v = printed_eq4(phi, vphi)
        ahead, behind = printed_eq3(phi + vphi * h), printed_eq3(phi - vphi * h)
        for i in range(4):
            dd = ((ahead[i][0] - behind[i][0]) / (2 * h), (ahead[i][1] - behind[i][1]) / (2 * h))
            assert max(abs(dd[0] - v[i][0]), abs(dd[1] - v[i][1])) > 1e-3 * R * vphi


def test_printed_eq4_corner_by_corner():
    """Printed v_4 and v_2 are the rigid velocities of corners 1 and 3; printed v_1 is that of
    corner 1 turning clockwise; printed v_3 is no rigid velocity at all (its length varies)."""
    vphi = 2.7
    for phi in np.linspace(-3.0, 3.0, 25):
        v = printed_eq4(phi, vphi)
        assert v[3] == pytest.approx(rigid_velocity(phi, vphi, BODY[0]), abs=1e-15)
        assert v[1] == pytest.approx(rigid_velocity(phi, vphi, BODY[2]), abs=1e-15)
        assert v[0] == pytest.approx(rigid_velocity(phi, vphi, BODY[0], sense=-1.0), abs=1e-15)
        v3_sq = v[2][0] ** 2 + v[2][1] ** 2
        assert v3_sq == pytest.approx(vphi**2 * (R**2 - 2 * R_D * R_T * math.sin(2 * phi)),
                                      rel=1e-12)
    # at phi = 0, where eq. (3) is right, printed v_1 is minus corner 1's rigid velocity
    v1 = printed_eq4(0.0, vphi)[0]
    assert v1 == pytest.approx(tuple(-x for x in rigid_velocity(0.0, vphi, BODY[0])), abs=1e-15)


def test_rigid_corner_velocity_is_the_derivative_of_its_position():
    vphi, h = 2.7, 1e-6
    for phi in (0.3, 1.1, 2.5, -0.8):
        for p in BODY:
            a, b = rotate(phi + vphi * h, p), rotate(phi - vphi * h, p)
            v = rigid_velocity(phi, vphi, p)
            assert (a[0] - b[0]) / (2 * h) == pytest.approx(v[0], rel=1e-8, abs=1e-12)
            assert (a[1] - b[1]) / (2 * h) == pytest.approx(v[1], rel=1e-8, abs=1e-12)


def test_energy_balance_of_the_implemented_forces():
    """dE/dt = -c sum |v_i|^2 over the penetrating corners, with the kernel's accelerations:
    the contact law, the moment of eq. (6) and the kinematics are consistent."""
    scene = load("paper").scene
    p = model_params(scene)
    rng = np.random.default_rng(11)
    checked = set()
    for _ in range(400):
        phi = rng.uniform(-7.0, 7.0)
        offsets = [rotate(phi, b)[1] for b in BODY]
        y = rng.uniform(-max(offsets) - 1e-4, -min(offsets) + 1e-4)
        vx, vy, vphi = rng.normal(0, 0.5), rng.normal(0, 0.5), rng.normal(0, 20.0)
        ax, ay, aphi = PY.accelerations_auto(p, (0.0, y, phi, vx, vy, vphi))
        de_dt = (M_PI_G * (vx * ax + vy * ay) + INERTIA * vphi * aphi + M_PI_G * G * vy)
        loss = 0.0
        n_pen = 0
        for b in BODY:
            dx, dy = rotate(phi, b)
            yi = y + dy
            if yi < 0.0:
                n_pen += 1
                vxi, vyi = vx - vphi * dy, vy + vphi * dx
                de_dt += K * yi * vyi
                loss += C * (vxi * vxi + vyi * vyi)
        checked.add(n_pen)
        scale = M_PI_G * G * abs(vy) + loss + K * R * R * abs(vphi) + 1e-12
        assert de_dt == pytest.approx(-loss, abs=1e-11 * scale)
    assert checked == {0, 1, 2, 3, 4}


# -- eq. (13) and the mass ---------------------------------------------------------------------

def test_printed_eq13_denominator_is_negative():
    w = M_PI_G * G
    printed = w / (2 * (R_D - R))
    fixed = w / (2 * (R - R_D))
    assert printed < 0 and printed == pytest.approx(-fixed)
    assert f"{fixed:.2f}" == "308.96"
    # r - r_d = r_t^2 / (r + r_d): small, so k_cr is large
    assert R - R_D == pytest.approx(R_T**2 / (R + R_D), rel=1e-9)


@pytest.mark.parametrize("mass,k_min,k_cr", [(M_PI_G, "154.9", "308.96"),
                                             (3.14e-3, "154.8", "308.80")])
def test_printed_figures_need_pi_grams(mass, k_min, k_cr):
    """Eqs. (9), (11), (12), (13) with m = pi g and m = 3.14 g: the paper prints 154.9 and
    308.96 N/m (pi g); the ratios 181.4 and 187.2 come out with either mass."""
    w = mass * G
    sink = w / (2 * K)
    assert f"{w * R / (2 * R_T**2):.1f}" == k_min
    assert f"{w / (2 * (R - R_D)):.2f}" == k_cr
    assert f"{(R - R_T) / (R - R_D):.1f}" == "181.4"
    assert f"{(R - R_T - sink) / (R - R_D - sink):.1f}" == "187.2"
    rep = analyse(load("paper").scene.with_overrides(mass=mass))
    assert f"{rep.k_min:.1f}" == k_min and f"{rep.k_cr:.2f}" == k_cr


def test_static_energies_with_the_springs_counted():
    """Eq. (10) counts the centroid's height only; with the springs' energy the three static
    states have m g r - (m g)^2 / 2k (on a corner), m g r_t - (m g)^2 / 4k (lying),
    m g r_d - (m g)^2 / 4k (standing), and the ratio of eq. (12) becomes 184.3."""
    w = M_PI_G * G
    on_corner = potential(R - w / K, PHI_CR, M_PI_G, K)
    lying = potential(R_T - w / (2 * K), 0.0, M_PI_G, K)
    standing = potential(R_D - w / (2 * K), math.pi / 2, M_PI_G, K)
    assert on_corner == pytest.approx(w * R - w * w / (2 * K), rel=1e-13)
    assert lying == pytest.approx(w * R_T - w * w / (4 * K), rel=1e-12)
    assert standing == pytest.approx(w * R_D - w * w / (4 * K), rel=1e-13)
    # the elastic part is what eq. (10) leaves out
    assert on_corner - w * (R - w / K) == pytest.approx(w * w / (2 * K), rel=1e-6)
    assert f"{(on_corner - lying) * 1e3:.5f}" == "0.27888"
    assert f"{(on_corner - standing) * 1e3:.6f}" == "0.001513"
    assert f"{(on_corner - lying) / (on_corner - standing):.1f}" == "184.3"


# -- k_min, E_crit and the wells -------------------------------------------------------------------

def test_heights_on_every_well_boundary():
    """On phi = +-phi_cr + j pi the corners sit at r, a, -a, -r about the centroid,
    a = (r_d^2 - r_t^2) / r; r - a = 2 r_t^2 / r."""
    a = (R_D**2 - R_T**2) / R
    assert R - a == pytest.approx(2 * R_T**2 / R, rel=1e-9)
    for j in range(-3, 4):
        for sign in (1.0, -1.0):
            phi = sign * PHI_CR + j * math.pi
            heights = sorted(rotate(phi, p)[1] for p in BODY)
            assert heights == pytest.approx([-R, -a, a, R], abs=1e-15)


def test_k_min_is_where_a_second_corner_touches_on_phi_cr():
    """On one corner at phi_cr the coin sinks by m g / k; the next corner is r - a = 2 r_t^2 / r
    higher, so it stays clear exactly when k >= m g r / (2 r_t^2) = k_min (eq. 11)."""
    w = M_PI_G * G
    k_min = w * R / (2 * R_T**2)
    a = (R_D**2 - R_T**2) / R
    for k, one_corner in ((k_min * 1.001, True), (k_min * 0.999, False)):
        y = R - w / k  # equilibrium height on the lowest corner alone
        assert (y - a >= 0.0) is one_corner


@pytest.mark.parametrize("k", [1.0e4, 1.0e3, 300.0, 170.0, 154.87])
def test_e_crit_is_the_least_potential_on_every_well_boundary(k):
    """For k >= k_min: min over y of U(y, phi) on each line phi = +-phi_cr + j pi is
    E_crit = m g (r - m g / 2k), reached on one corner sunk by m g / k (scipy, bounded)."""
    w = M_PI_G * G
    e_crit = w * (R - w / (2 * k))
    assert k >= w * R / (2 * R_T**2)
    for phi in (PHI_CR, -PHI_CR, math.pi - PHI_CR, math.pi + PHI_CR, -math.pi + PHI_CR,
                2 * math.pi + PHI_CR):
        res = minimize_scalar(lambda y, phi=phi: potential(y, phi, M_PI_G, k), bounds=(-0.02, 0.03),
                              method="bounded", options={"xatol": 1e-13})
        assert res.fun == pytest.approx(e_crit, rel=1e-10)
        assert res.x == pytest.approx(R - w / k, abs=1e-8)
        assert least_potential_at(phi, M_PI_G, k) == pytest.approx(e_crit, rel=1e-12)
    assert load("paper").scene.with_overrides(k=k).e_crit == pytest.approx(e_crit, rel=1e-14)


@pytest.mark.parametrize("k", [154.5, 150.0, 120.0])
def test_below_k_min_e_crit_is_a_lower_bound(k):
    """Below k_min the second corner carries part of the weight and the least potential on the
    boundary is higher than E_crit: the certificate stays valid, only not tight."""
    w = M_PI_G * G
    e_crit = w * (R - w / (2 * k))
    res = minimize_scalar(lambda y: potential(y, PHI_CR, M_PI_G, k), bounds=(-0.02, 0.03),
                          method="bounded", options={"xatol": 1e-13})
    assert res.fun > e_crit * (1 + 1e-9)
    assert least_potential_at(PHI_CR, M_PI_G, k) == pytest.approx(res.fun, rel=1e-10)



def test_one_rest_state_per_well():
    """k = 10 kN/m: the least potential over y, W(phi), rises strictly from 0 to phi_cr and falls
    strictly from phi_cr to pi/2. Rest states are the stationary points of W, so each well holds
    one, at j pi/2 (the other wells are images of these two under phi -> -phi, phi -> phi + pi)."""
    rising = [least_potential_at(phi, M_PI_G, K) for phi in np.linspace(0.0, PHI_CR, 4001)]
    falling = [least_potential_at(phi, M_PI_G, K)
               for phi in np.linspace(PHI_CR, math.pi / 2, 4001)]
    assert np.all(np.diff(rising) > 0.0)
    assert np.all(np.diff(falling) < 0.0)

def independent_well(phi):
    """The j whose well holds phi: |phi - j pi/2| < phi_cr (even j), < pi/2 - phi_cr (odd j)."""
    hits = []
    for j in range(int(phi / (math.pi / 2)) - 3, int(phi / (math.pi / 2)) + 4):
        half_width = PHI_CR if j % 2 == 0 else math.pi / 2 - PHI_CR
        if abs(phi - j * math.pi / 2) < half_width:
            hits.append(j)
    assert len(hits) <= 1, (phi, hits)  # the wells do not overlap
    return hits[0] if hits else None


def test_wells_tile_the_angle_axis_and_match_well_index():
    p = model_params(load("paper").scene)
    assert math.degrees(PHI_CR) == pytest.approx(84.2894, abs=1e-4)
    assert math.degrees(math.pi / 2 - PHI_CR) == pytest.approx(5.7106, abs=1e-4)
    rng = np.random.default_rng(5)
    for phi in rng.uniform(-20.0, 20.0, 4000):
        j = independent_well(phi)
        assert j is not None  # every angle off the boundaries is in exactly one well
        assert PY.well_index(p, phi) == j
    # the boundaries are +-phi_cr + j pi: the well changes there, from j to j + 1
    for j in range(-3, 4):
        for b in (PHI_CR + j * math.pi, -PHI_CR + j * math.pi):
            below, above = independent_well(b - 1e-9), independent_well(b + 1e-9)
            assert below is not None and above == below + 1
            assert PY.well_index(p, b - 1e-9) == below
            assert PY.well_index(p, b + 1e-9) == above


def test_well_and_rounding_differ_between_45_degrees_and_phi_cr():
    p = model_params(load("paper").scene)
    for deg in (46.0, 60.0, 84.0, -50.0, 180.0 + 70.0):
        phi = math.radians(deg)
        j_round = PY.rounded_quarter_turns(phi)
        assert j_round % 2 == 1  # rounding says standing
        assert PY.well_index(p, phi) % 2 == 0  # the coin is in a lying well
    for deg in (30.0, 85.0, 95.0, 180.0):
        phi = math.radians(deg)
        assert PY.well_index(p, phi) == PY.rounded_quarter_turns(phi)


# -- the standing well: k_cr / 2, and the rocking limit ------------------------------------------

def test_standing_rest_is_below_e_crit_iff_k_above_half_k_cr():
    w = M_PI_G * G
    k_cr = w / (2 * (R - R_D))
    k_lin = w * R_D / (2 * R_T**2)
    k_min = w * R / (2 * R_T**2)
    assert f"{k_cr / 2:.1f}" == "154.5" and f"{k_lin:.1f}" == "154.1"
    # k_cr / 2 = w (r + r_d) / (4 r_t^2) is the mean of k_lin and k_min
    assert k_cr / 2 == pytest.approx((k_lin + k_min) / 2, rel=1e-9)
    for k, below in ((k_cr / 2 * (1 + 1e-6), True), (k_cr / 2 * (1 - 1e-6), False)):
        standing = least_potential_at(math.pi / 2, M_PI_G, k)
        assert standing == pytest.approx(w * R_D - w * w / (4 * k), rel=1e-12)
        assert (standing < w * (R - w / (2 * k))) is below
    for k in (250.0, 170.0, 140.0):
        rep = analyse(load("paper").scene.with_overrides(k=k))
        assert (rep.standing_well_depth > 0) is (k > k_cr / 2)
        assert rep.k_stand_exact == pytest.approx(k_cr / 2, rel=1e-12)


def barrier_out_of_standing(k, n=4001):
    """Least energy with which a standing coin can reach the lying well: the maximum over
    phi in [phi_cr, pi/2] of min_y U(y, phi), minus the standing rest energy; and where it is."""
    phis = np.linspace(PHI_CR, math.pi / 2, n)
    least = np.array([least_potential_at(phi, M_PI_G, k) for phi in phis])
    top = int(np.argmax(least))
    return least[top] - least[-1], phis[top]


def test_standing_barrier_for_the_paper_and_near_the_thresholds():
    w = M_PI_G * G
    k_lin = w * R_D / (2 * R_T**2)
    # k = 10 kN/m: the barrier sits on phi_cr and is E_crit minus the standing rest energy
    depth, where = barrier_out_of_standing(K)
    assert where == PHI_CR
    assert depth == pytest.approx(w * (R - R_D) - w * w / (4 * K), rel=1e-9)
    # between k_lin and k_cr / 2 a (nanojoule) well remains, though its floor is above E_crit
    depth, where = barrier_out_of_standing(154.3)
    assert depth > 0 and where > PHI_CR
    assert w * R_D - w * w / (4 * 154.3) > w * (R - w / (2 * 154.3))
    # the standing pose is a local minimum of the potential iff k > k_lin = m g r_d / (2 r_t^2)
    for k, stable in ((k_lin * 1.001, True), (k_lin * 0.999, False)):
        rest = least_potential_at(math.pi / 2, M_PI_G, k)
        for tilt in (0.01, -0.01):
            assert (least_potential_at(math.pi / 2 + tilt, M_PI_G, k) > rest) is stable



def test_standing_coin_between_rocking_limit_and_half_k_cr_stays_standing():
    """At k = 154.3 N/m (above k_lin = 154.1, below k_cr / 2 = 154.5) a standing coin nudged by
    0.01 rad/s keeps standing: the potential has a standing minimum there. Its energy stays above
    E_crit, so no run can certify it: it is reported unsettled."""
    k = 154.3
    scene = load("paper").scene.with_overrides(k=k)
    w = scene.coin.mass * scene.g
    run = scene.with_overrides(y0=scene.coin.r_d - w / (2 * k), phi0=math.pi / 2, vphi=0.01,
                               t_end=5.0, stop_on_settle=False, rtol=1e-8)
    tr = simulate(run, sample_dt=0.01)
    assert tr.status == Status.UNSETTLED and tr.energy_final > scene.e_crit
    assert np.all(np.abs(np.degrees(tr.samples[:, 3]) - 90.0) < 0.6)
    assert abs(math.degrees(tr.final_state[2]) - 90.0) < 0.05

# -- conservative advancement: the flight bound ----------------------------------------------------

def test_flight_corner_height_lower_bound():
    """In flight a corner's height h obeys h'' = -g - vphi^2 d_yi >= -(g + vphi^2 r), so
    h(t + s) >= h + h' s - (g + vphi^2 r) s^2 / 2 for every s >= 0."""
    rng = np.random.default_rng(2)
    s = np.linspace(0.0, 0.05, 2001)
    for _ in range(200):
        y0, vy, phi0, vphi = (rng.uniform(0.0, 0.02), rng.normal(0, 1.0),
                              rng.uniform(-4, 4), rng.normal(0, 100.0))
        a = G + vphi * vphi * R
        for px, py in BODY:
            phi = phi0 + vphi * s
            h = y0 + vy * s - 0.5 * G * s * s + px * np.sin(phi) + py * np.cos(phi)
            h0 = y0 + px * math.sin(phi0) + py * math.cos(phi0)
            dh0 = vy + vphi * (px * math.cos(phi0) - py * math.sin(phi0))
            bound = h0 + dh0 * s - 0.5 * a * s * s
            assert np.all(h >= bound - 1e-15)


# -- the throw of fig. 2 -----------------------------------------------------------------------

@pytest.mark.parametrize("vy,rtol,n", [(1.197, 1e-6, 6), (1.197, 1e-9, 6), (1.1973, 1e-6, 6),
                                       (1.1974, 1e-6, 7), (1.1975, 1e-6, 7), (1.1975, 1e-9, 7)])
def test_fig2_throw_and_the_n7_island(vy, rtol, n):
    """The printed throw (y0 = r, vy0 = 1.197 m/s, vphi0 = 3.508 rad/s) lies after 6 quarter
    turns; from vy0 = 1.1974 m/s on the coin stands after 7, as in the paper."""
    tr = simulate(load("paper").scene.with_overrides(vy=vy, vphi=3.508, rtol=rtol))
    assert tr.settled and tr.quarter_turns == n


@pytest.mark.parametrize("vy,n", [(1.197, 6), (1.198, 7)])
def test_fig2_with_the_papers_method(vy, n):
    """Symplectic Euler at h = 1e-6 s for the full 2 s (the paper's method) agrees."""
    tr = simulate(load("paper-method").scene.with_overrides(vy=vy, vphi=3.508))
    assert tr.t_final == pytest.approx(2.0)
    assert tr.settled and tr.quarter_turns == n and tr.rounded_quarter_turns == n


def test_fig2_with_the_texts_mass():
    tr = simulate(load("paper").scene.with_overrides(vy=1.197, vphi=3.508, mass=3.14e-3))
    assert tr.settled and tr.quarter_turns == 6
