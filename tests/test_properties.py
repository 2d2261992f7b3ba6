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


@settings(deadline=None)
@given(st.integers(2, 40), st.integers(2, 40), st.integers(1, 17), st.integers(1, 17),
       st.sampled_from([("vy", "vphi"), ("vx", "vphi"), ("phi0", "vy")]))
def test_mirror_pairs_cover_every_tile_once(n0, n1, c0, c1, dims):
    """The tiles a mirrored sweep computes, with their mirror images, are every tile once; a
    tile's mirror holds the mirror cells; the cells computed are counted right."""
    ranges = {"vy": (0.1, 1.0), "vx": (-0.5, 0.5), "vphi": (-5.0, 5.0), "phi0": (-1.0, 1.0)}
    grid = make_grid(Scene(), {d: ranges[d] for d in dims}, (n0, n1), (c0, c1))
    filled = [u for t in grid.work_tiles() for u in grid.task_tiles(t)]
    assert sorted(filled) == grid.tiles()
    assert grid.work_cells == sum(grid.tile_cells(t) for t in grid.work_tiles())
    flips = grid.mirror_flips
    if flips is None:
        assert any(n % c for n, c, d in zip(grid.shape, grid.chunk, dims, strict=True)
                   if d != "vy") and grid.work_cells == grid.n_cells
        return
    for tile in grid.work_tiles():  # the mirror tile's states, reversed, are the negated ones
        mirror = grid.mirror_tile(tile)
        s0, s1 = grid.tile_slices(tile)
        a = grid.tile_states(tile).reshape(s0.stop - s0.start, s1.stop - s1.start, 6)
        b = grid.tile_states(mirror).reshape(a.shape)
        order = tuple(slice(None, None, -1) if f else slice(None) for f in flips)
        for index, name in ((grid.axes[0].index, dims[0]), (grid.axes[1].index, dims[1])):
            sign = -1.0 if name != "vy" else 1.0
            np.testing.assert_allclose(b[order][..., index], sign * a[..., index], atol=1e-12)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.floats(0.05, 1.2), st.floats(0.5, 20.0), st.floats(-0.3, 0.3))
def test_mirror_symmetry_of_the_outcome(vy, vphi, vx):
    """Mirroring the throw (x -> -x: vphi -> -vphi, vx -> -vx, phi0 -> -phi0) mirrors n."""
    scene = coincli.load_preset("paper").with_overrides(vy=vy, vphi=vphi, vx=vx)
    mirrored = scene.with_overrides(vphi=-vphi, vx=-vx)
    a, b = coincli.classify(scene), coincli.classify(mirrored)
    assert a.status == b.status
    assert a.quarter_turns == -b.quarter_turns
