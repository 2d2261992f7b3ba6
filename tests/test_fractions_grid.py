"""`coin fractions` over a grid of two parameters (--over twice, coincli.fractions_over with
two): the same samples at every point, so a point of the grid is the run over one parameter
there, count for count; one resumable store shared by several writers; the JSON, the xarray
Dataset, the map with its line P = 1/3 and the live map; and a corner's coefficient of
restitution against the model's own impact."""

from __future__ import annotations

import json
import math
import threading
from pathlib import Path

import numpy as np
import pytest
from test_fractions_store import run_together
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.models import model_params
from coincli.montecarlo import corner_restitution, parse_over
from coincli.montecarlo.estimate import pilot_values
from coincli.montecarlo.results import level_crossing
from coincli.params import ParameterError
from coincli.stores.fractions_store import FractionsStore

PAPER = coincli.load_preset("paper")
ROOT = Path(__file__).parent.parent
RUN = dict(phi0="-pi:pi", samples=1024, batch=512, threads=1)


def _files(path: Path) -> dict[str, bytes]:
    """The store's files but its records (runs.jsonl differs from run to run)."""
    from conftest import store_files

    return store_files(path)


def _counts(r) -> tuple:
    return (r.samples, r.counted, r.standing, r.outcomes, r.uncertain, r.all_decided)


@pytest.fixture(scope="module")
def grid(tmp_path_factory):
    """A 2 x 2 grid at the preset's own thickness (mass and inertia held: the preset's coin
    itself) and twice it, over two dampings, in a store."""
    store = tmp_path_factory.mktemp("grid") / "g.zarr"
    result = coincli.fractions_over(PAPER, over={"thickness": [0.002, 0.004], "c": [0.5, 2.0]},
                                    keep=("mass", "inertia"), store=store, **RUN)
    return result, store


def test_a_grid_point_at_the_presets_own_thickness_is_the_run_over_c(grid):
    result, _ = grid
    one = coincli.fractions_over(PAPER, "c", [0.5, 2.0], **RUN)
    assert result.parameters == ("thickness", "c") and result.shape == (2, 2)
    for j, c in enumerate((0.5, 2.0)):
        point = result.results[j]  # thickness 0.002, the first parameter outermost
        assert point.at == {"thickness": 0.002, "c": c}
        assert point.scene == one.results[j].scene  # the preset's coin, damped by c
        assert _counts(point) == _counts(one.results[j])
    assert result.results[1].standing["count"] > 10  # counts worth comparing
    assert [r.at for r in result.results] == [
        {"thickness": t, "c": c} for t in (0.002, 0.004) for c in (0.5, 2.0)]
    assert result.standing.shape == (2, 2, 3)
    # the same samples at every point: the thicker coin's y0 = r is its own r
    drawn = coincli.open_fractions(grid[1])["initial"].values  # (thickness, c, sample, ic)
    assert np.array_equal(drawn[0, 0, :, 1:], drawn[1, 1, :, 1:])


def test_the_forms_of_over_make_the_same_grid():
    """A dict, (name, values) pairs and 'NAME=...' strings, evenly spaced or listed."""
    forms = [{"thickness": [0.002, 0.004], "c": [0.5, 2.0]},
             [("thickness", [0.002, 0.004]), ("c", (0.5, 2.0))],
             ["thickness=0.002:0.004:2", "c=0.5,2"]]
    plans = [coincli.plan_fractions(PAPER, over=over, samples=512) for over in forms]
    assert all(p.attrs == plans[0].attrs and p.axes == ((0.002, 0.004), (0.5, 2.0))
               for p in plans)
    assert plans[0].attrs["over"]["parameters"] == ["thickness", "c"]
    assert plans[0].at(1) == {"thickness": 0.002, "c": 2.0}
    one = coincli.plan_fractions(PAPER, over="c=0.5:2:2", samples=512)
    assert set(one.attrs["over"]) == {"parameter", "values", "keep", "note"}  # as 0.9.0
    assert one.parameter == "c" and one.values == (0.5, 2.0)
    assert list(parse_over("c=0.1, 0.5,2")[1]) == [0.1, 0.5, 2.0]
    # a name spelled as its option is (--slip-velocity) is the parameter's
    assert parse_over("slip-velocity=1e-3,1e-4")[0] == "slip_velocity"
    assert pilot_values((20,)) == [0, 10, 19] and pilot_values((3, 4)) == [0, 3, 6, 8, 11]


@pytest.mark.parametrize("over,fragment", [
    (["c=1,2", "c=3,4"], "given twice"),
    (["c=1,2", "k=1e4,2e4", "g=9,10"], "at most 2"),
    (["c=1,1"], "differ"),
    (["c=1:2"], "NAME=V1,V2"),
])
def test_a_bad_grid_is_refused_in_api_words(over, fragment):
    with pytest.raises(ParameterError, match=fragment):
        coincli.plan_fractions(PAPER, over=over, samples=512)


def test_the_json_names_both_values_of_every_result(tmp_path):
    args = ["fractions", "--phi0", "-pi:pi", "--samples", "512", "--batch", "512", "--threads",
            "1", "--json", "-q"]
    out = CliRunner().invoke(app, [*args, "--over", "thickness=0.002,0.004", "--over",
                                   "c=0.5:2:2", "--store", str(tmp_path / "g.zarr")])
    assert out.exit_code == 0, out.output
    data = json.loads(out.stdout)
    assert data["parameters"] == ["thickness", "c"] and data["shape"] == [2, 2]
    assert data["axes"]["c"] == {"units": "N s/m", "values": [0.5, 2.0]}
    assert [r["at"] for r in data["results"]] == [
        {"thickness": t, "c": c} for t in (0.002, 0.004) for c in (0.5, 2.0)]
    for r in data["results"]:
        assert r["parameters"]["coin"]["thickness"] == r["at"]["thickness"]
        assert r["parameters"]["foundation"]["c"] == r["at"]["c"]
        assert r["standing"]["low"] <= r["standing"]["probability"] <= r["standing"]["high"]
    one = json.loads(CliRunner().invoke(app, [*args, "--over", "c=0.5,2"]).stdout)
    assert (one["parameter"], one["units"], one["values"]) == ("c", "N s/m", [0.5, 2.0])
    assert one["parameters"] == ["c"]
    assert [(r["parameter"], r["value"], r["at"]) for r in one["results"]] == [
        ("c", 0.5, {"c": 0.5}), ("c", 2.0, {"c": 2.0})]
    table = CliRunner().invoke(app, [*args[:-2], "--over", "thickness=0.002,0.004", "--over",
                                     "c=0.5:2:2", "--store", str(tmp_path / "g.zarr")])
    assert table.exit_code == 0 and "2 x 2 = 4 points" in table.stdout
    assert "512 samples a point" in " ".join(table.stdout.split())


def test_the_dataset_has_a_dimension_a_parameter_and_writes_to_netcdf(grid, tmp_path):
    import xarray as xr

    result, _ = grid
    ds = result.to_dataset()
    assert ds["probability"].dims == ("thickness", "c", "outcome")
    assert list(ds["c"].values) == [0.5, 2.0] and ds["c"].attrs["units"] == "N s/m"
    for r in result.results:
        at = ds.sel(**r.at)
        assert at["probability"].sel(outcome="standing") == r.standing["probability"]
        assert at["high"].sel(outcome="lying") == r.lying["high"]
        assert at["decided_count"].sel(outcome="standing") == \
            r.all_decided["standing"]["count"]
        assert int(at["chaotic"]) == r.uncertain["chaotic"]
        assert int(at["undecided"]) == r.uncertain["undecided"]
        assert at["uncertain"] == r.uncertain["probability"]
        for row in r.outcomes:
            assert int(at["n_count"].sel(n=row["n"])) == row["count"]
        assert int(at["n_count"].sum()) == r.counted
    path = tmp_path / "g.nc"
    ds.to_netcdf(path)
    back = xr.load_dataset(path)
    assert back["probability"].equals(ds["probability"])
    assert back["n_count"].equals(ds["n_count"])


def test_an_interrupted_grid_resumes_to_the_store_of_one_run(grid, tmp_path):
    """Stopped after a few batches and run again: the same store, file for file, and the same
    numbers as the uninterrupted run."""
    clean, clean_store = grid
    store = tmp_path / "g.zarr"
    stop = threading.Event()

    def progress(update):
        if update.computed >= 1024:
            stop.set()

    over = {"thickness": [0.002, 0.004], "c": [0.5, 2.0]}
    part = coincli.fractions_over(PAPER, over=over, keep=("mass", "inertia"), store=store,
                                  progress=progress, stop=stop, **RUN)
    assert part.interrupted and 0 < part.cost["computed"] < 4096
    again = coincli.fractions_over(PAPER, over=over, keep=("mass", "inertia"), store=store,
                                   **RUN)
    assert again.cost["from_store"] == part.cost["computed"]
    assert [_counts(r) for r in again.results] == [_counts(r) for r in clean.results]
    assert _files(store) == _files(clean_store)


def test_several_writers_share_the_batches_of_a_grid(grid, tmp_path):
    clean, clean_store = grid
    store = tmp_path / "shared.zarr"
    args = ["fractions", "--phi0", "-pi:pi", "--samples", "1024", "--batch", "512",
            "--threads", "1", "--over", "thickness=0.002,0.004", "--over", "c=0.5,2", "--mass",
            str(PAPER.coin.mass), "--inertia", str(PAPER.coin.inertia), "--store", str(store),
            "-q"]
    for data in run_together(args, 2):
        assert [r["standing"] for r in data["results"]] == [r.standing for r in clean.results]
    assert sum(run["samples"] for run in FractionsStore(store).runs()) == 4096  # each once
    assert _files(store) == _files(clean_store)


def test_the_map_draws_p_and_its_line_at_one_third(tmp_path):
    """Across t/d and up c: P(standing) rises through 1/3 near t/d = 0.8, so the map has its
    line P = 1/3, both ends of its band, and the two published limits; the crossing the line
    draws is FractionsOver.crossing's."""
    result = coincli.fractions_over(
        PAPER, over={"thickness": [0.011, 0.016, 0.02], "c": [0.5, 8.0]}, y0="r:5r",
        phi0="-pi:pi", vx="-0.5:0.5", samples=512, batch=512, threads=1)
    fig = coincli.render_fractions(result, tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 20_000
    first = fig.axes[0]
    assert first.get_xlabel().startswith("t / d") and first.get_yscale() == "log"
    lines = {t.get_text().split(":")[0] for t in first.get_legend().get_texts()}
    assert {"P = 0.333", "95 % band (low, high ends)", "no bounce, (2/pi) arctan(t/d)",
            "Pender & Uhrin, planar die"} <= lines
    cross = result.crossing()
    p = result.estimate()
    for j in range(2):
        t = cross["at"][j]
        assert 0.011 < t < 0.02 and cross["from"][j] <= t <= cross["to"][j]
        i = np.searchsorted([0.011, 0.016, 0.02], t) - 1
        assert p[i, j, 0] < 1 / 3 <= p[i + 1, j, 0]
    with pytest.raises(ParameterError, match="panel"):
        coincli.render_fractions(result, panels=["outcomes"])
    # issue 48: where labels are uncertain (here 40-70 % at c = 0.5), the maps say so: those
    # cells hatched on both maps of P, the share written in each
    share = np.array([r.uncertain["probability"] for r in result.results]).reshape(3, 2)
    marked = share >= 0.05
    assert marked[:, 0].all() and not marked[:, 1].any(), share
    for panel in fig.axes[:2]:
        hatched = [c for c in panel.collections if c.get_hatch()]
        assert len(hatched) == 1 and len(hatched[0].get_paths()) == 3
        written = sorted(t.get_text() for t in panel.texts if "uncertain" in t.get_text())
        assert written == sorted(f"{100 * s:.0f} %\nuncertain" for s in share[:, 0])
    assert "5 % or more uncertain" in {t.get_text() for t in first.get_legend().get_texts()}


def test_no_cell_of_a_positive_parameter_is_drawn_below_zero(grid):
    """c = 0.5 and 2 as cells as wide as their gap would reach c = -0.25: the axis goes log,
    ticked at the two values; t/d 0.1 and 0.2 stay linear (their cells end at 0.05)."""
    fig = coincli.render_fractions(grid[0])
    first = fig.axes[0]
    assert first.get_yscale() == "log" and first.get_ylim()[0] > 0
    assert list(first.get_yticks()) == [0.5, 2.0]
    assert first.get_xscale() == "linear" and first.get_xlim()[0] == pytest.approx(0.05)


def test_level_crossing_interpolates_and_says_nan_outside():
    x = np.arange(5.0)
    p = np.array([0.0, 0.2, 0.4, 0.6, 0.8])
    assert level_crossing(x, p, p - 0.05, p + 0.05, 0.5) == pytest.approx((2.5, 2.25, 2.75))
    assert all(math.isnan(v) for v in level_crossing(x, p + 0.6, p, p + 0.7, 0.5)[:2])
    # a noisy rise: the band runs from the first rise of its high end to the last of its low
    noisy = np.array([0.1, 0.45, 0.55, 0.48, 0.9])
    at, start, end = level_crossing(x, noisy, noisy - 0.01, noisy + 0.01, 0.5)
    assert at == pytest.approx(1.5) and start < at and end == pytest.approx(3 + 0.03 / 0.42)


def test_the_live_view_fills_the_map_in_a_point_at_a_time(tmp_path):
    from test_live import rows

    rrd = tmp_path / "g.rrd"
    out = CliRunner().invoke(app, ["fractions", "--phi0", "-pi:pi", "--samples", "512",
                                   "--batch", "512", "--threads", "1", "-q", "--json", "--over",
                                   "thickness=0.002,0.004,0.006", "--over", "c=0.5,2", "--rrd",
                                   str(rrd)])
    assert out.exit_code == 0, out.output
    data = json.loads(out.stdout)
    tables = rows(rrd)
    for basis in ("certain", "decided"):
        images = tables[(f"/map/{basis}", False)].sort_by("points_done")
        assert images.column("points_done").to_pylist() == [1, 2, 3, 4, 5, 6]
        fmt = images.column("Image:format").to_pylist()[-1][0]
        last = np.frombuffer(bytes(images.column("Image:buffer").to_pylist()[-1][0]),
                             dtype=np.uint8).reshape(fmt["height"], fmt["width"], 4)
        assert last.shape == (2, 3, 4) and (last[..., 3] == 255).all()  # every point drawn
        first = np.frombuffer(bytes(images.column("Image:buffer").to_pylist()[0][0]),
                              dtype=np.uint8).reshape(2, 3, 4)
        assert (first[..., 3] == 255).sum() == 1  # one point, the rest transparent
        points = tables[(f"/map/{basis}/points", False)].sort_by("points_done")
        labels = points.column("Points2D:labels").to_pylist()[-1]
        key = "standing" if basis == "certain" else "all_decided"
        for r in data["results"]:
            row = r[key] if basis == "certain" else r[key]["standing"]
            text = (f"thickness = {r['at']['thickness']:g}, c = {r['at']['c']:g}: P(standing) "
                    f"{100 * row['probability']:.3g} %")
            assert any(label.startswith(text) for label in labels), (text, labels)


def test_a_corners_restitution_is_the_models_impact():
    """A coin whose diagonal is vertical, dropped straight onto its lowest corner with gravity
    off: the contact is the damped oscillator of that corner with the whole mass behind it,
    so the speed it leaves with is e times the speed it came with (and none past critical
    damping); it is the restitution the model's horizon uses."""
    for c, e in ((0.5, 0.8691), (5.0, 0.2090), (15.0, 0.0)):
        scene = PAPER.with_overrides(c=c, g=1e-9)
        p = model_params(scene)
        assert corner_restitution(scene) == pytest.approx(e, abs=1e-4)
        if e:
            assert corner_restitution(scene) == pytest.approx(1 - 1 / p.bounce_factor)
        throw = coincli.simulate(scene, verify=False, record_events=True, phi0=p.phi_cr,
                                 y0=p.r + 1e-4, vy=-0.2, vx=0.0, vphi=0.0, t_end=0.01,
                                 rtol=1e-10)
        kinds = list(throw.events_table()["kind"])
        if e:  # it left the foundation, and flies on at the speed it left with
            assert kinds == ["onset", "lift-off"]
            assert throw.final.vy / 0.2 == pytest.approx(corner_restitution(scene), abs=1e-5)
        else:  # past critical damping the corner creeps back and never leaves
            assert kinds == ["onset"] and throw.final.vy < 1e-3 * 0.2
    flat = PAPER.coin
    assert corner_restitution(PAPER, lever=flat.r_d) < corner_restitution(PAPER)


def test_a_grid_too_large_for_memory_is_refused_in_one_line_before_any_work(monkeypatch):
    """Thousands of values a side: refused naming the grid's size before a point's scene is
    built (it used to end in a MemoryError's traceback), as a tile too large is refused."""
    result = CliRunner().invoke(app, ["fractions", "--over", "thickness=0.0015:0.0025:10000",
                                      "--over", "c=0.1:1:10000"])
    err = result.stderr.strip()
    assert result.exit_code == 2 and len(err.splitlines()) == 1, result.output
    assert err.startswith("error: --over: a grid of 10,000 x 10,000 = 100,000,000 points "
                          "need about"), err
    assert "give fewer values" in err and "Traceback" not in result.output
    from coincli.montecarlo import plan as plan_module

    monkeypatch.setattr(plan_module, "available_memory", lambda: 50 * plan_module.POINT_BYTES)
    with pytest.raises(ParameterError, match="a grid of 10 x 10 = 100 points") as refused:
        coincli.plan_fractions(PAPER, samples=512, over={"thickness": np.linspace(
            0.0015, 0.0025, 10), "c": np.linspace(0.1, 1, 10)})
    assert refused.value.parameters == ("over",) and "at most about 50 points" in str(
        refused.value)
    with pytest.raises(ParameterError, match="over: 60 values need"):
        coincli.plan_fractions(PAPER, samples=512, over=("c", np.linspace(0.1, 1, 60)))
    coincli.plan_fractions(PAPER, samples=512, over=("c", np.linspace(0.1, 1, 40)))  # fits
