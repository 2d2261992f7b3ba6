"""A throw at home in a notebook: named columns and final state, Trajectory.to_dataset() and its
NetCDF round trip, the contact events as a table, coincli.record() read back with Rerun's own
reader, Trajectory.show() in a real kernel, without rerun-notebook and outside a notebook, and
the stability report's table in mJ."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from conftest import outputs_in_a_kernel, shows_a_widget

import coincli
from coincli.defaults import DEFAULT_LOG_EVERY
from coincli.integrators.common import EVENT_COLUMNS, LIFTOFF, ONSET, SAMPLE_COLUMNS
from coincli.models import PAPER, model_params
from coincli.params import STATE_NAMES, ParameterError
from coincli.recordings import rrd as rrd_io
from coincli.recordings import stream as rerun_stream
from coincli.recordings.frames import build_frames
from coincli.throw import EVENT_NAMES, QUANTITIES, SAMPLE_NAMES

FIG2 = dict(vy=1.197, vphi=3.508)
SAMPLE_DT = 1e-3


@pytest.fixture(scope="module")
def scene():
    return coincli.load_preset("paper").with_overrides(**FIG2)


@pytest.fixture(scope="module")
def run(scene):
    """The fig.-2 throw with its samples and contact events."""
    return coincli.simulate(scene, sample_dt=SAMPLE_DT, record_events=True)


@pytest.fixture(scope="module")
def bare(scene):
    """The same throw keeping nothing but its outcome."""
    return coincli.simulate(scene)


# -- named data ---------------------------------------------------------------------------------

def test_columns_are_named_once_with_units(run):
    assert run.samples.shape[1] == len(SAMPLE_NAMES) == SAMPLE_COLUMNS
    assert run.events.shape[1] == len(EVENT_NAMES) == EVENT_COLUMNS
    assert SAMPLE_NAMES == ("t", *STATE_NAMES)
    assert set(SAMPLE_NAMES) | set(EVENT_NAMES) <= set(QUANTITIES)


def test_final_state_by_name_and_as_the_array(run):
    final = run.final
    assert final.phi == run.final_state[2] and final.vy == run.final_state[4]
    assert list(final) == run.final_state.tolist()  # the array stays as it was
    assert final._asdict() == run.summary()["final_state"]


def test_to_dataset_names_every_variable_with_units(run, scene):
    ds = run.to_dataset()
    assert list(ds.dims) == ["t"]
    np.testing.assert_array_equal(ds.t.values, run.samples[:, 0])
    for i, name in enumerate(STATE_NAMES, start=1):
        np.testing.assert_array_equal(ds[name].values, run.samples[:, i])
    for name in [*ds.data_vars, "t"]:
        assert ds[name].attrs["units"] == QUANTITIES[name][0]
        assert ds[name].attrs["long_name"] == QUANTITIES[name][1]
    # the energies are the model's own, sample by sample
    p = model_params(scene)
    for row in (0, len(run.samples) // 2, len(run.samples) - 1):
        kinetic, gravity, elastic = PAPER.kernels("python").energies(p, run.samples[row, 1:])
        assert ds.kinetic.values[row] == pytest.approx(kinetic, rel=1e-12)
        assert ds.elastic.values[row] == pytest.approx(elastic, rel=1e-12, abs=1e-18)
        assert ds.energy.values[row] == pytest.approx(kinetic + gravity + elastic, rel=1e-12)
    assert ds.attrs["n"] == run.quarter_turns == 6
    assert ds.attrs["pose"] == "lying" and ds.attrs["status"] == "settled"
    assert ds.attrs["certainty"] == run.certainty.label
    assert ds.attrs["settle_time"] == run.settle_time
    assert ds.attrs["initial.vy"] == 1.197 and ds.attrs["foundation.k"] == scene.foundation.k
    assert all(not isinstance(value, (dict, list, bool, type(None)))
               for value in ds.attrs.values())


def test_dataset_netcdf_round_trip(run, tmp_path):
    xr = pytest.importorskip("xarray")
    ds = run.to_dataset()
    ds.to_netcdf(tmp_path / "throw.nc")
    with xr.open_dataset(tmp_path / "throw.nc") as back:
        xr.testing.assert_identical(back.load(), ds)


def test_dataset_of_a_run_without_outcome_leaves_n_out(scene, tmp_path):
    run = coincli.simulate(scene.with_overrides(max_steps=20, verify=False), sample_dt=0.01)
    assert run.quarter_turns is None and len(run.samples)
    ds = run.to_dataset()
    assert "n" not in ds.attrs and ds.attrs["status"] == "budget"
    assert math.isnan(ds.attrs["settle_time"]) and "budget" in ds.attrs["notes"]
    ds.to_netcdf(tmp_path / "budget.nc")  # still NetCDF-safe


def test_dataset_needs_samples_and_says_so_in_one_line(bare):
    with pytest.raises(ParameterError, match="sample_dt") as error:
        bare.to_dataset()
    assert "\n" not in str(error.value)


def test_events_table(run):
    table = run.events_table()
    assert list(table.columns) == list(EVENT_NAMES)
    assert len(table) == len(run.events) > 0
    np.testing.assert_array_equal(table["t"].to_numpy(), run.events[:, 0])
    np.testing.assert_array_equal(table[list(STATE_NAMES)].to_numpy(), run.events[:, 3:])
    kinds = {ONSET: "onset", LIFTOFF: "lift-off"}
    assert table["kind"].tolist() == [kinds[int(k)] for k in run.events[:, 2]]
    assert table["kind"].iloc[0] == "onset"  # a throw starts in the air
    assert table.attrs["units"]["t"] == "s"
    with pytest.raises(ParameterError, match="record_events"):
        coincli.simulate(run.scene, sample_dt=SAMPLE_DT).events_table()


# -- coincli.record ------------------------------------------------------------------------------

def _read_back(path):
    """The entities of the one recording in ``path``, and the times (ns) of the coin's moves."""
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    assert len(reader.recordings()) == 1
    entities, coin_times = set(), []
    for chunk in reader.store().stream().to_chunks():
        entities.add(chunk.entity_path)
        if chunk.entity_path == "/scene/world/coin" and not chunk.is_static:
            batch = chunk.to_record_batch()
            coin_times += batch.column("sim_time").cast("int64").to_pylist()
    return entities, np.sort(coin_times)


def test_record_writes_a_recording_rerun_reads_back(bare, tmp_path):
    """A throw that kept nothing is simulated again keeping its samples and events; what is
    written is what record() says."""
    pytest.importorskip("rerun")
    info = coincli.record(bare, rrd=tmp_path / "throw.rrd")
    assert info.rrd == tmp_path / "throw.rrd" and not info.spawn and info.viewer is None
    entities, times = _read_back(info.rrd)
    assert {"/scene/world/coin", "/plots/energy/total", "/events", "/info"} <= entities
    frames = build_frames(coincli.simulate(bare.scene, sample_dt=DEFAULT_LOG_EVERY,
                                           record_events=True))
    assert info.frames == len(frames) == len(times)
    assert info.events == len(frames.events) > 0
    np.testing.assert_array_equal(times, np.round(frames.t * 1e9).astype(np.int64))


def test_record_keeps_the_samples_it_is_given(run, tmp_path):
    info = coincli.record(run, rrd=tmp_path / "throw.rrd")
    assert info.frames == len(build_frames(run))


def test_record_needs_a_destination_and_a_usable_rate(run, tmp_path):
    with pytest.raises(ParameterError, match="destination"):
        coincli.record(run)
    for bad in (0, -1e-3, math.nan, True, "1e-3"):
        with pytest.raises(ParameterError, match="log_every"):
            coincli.record(run, rrd=tmp_path / "x.rrd", log_every=bad)
    with pytest.raises(ParameterError, match="^connect must be the URL"):
        coincli.record(run, connect="localhost:9876")
    assert not (tmp_path / "x.rrd").exists()


# -- Trajectory.show ----------------------------------------------------------------------------

def test_show_without_rerun_notebook_names_the_extra(run, monkeypatch):
    monkeypatch.setitem(sys.modules, "rerun_notebook", None)  # as if not installed
    with pytest.raises(ImportError) as error:
        run.show()
    message = str(error.value)
    assert 'pip install "coincli[notebook]"' in message and "\n" not in message
    with pytest.raises(ImportError, match="coincli\\[notebook\\]"):
        coincli.record(run, notebook=True)


def test_show_outside_a_notebook_says_what_to_do_instead(run):
    pytest.importorskip("rerun_notebook")
    with pytest.raises(RuntimeError, match=r"record\(run, rrd=") as error:
        run.show()
    assert "\n" not in str(error.value)


def test_inline_viewer_receives_the_recording(run, monkeypatch):
    """The viewer object is built and the whole recording sent to it; show() displays it when
    in a notebook."""
    pytest.importorskip("rerun_notebook")
    from rerun.notebook import Viewer

    sent, shown = [], []
    monkeypatch.setattr(Viewer, "_flush_hook", lambda self, data: sent.append(bytes(data)))
    viewer = rrd_io.inline_viewer(run, width=500, height=300)
    assert isinstance(viewer, Viewer)
    assert sum(map(len, sent)) > 10_000  # the blueprint, scene, plots and log

    monkeypatch.setattr(rerun_stream, "in_notebook", lambda: True)
    monkeypatch.setattr(Viewer, "display", lambda self, **_: shown.append(self))
    assert run.show() is None
    assert len(shown) == 1


def test_show_in_a_real_notebook_kernel(tmp_path):
    """Executed by a Jupyter kernel: run.show() displays Rerun's widget, no error."""
    outputs = outputs_in_a_kernel(
        "import coincli\n"
        f"run = coincli.simulate(coincli.load_preset('paper').with_overrides(**{FIG2!r}))\n"
        "run.show(width=500, height=300)", tmp_path)
    assert shows_a_widget(outputs)


# -- reprs ---------------------------------------------------------------------------------------

def test_stability_report_is_a_small_table_in_millijoules(scene):
    report = coincli.stability(scene)
    text = repr(report)
    lines = text.splitlines()
    assert lines[0] == "StabilityReport" and 10 < len(lines) < 25
    assert max(map(len, lines)) <= 100  # fits a cell
    assert "(energies in mJ)" in lines[1]
    assert f"{report.e_crit * 1e3:.6g} mJ" in text
    assert f"{report.rigid.v_max * 1e3:.6g}" in text  # joules shown as millijoules
    assert f"{report.k_cr:.2f} N/m" in text


def test_stability_cli_prints_the_same_rows():
    from typer.testing import CliRunner

    from coincli.cli import app

    result = CliRunner().invoke(app, ["stability"], env={"COLUMNS": "160"})
    assert result.exit_code == 0, result.output
    report = coincli.stability(coincli.load_preset("paper"))
    for row in repr(report).splitlines()[2:8]:
        label, *values = row.strip().rsplit(None, 2)
        assert label in result.output and all(v in result.output for v in values)
