"""The event method with Hairer's DOP853 in contact (``event_dop853``, the verified ladder's upper
rungs): its tableau satisfies the order conditions, the driver built on it converges at its order
on a smooth contact problem, takes fewer steps than Dormand-Prince 5(4) for a smaller error, and
finds the same contact events and labels."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from test_integrators import run_smooth, smooth_error

from coincli import simulate
from coincli.integrators import dop853, info

# -- order conditions --------------------------------------------------------------------------

@cache
def trees(n: int) -> tuple:
    """The rooted trees with n nodes, each a sorted tuple of its subtrees."""
    if n == 1:
        return ((),)
    found = set()

    def forests(m, smallest):
        if m == 0:
            yield ()
            return
        for k in range(smallest[0], m + 1):
            for i, t in enumerate(trees(k)):
                if (k, i) >= smallest:
                    for rest in forests(m - k, (k, i)):
                        yield (t, *rest)

    for forest in forests(n - 1, (1, 0)):
        found.add(tuple(sorted(forest, key=repr)))
    return tuple(sorted(found, key=repr))


def gamma(t) -> int:
    out = 1 + sum(_size(c) for c in t)
    for c in t:
        out *= gamma(c)
    return out


def _size(t) -> int:
    return 1 + sum(_size(c) for c in t)


def elementary_weight(a, b, t) -> float:
    def g(t):
        v = np.ones(a.shape[0])
        for c in t:
            v = v * (a @ g(c))
        return v

    return float(b @ g(t))


def satisfied_order(a, b, theta=1.0, upto=9) -> int:
    """The largest p such that b satisfies every order condition up to p (at fraction theta of
    the step, for a continuous extension), to rounding of the coefficients' magnitude."""
    tol = 1e-13 * max(1.0, np.abs(a).max(), np.abs(b).max())
    for n in range(1, upto + 1):
        for t in trees(n):
            if abs(elementary_weight(a, b, t) - theta**n / gamma(t)) > tol * 10:
                return n - 1
    return upto


def tableau(rows: dict, n: int) -> np.ndarray:
    """Butcher matrix from {stage: (coefficients, the stages they multiply)} (1-based)."""
    a = np.zeros((n, n))
    for i, (coefficients, columns) in rows.items():
        for value, j in zip(coefficients, columns, strict=True):
            a[i - 1, j - 1] = value
    return a


def weights(n, *terms) -> np.ndarray:
    w = np.zeros(n)
    for coefficients, columns in terms:
        for value, j in zip(coefficients, columns, strict=True):
            w[j - 1] += value
    return w


def test_trees_are_counted_right():
    assert [len(trees(n)) for n in range(1, 9)] == [1, 1, 2, 4, 9, 20, 48, 115]


DOP853_ROWS = {2: (1,), 3: (1, 2), 4: (1, 3), 5: (1, 3, 4), 6: (1, 4, 5), 7: (1, 4, 5, 6),
               8: (1, 4, 5, 6, 7), 9: (1, 4, 5, 6, 7, 8), 10: (1, 4, 5, 6, 7, 8, 9),
               11: (1, 4, 5, 6, 7, 8, 9, 10), 12: (1, 4, 5, 6, 7, 8, 9, 10, 11),
               14: (1, 7, 8, 9, 10, 11, 12, 13), 15: (1, 6, 7, 8, 11, 12, 13, 14),
               16: (1, 6, 7, 8, 9, 13, 14, 15)}
DOP853_B = (1, 6, 7, 8, 9, 10, 11, 12)
DOP853_D = (1, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16)


def test_dop853_order_conditions():
    rows = {i: (getattr(dop853, f"A{i}"), cols) for i, cols in DOP853_ROWS.items()}
    rows[13] = (dop853.B, DOP853_B)
    a = tableau(rows, 16)
    step = a[:13, :13]
    b = weights(13, (dop853.B, DOP853_B))
    assert satisfied_order(step, b) == 8
    assert satisfied_order(step, b - weights(13, (dop853.E5, DOP853_B))) == 5
    assert satisfied_order(step, b - weights(13, (dop853.E3, DOP853_B))) == 3
    # contd8: theta (F0 + u (F1 + theta (F2 + u (F3 + theta (F4 + u (F5 + theta F6)))))),
    # F0 = h b.k, F1 = h k1 - F0, F2 = 2 F0 - h (k13 + k1), F3..F6 = h D.k
    b16 = weights(16, (dop853.B, DOP853_B))
    e1, e13 = np.eye(16)[0], np.eye(16)[12]
    f = [b16, e1 - b16, 2 * b16 - e1 - e13] + [weights(16, (getattr(dop853, f"D{j}"), DOP853_D))
                                               for j in (4, 5, 6, 7)]
    for theta in (0.25, 0.6, 1.0):
        u = 1.0 - theta
        w = f[6]
        for j in range(5, -1, -1):
            w = f[j] + (theta if j % 2 else u) * w
        assert satisfied_order(a, theta * w, theta) >= 7


# -- the driver with DOP853 ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def smooth_reference_tight(paper):
    """The smooth problem by DOP853 at rtol 1e-13 (2e-11 from RK4 at h 1e-7: rather use it,
    since the pairs' errors go below RK4's own)."""
    return run_smooth(paper, "event_dop853", rtol=1e-13)[0]


@pytest.mark.parametrize("name", ["event", "event_dop853"])
def test_pair_convergence_order(paper, smooth_reference_tight, name):
    """Error against steps on the smooth contact problem falls like steps^-order (an adaptive
    run is up to about one order steeper before its asymptotic range), and a decade of rtol
    buys about a decade of error."""
    rtols = np.geomspace(1e-8, 1e-11, 4)  # the asymptotic range (errors above 2e-11)
    errors, steps = [], []
    for rtol in rtols:
        final, n = run_smooth(paper, name, rtol=rtol)
        errors.append(smooth_error(final, smooth_reference_tight))
        steps.append(n)
    for i in range(len(errors) - 1):
        assert 3.0 < errors[i] / errors[i + 1] < 40.0, errors
    slope = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    order = info(name).order
    assert order - 0.5 < slope < order + 1.7, f"{name}: error ~ steps^-{slope:.2f}"


def test_dop853_takes_fewer_steps(paper):
    """At rtol 1e-9 on the smooth problem DOP853 takes fewer steps than DP5, and is more
    accurate."""
    ref = run_smooth(paper, "event_dop853", rtol=1e-13)[0]
    (dp5, dp5_steps), (dop, dop_steps) = (run_smooth(paper, name, rtol=1e-9)
                                          for name in ("event", "event_dop853"))
    assert dop_steps < dp5_steps / 2, (dop_steps, dp5_steps)
    assert smooth_error(dop, ref) < smooth_error(dp5, ref)


EVENT_THROWS = [dict(vy=1.197, vphi=3.508), dict(vy=0.5, vphi=-12.0), dict(vy=0.8, vphi=7.0),
                dict(vy=1.9, vphi=17.0, vx=0.2)]


def test_event_times_agree_with_dopri(paper):
    """Over the first impacts (before chaos amplifies differences), DOP853 at rtol 1e-10
    finds the same onsets and lift-offs of the same corners as DP5 at rtol 1e-13, at the same
    times (DP5's own error at 1e-10 is up to 3e-9 s by the 8th event), in the same states."""
    scale = np.array([paper.coin.r, paper.coin.r, 1.0, 1.0, 1.0, 1.0 / paper.coin.r])
    for throw in EVENT_THROWS:
        scene = paper.with_overrides(stop_on_settle=False, t_end=0.6, **throw)
        ref = simulate(scene.with_overrides(method="event", rtol=1e-13),
                       record_events=True).events[:8]
        ev = simulate(scene.with_overrides(method="event_dop853", rtol=1e-10),
                      record_events=True).events
        assert len(ref) == 8 and len(ev) >= 8
        np.testing.assert_array_equal(ev[:8, 1:3], ref[:, 1:3])
        np.testing.assert_allclose(ev[:8, 0], ref[:, 0], rtol=0, atol=5e-9)
        np.testing.assert_allclose(ev[:8, 3:] / scale, ref[:, 3:] / scale, rtol=0, atol=1e-6)


def test_same_labels_as_dopri_at_tight_tolerance(paper):
    """Labels of a few throws at rtol 1e-10 equal DP5's at 1e-10."""
    for vy, vphi in [(0.4, 6.0), (0.6, -9.0), (0.75, 3.0), (1.197, 3.508), (1.5, -15.0)]:
        scene = paper.with_overrides(rtol=1e-10, vy=vy, vphi=vphi, verify=False)
        a = simulate(scene.with_overrides(method="event"))
        b = simulate(scene.with_overrides(method="event_dop853"))
        assert a.settled and b.settled
        assert a.quarter_turns == b.quarter_turns, (vy, vphi)


def test_the_driver_compiled_first_is_the_one_integrate_calls():
    """A first compilation builds the DOP853 driver first (Labeller.compile_all), from arrays
    typed as integrate passes them: had the types differed, integrate would compile a second
    specialisation of its own. The driver holds one specialisation, looked up in the cache
    once (loaded, or compiled if this process made the cache) and found in memory after."""
    from dataclasses import replace

    from coincli.enums import Method
    from coincli.integrators.pairs import integrate_adaptive_dop853
    from coincli.labeller import Labeller
    from coincli.models import PAPER
    from coincli.params import Scene

    driver = PAPER.kernels()[integrate_adaptive_dop853]
    scene = Scene()
    labeller = Labeller.of(scene)
    # a short DOP853 throw of the default scene (only the argument types matter)
    short = replace(labeller, settings=labeller.settings._replace(
        method=int(Method.EVENT_DOP853), t_end=labeller.settings.dt * 4))
    # integrate, which calls the driver: loaded
    short.final_state(np.array([0.0, scene.y0, 0.0, 0.0, 1.0, 3.0]))
    labeller.compile_all()  # what a first compilation does first, in this process
    stats = driver.stats  # numba's public counts of this dispatcher's cache look-ups
    assert sum(stats.cache_hits.values()) + sum(stats.cache_misses.values()) == 1, stats
    assert len(driver.signatures) == 1
