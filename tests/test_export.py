"""Basin Datasets that export and figures that compose (issue 31): NetCDF round trips, one
missing-label convention on every route, `coin basin export` (NetCDF and CSV), maps drawn into
the caller's Axes, and xarray's plot in the orientation of the render."""

from __future__ import annotations

import csv
import errno

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure
from typer.testing import CliRunner

import coincli
from coincli.charts import export
from coincli.cli import app
from coincli.engines.basin import run_tile_task
from coincli.engines.basin_plan import sweep_attrs
from coincli.enums import Status
from coincli.grid import make_grid, make_spec
from coincli.integrators import NO_LABEL, info
from coincli.params import ParameterError, Scene
from coincli.stores.basin_store import BasinStore

runner = CliRunner()
RANGES = {"vy": (0.3, 1.9), "vphi": (-15.0, 15.0)}


@pytest.fixture(scope="module")
def partial(tmp_path_factory):
    """An 8 x 8 store with 2 of its 4 tiles computed: those of the first half of vy."""
    path = tmp_path_factory.mktemp("export") / "partial.zarr"
    scene = Scene()
    grid = make_grid(scene, RANGES, (8, 8), (4, 4), use_mirror=False)
    spec = make_spec(scene, grid)
    BasinStore(path).create_or_resume(sweep_attrs(scene, info("event"), spec), spec.grid)
    store = BasinStore.open(path)
    for tile in ((0, 0), (0, 1)):
        run_tile_task(store, spec, store.parameters, tile)
    return path


@pytest.fixture(scope="module")
def whole():
    return coincli.basin(Scene(), res=8, chunk=4, threads=1, **RANGES)


def plain(attrs: dict) -> dict:
    """Variable attributes comparable across NetCDF (which gives lists back as arrays)."""
    return {k: np.asarray(v).tolist() for k, v in attrs.items()}


@pytest.mark.parametrize("route", ["open_basin", "basin", "export_basin"])
def test_a_netcdf_round_trip_gives_back_the_labels_and_attributes(tmp_path, partial, whole,
                                                                   route):
    ds = whole if route == "basin" else coincli.open_basin(partial)
    nc = tmp_path / "m.nc"
    if route == "export_basin":
        coincli.export_basin(partial, nc)
    else:
        ds.to_netcdf(nc)
    back = xr.open_dataset(nc)
    assert set(back.data_vars) == set(ds.data_vars)
    for name in ds.data_vars:
        assert back[name].dtype == ds[name].dtype, name
        assert np.array_equal(back[name].values, ds[name].values,
                              equal_nan=ds[name].dtype.kind == "f"), name
        assert plain(back[name].attrs) == plain(ds[name].attrs), name
    for name in ds.coords:
        assert np.array_equal(back[name].values, ds[name].values)
    assert back.attrs == ds.attrs  # the nested ones as JSON text
    decoded = coincli.basin_attrs(back)
    assert decoded == coincli.basin_attrs(ds)
    assert decoded["parameters"]["coin"]["diameter"] == 0.02
    assert decoded["sweep"]["dims"] == ["vy", "vphi"]
    if route != "basin":
        assert decoded["damaged_tiles"] == [] and len(decoded["runs"]) == 0
    # the reopened Dataset is a basin to everything that takes one
    assert coincli.basin_stats(back) == coincli.basin_stats(ds)
    assert coincli.cell_scene(back, cell=(3, 2)) == coincli.cell_scene(ds, cell=(3, 2))
    assert isinstance(coincli.render_basin(back), Figure)
    again = coincli.open_basin(nc)  # the export read back as a basin
    assert np.array_equal(again.quarter_turns.values, ds.quarter_turns.values, equal_nan=True)


def test_missing_labels_are_nan_on_every_route_and_minus_32768_on_disk(tmp_path, partial):
    nc = tmp_path / "m.nc"
    coincli.export_basin(partial, nc)
    ours = coincli.open_basin(partial)
    missing = ours.status.values == Status.NOT_COMPUTED
    assert missing.sum() == 32  # 2 of 4 tiles
    routes = {"open_basin": ours, "open_zarr": xr.open_zarr(partial),
              "open_dataset": xr.open_dataset(nc), "open_basin(nc)": coincli.open_basin(nc)}
    for route, ds in routes.items():
        q = ds.quarter_turns
        assert q.dtype == np.float32, route
        assert np.array_equal(np.isnan(q.values), missing), route
        assert q.dims == ("vy", "vphi"), route
    # undecoded, every route has the stored int16 with its missing_value
    for route, raw in (("zarr", xr.open_zarr(partial, mask_and_scale=False)),
                       ("netcdf", xr.open_dataset(nc, mask_and_scale=False))):
        q = raw.quarter_turns
        assert q.dtype == np.int16 and q.attrs["missing_value"] == NO_LABEL, route
        assert np.array_equal(q.values == NO_LABEL, missing), route
        counted = coincli.basin_stats(ours)  # the costs: in the store's cost records only
        assert coincli.basin_stats(raw) == {**counted, "cost": coincli.basin_stats(raw)["cost"]}


def test_csv_has_a_row_per_cell_with_units_and_empty_fields_where_missing(tmp_path, partial):
    out = tmp_path / "m.csv"
    coincli.export_basin(partial, out)
    ds = coincli.open_basin(partial)
    with open(out, newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    assert header == ["vy [m/s]", "vphi [rad/s]", "n [quarter turns]", "pose", "status",
                      "certainty", "settle_time [s]", "steps", "rung"]
    assert len(body) == 64
    for k, row in enumerate(body):
        i, j = divmod(k, 8)  # the first swept axis outermost
        assert float(row[0]) == ds.vy.values[i] and float(row[1]) == ds.vphi.values[j]
        n = ds.quarter_turns.values[i, j]
        if np.isnan(n):
            assert row[2:] == ["", "", "not computed", "not computed", "", "", ""], row
        else:
            assert int(row[2]) == n and row[3] == ("standing" if n % 2 else "lying")
            assert row[4] == Status(int(ds.status.values[i, j])).label
            assert float(row[6]) == pytest.approx(float(ds.settle_time.values[i, j]), rel=1e-6)
            assert int(row[7]) == ds.steps.values[i, j] and int(row[8]) == ds.rung.values[i, j]


def test_coin_basin_export_writes_replaces_and_refuses_in_one_line(tmp_path, partial):
    out = tmp_path / "m.nc"
    out.write_text("old")
    result = runner.invoke(app, ["basin", "export", str(partial), str(out)])
    assert result.exit_code == 0, result.output
    assert f"wrote {out}" in result.stdout and "partial: 2 of 4 tiles" in result.stderr
    assert coincli.basin_stats(xr.open_dataset(out))["computed"] == 32
    for args, message in (([str(partial), str(tmp_path / "m.txt")], "must end in .nc"),
                          ([str(tmp_path / "none.zarr"), str(out)], "does not exist"),
                          ([str(partial), str(tmp_path / "no" / "m.csv")], "does not exist"),
                          ([str(out), str(tmp_path / "x.csv")], "")):
        result = runner.invoke(app, ["basin", "export", *args])
        assert result.exit_code == 2, result.output
        assert result.output.startswith("error: ") and message in result.output
        assert len(result.output.strip().splitlines()) == 1 and "Traceback" not in result.output


def test_an_export_that_fails_leaves_no_file_behind(tmp_path, partial, monkeypatch):
    out = tmp_path / "m.csv"
    out.write_text("the previous export\n")

    def full_disk(basin, path):
        path.write_text("half")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(export, "write_csv", full_disk)
    result = runner.invoke(app, ["basin", "export", str(partial), str(out)])
    assert result.exit_code == 2 and "no space left on device" in result.output
    assert out.read_text() == "the previous export\n"  # untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.csv"]  # no temporary file


def test_two_maps_side_by_side_in_one_figure(tmp_path, partial, whole):
    fig = Figure(figsize=(12, 5), layout="constrained")
    a, b = fig.subplots(1, 2)
    assert coincli.render_basin(whole, ax=a) is fig
    assert coincli.render_basin(partial, ax=b, field="settle_time") is fig
    # each map keeps its own colour bar beside it, not over the other
    assert len(fig.axes) == 4
    fig.savefig(tmp_path / "two.png")
    fig.canvas.draw()
    left_to_right = sorted(fig.axes, key=lambda ax: ax.get_position().x0)
    assert left_to_right[0] is a and left_to_right[2] is b  # each followed by its bar
    for one, right in zip(left_to_right, left_to_right[1:], strict=False):
        assert one.get_position().x1 <= right.get_position().x0
    assert "8 x 8 cells" in a.get_title() and "partial" in b.get_title()
    assert list(tmp_path.iterdir()) == [tmp_path / "two.png"]  # no file without out
    with pytest.raises(ParameterError, match="1 panel to draw, got 2 Axes"):
        coincli.render_basin(whole, ax=[a, b])
    with pytest.raises(TypeError, match="matplotlib Axes"):
        coincli.render_basin(whole, ax="left")
    with pytest.raises(ParameterError, match="unknown panel 'maps'"):
        coincli.render_analysis(None, ax=a, panels=["maps"])


def test_the_render_and_xarrays_plot_with_x_agree_on_orientation(partial):
    """The render draws the first swept axis horizontally; ``.plot(x=dims[0])`` (documented
    in open_basin) draws the same cells at the same places."""
    ds = coincli.open_basin(partial)
    fig = Figure()
    rendered, plotted = fig.subplots(1, 2)
    coincli.render_basin(ds, ax=rendered)
    q = ds.quarter_turns
    q.plot(x=q.dims[0], ax=plotted)
    assert rendered.get_xlim() == pytest.approx(plotted.get_xlim())
    assert rendered.get_ylim() == pytest.approx(plotted.get_ylim())
    image = rendered.get_images()[0].get_array()  # rows: the second axis, from the bottom
    mesh = plotted.collections[0].get_array().reshape(image.shape[:2])
    n0, n1 = q.shape
    assert image.shape[:2] == (n1, n0)
    # the same cells in the same places: those not computed (half of vy) are transparent in
    # the render and masked (NaN) in xarray's
    blank = np.ma.getmaskarray(mesh) | np.isnan(np.ma.getdata(mesh))
    assert blank.sum() == 32 and np.array_equal(image[..., 3] == 0, blank)
    assert not blank[:, : n0 // 2].any()  # the first half of vy: on the left
    # xarray's default puts the first dimension on the vertical axis: the other way round
    default = Figure().subplots()
    q.plot(ax=default)
    assert default.get_ylim() == pytest.approx(rendered.get_xlim())


def test_the_charts_of_several_panels_draw_into_the_axes_given(whole):
    analysis = coincli.analyze(whole, points=0, box=2, bands=2, threads=1)
    fig = Figure()
    axes = fig.subplots(1, 3)  # an array of Axes, as subplots gives
    assert coincli.render_analysis(analysis, ax=axes) is fig
    assert [ax.get_title() for ax in axes][1:] == ["Basin entropy by band",
                                                  "Uncertainty exponent by band"]
    one = Figure().subplots()
    coincli.render_analysis(analysis, ax=one, panels=["alpha"])
    assert one.get_title() == "Uncertainty exponent by band"
    with pytest.raises(ParameterError, match="3 panels to draw, got 1 Axes .panels= says"):
        coincli.render_analysis(analysis, ax=one)
    over = coincli.fractions_over(Scene(), "thickness", [0.002, 0.004], samples=256, batch=256,
                                  threads=1)
    fig = Figure()
    left, right = fig.subplots(1, 2)
    assert coincli.render_fractions(over, ax=[right, left],
                                    panels=["outcomes", "standing"]) is fig
    assert left.get_ylabel() == "probability" and right.get_ylabel().startswith("P(n)")
    assert left.get_xlabel() == right.get_xlabel() == "thickness (m)"
    shown = coincli.render_fractions(over)  # a new figure, which a notebook shows as a PNG
    assert len(shown.axes) == 2 and shown._repr_png_().startswith(b"\x89PNG")
