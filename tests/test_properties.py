"""Property tests (hypothesis) where they pay: the range and resolution parsers, scene round
trips, tile coverage, and mirror symmetry of the outcome."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import coincli
from coincli.grid import make_grid, parse_pair, parse_range
from coincli.params import ParameterError, Scene, scene_from_dict

finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)


@given(finite, finite)
def test_parse_range_round_trip(a, b):
    lo, hi = sorted((a, b))
    if lo == hi:
        for text in (f"{lo!r}:{hi!r}", (lo, hi)):
            try:
                parse_range("vy", text)
            except ParameterError as exc:
                assert "empty range" in str(exc)
            else:
                raise AssertionError("an empty range was accepted")
        return
    assert parse_range("vy", f"{lo!r}:{hi!r}") == (lo, hi)
    assert parse_range("vy", f" {lo!r} : {hi!r} ") == (lo, hi)
    assert parse_range("vy", (lo, hi)) == (lo, hi)
    assert parse_range("vy", repr(lo)) == lo and parse_range("vy", lo) == lo


@given(st.text(max_size=12))
def test_parse_range_never_raises_anything_but_a_parameter_error(text):
    try:
        value = parse_range("vy", text)
    except ParameterError:
        return
    values = value if isinstance(value, tuple) else (value,)
    assert all(math.isfinite(v) for v in values)


@given(st.integers(1, 70000), st.integers(1, 70000))
def test_parse_pair(n, m):
    for text in (f"{n}x{m}", (n, m)):
        try:
            assert parse_pair("res", text) == (n, m)
        except ParameterError as exc:
            assert max(n, m) > 1 << 16, exc


scene_values = st.fixed_dictionaries({
    "diameter": st.floats(0.005, 0.1), "thickness_ratio": st.floats(0.01, 0.9),
    "mass": st.floats(1e-4, 0.1), "inertia": st.floats(1e-9, 1e-5), "k": st.floats(10, 1e6),
    "c": st.floats(0, 10), "g": st.floats(0.1, 30), "vy": finite, "vphi": finite,
    "method": st.sampled_from(["event", "dopri5", "rk4", "verlet", "symplectic_euler"]),
    "rtol": st.floats(1e-12, 1e-3), "stop_on_settle": st.booleans()})


@settings(deadline=None)
@given(scene_values)
def test_scene_round_trips_through_its_dict(values):
    values = dict(values)
    values["thickness"] = values["diameter"] * values.pop("thickness_ratio")
    scene = Scene().with_overrides(**values)
    back = scene_from_dict(scene.to_dict())
    assert back == scene.with_overrides(y0=scene.y0)  # y0 = r resolved in the dict
    assert back.to_dict() == scene.to_dict()


@settings(deadline=None)  # real grids: timing varies on a shared machine
@given(st.integers(2, 40), st.integers(2, 40), st.integers(1, 17), st.integers(1, 17))
def test_tiles_cover_every_cell_once(n0, n1, c0, c1):
    grid = make_grid(Scene(), {"vy": (0.1, 1.0), "vphi": (-5.0, 5.0)}, (n0, n1), (c0, c1))
    seen = np.zeros(grid.shape, int)
    rows = []
    for tile in grid.tiles():
        s0, s1 = grid.tile_slices(tile)
        seen[s0, s1] += 1
        states = grid.tile_states(tile)
        assert states.shape == (grid.tile_cells(tile), 6)
        rows.append(states)
    assert (seen == 1).all()
    every = grid.states()
    assert len(every) == n0 * n1
    # each cell's state is its coordinates, the fixed values elsewhere
    vy, vphi = np.meshgrid(grid.axes[0].coords, grid.axes[1].coords, indexing="ij")
    np.testing.assert_array_equal(every[:, 4], vy.ravel())
    np.testing.assert_array_equal(every[:, 5], vphi.ravel())
    assert sorted(map(tuple, np.concatenate(rows))) == sorted(map(tuple, every))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.floats(0.05, 1.2), st.floats(0.5, 20.0), st.floats(-0.3, 0.3))
def test_mirror_symmetry_of_the_outcome(vy, vphi, vx):
    """Mirroring the throw (x -> -x: vphi -> -vphi, vx -> -vx, phi0 -> -phi0) mirrors n."""
    scene = coincli.load_preset("paper").with_overrides(vy=vy, vphi=vphi, vx=vx)
    mirrored = scene.with_overrides(vphi=-vphi, vx=-vx)
    a, b = coincli.classify(scene), coincli.classify(mirrored)
    assert a.status == b.status
    assert a.quarter_turns == -b.quarter_turns
