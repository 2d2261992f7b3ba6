"""The public API: what a notebook calls, and the same numbers the command line gives."""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.enums import Certainty, Method, Status
from coincli.params import ParameterError

SMALL = dict(vy=(0.3, 1.0), vphi=(-15.0, 15.0), res=16)


def test_basin_in_memory_equals_coin_basin_cell_for_cell(tmp_path):
    ds = coincli.basin(coincli.load_preset("paper"), **SMALL)
    store = tmp_path / "cli.zarr"
    result = CliRunner().invoke(app, ["basin", str(store), "--vy", "0.3:1", "--vphi", "-15:15",
                                      "--res", "16", "-q"])
    assert result.exit_code == 0, result.output
    cli = coincli.open_basin(store)
    for name in ("quarter_turns", "status", "settle_time", "steps"):
        np.testing.assert_array_equal(ds[name].values, cli[name].values, err_msg=name)
    assert ds.sizes["vy"] == 16 and ds.sizes["vphi"] == 16
    np.testing.assert_array_equal(ds["vy"].values, np.linspace(0.3, 1.0, 16))
    for key in ("parameters", "sweep", "method", "version"):
        assert ds.attrs[key] == cli.attrs[key]
    # missing labels are NaN on every route (int16 with missing_value -32768 on disk)
    assert ds["quarter_turns"].dtype == np.float32 and (ds["done"] == 1).all()


def test_the_issue_one_liner_prints_a_dataset():
    code = ("import coincli; print(coincli.basin(coincli.load_preset('paper'), vy=(0.3, 1.0), "
            "vphi=(-15.0, 15.0), res=16))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.startswith("<xarray.Dataset>") and "quarter_turns" in out


def test_basin_into_a_store_reports_progress_and_resumes(tmp_path):
    scene = coincli.load_preset("paper")
    seen = []
    ds = coincli.basin(scene, store=tmp_path / "b.zarr", chunk=8, progress=seen.append, **SMALL)
    # vphi sweeps symmetrically: each tile computed fills its mirror tile too
    assert [p.tiles_done for p in seen] == [2, 4]
    assert seen[-1].cells_done == seen[-1].cells_todo == 256
    assert ds.attrs["store"] == str(tmp_path / "b.zarr")
    again = []
    coincli.basin(scene, store=tmp_path / "b.zarr", chunk=8, progress=again.append, **SMALL)
    assert again == []  # everything was done: nothing computed twice
    with pytest.raises(ParameterError, match="different sweep"):
        coincli.basin(scene.with_overrides(k=5000.0), store=tmp_path / "b.zarr", chunk=8,
                      **SMALL)


@pytest.mark.parametrize("first, then", [(False, True), (True, False)])
def test_a_store_is_not_resumed_with_the_other_kind_of_labels(tmp_path, first, then):
    """The ladder is part of a store's parameters: single-pass cells never mix with verified
    ones, either way round."""
    scene = coincli.load_preset("paper")
    coincli.basin(scene.with_overrides(verify=first), store=tmp_path / "b.zarr", chunk=8,
                  **SMALL)
    with pytest.raises(ParameterError, match="different sweep"):
        coincli.basin(scene.with_overrides(verify=then), store=tmp_path / "b.zarr", chunk=8,
                      **SMALL)


def test_stop_event_interrupts_and_the_store_resumes_to_the_same_map(tmp_path):
    scene = coincli.load_preset("paper")
    plan = coincli.plan_sweep(scene, chunk=4, **SMALL)
    stop = threading.Event()
    report = coincli.sweep(plan, tmp_path / "s.zarr", threads=1, stop=stop,
                           progress=lambda _: stop.set())  # asked to stop after a tile
    # ... which filled its mirror tile too (vphi sweeps -15:15)
    assert report.interrupted and not report.complete and report.tiles_done == 2
    report = coincli.sweep(plan, tmp_path / "s.zarr")
    assert report.complete and not report.interrupted
    whole = coincli.basin(scene, chunk=4, **SMALL)
    np.testing.assert_array_equal(coincli.open_basin(tmp_path / "s.zarr")["quarter_turns"],
                                  whole["quarter_turns"])


def test_simulate_and_classify_give_named_results():
    scene = coincli.load_preset("paper").with_overrides(vy=1.197, vphi=3.508)
    run = coincli.simulate(scene)
    assert run.quarter_turns == 6 and run.pose == "lying" and run.status is Status.SETTLED
    assert run.settle_time == pytest.approx(0.3622, abs=1e-4)
    assert run.energy_final < run.e_crit < run.energy_initial
    outcome = coincli.classify(scene)
    assert outcome == (6, Status.SETTLED, run.settle_time, Certainty.CERTAIN)
    assert outcome.pose == "lying" and run.certainty is Certainty.CERTAIN
    assert [r.setting for r in run.rungs] == ["rtol = 1e-06", "rtol = 1e-08 with event_dop853"]
    recorded = coincli.simulate(scene, sample_dt=1e-3, record_events=True)
    assert recorded.samples.shape[1] == 7 and recorded.events.shape[1] == 9
    assert recorded.quarter_turns == run.quarter_turns


def test_stats_and_render_take_a_dataset_or_a_store(tmp_path):
    scene = coincli.load_preset("paper")
    ds = coincli.basin(scene, store=tmp_path / "b.zarr", **SMALL)
    stats = coincli.basin_stats(ds)
    assert stats == {**coincli.basin_stats(tmp_path / "b.zarr"), "cost": stats["cost"]}
    assert stats["cells"] == stats["labelled"] == 256
    assert sum(row["count"] for row in stats["outcomes"]) == 256
    coincli.render_basin(ds, tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 10_000
    # the format is the file name's: PNG, SVG and PDF are what they say they are
    magic = {".png": b"\x89PNG", ".svg": b"<?xml", ".pdf": b"%PDF"}
    for suffix, head in magic.items():
        coincli.render_basin(ds, tmp_path / f"map{suffix}", field="settle_time")
        assert (tmp_path / f"map{suffix}").read_bytes().startswith(head), suffix
    # a store opened by xarray itself (quarter_turns masked to float) works too
    import xarray as xr

    raw = xr.open_zarr(tmp_path / "b.zarr")
    assert coincli.basin_stats(raw)["outcomes"] == stats["outcomes"]


def test_keyword_options_are_checked_in_one_line():
    scene = coincli.load_preset("paper")
    with pytest.raises(ParameterError, match="exactly two"):
        coincli.basin(scene, vx=(0.0, 1.0), res=4)
    with pytest.raises(ParameterError, match="empty range"):
        coincli.basin(scene, vy=(2.0, 1.0), res=4)
    with pytest.raises(ParameterError, match="unknown method"):
        scene.with_overrides(method="nope")
    with pytest.raises(ParameterError, match="store"):
        coincli.basin(scene, workers=2, res=4)
    assert scene.with_overrides(method="rk4").integration.method is Method.RK4


def test_stability_report():
    report = coincli.stability(coincli.load_preset("paper"))
    assert report.k_cr == pytest.approx(308.96, abs=0.01)
    assert report.elastic.ratio == pytest.approx(187.2, abs=0.05)


def test_import_is_light_and_leaves_numba_alone():
    """`import coincli` loads neither numpy nor numba, and using the kernels does not change
    numba's cache directory for other code in the same process."""
    code = ("import sys, coincli; assert 'numba' not in sys.modules and 'numpy' not in "
            "sys.modules, sorted(m for m in sys.modules if m.startswith(('numba', 'numpy')))\n"
            "import numba.core.config as c; before = c.CACHE_DIR\n"
            "coincli.classify(coincli.load_preset('paper').with_overrides(vy=0.5))\n"
            "assert c.CACHE_DIR == before, (before, c.CACHE_DIR)")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_the_command_runs_its_compiled_kernels(tmp_path):
    """`coin basin`, as the console script runs it (a process of its own, loading the compiled
    kernels from the cache), computes its map and exits 0."""
    store = tmp_path / "a.zarr"
    done = subprocess.run([sys.executable, "-m", "coincli", "basin", str(store), "--res", "4",
                           "-q"], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert coincli.open_basin(store).quarter_turns.shape == (4, 4)


def test_the_command_line_declares_its_options_without_numpy():
    """`coin --help` and option parsing load the command modules only: no numpy, numba or
    kernels (their import is most of a command's start-up)."""
    code = ("import sys, coincli.cli\n"
            "heavy = sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'numba', "
            "'zarr', 'xarray', 'scipy', 'matplotlib', 'rerun', 'dask') "
            "or m.startswith(('coincli.integrators', 'coincli.montecarlo', 'coincli.stores', "
            "'coincli.recordings', 'coincli.charts', 'coincli.engines')))\n"
            "assert not heavy, heavy")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_worked_example_runs(tmp_path):
    """docs/example.py, the README's worked example, runs as it is."""
    example = Path(__file__).resolve().parent.parent / "docs" / "example.py"
    out = subprocess.run([sys.executable, str(example)], cwd=tmp_path, capture_output=True,
                         text=True, check=True).stdout
    assert "fig.-2 throw: n = 6 (lying)" in out and "<xarray.Dataset>" in out
    assert (tmp_path / "example-basin.png").stat().st_size > 10_000


def test_public_names_are_one_list_and_all_resolve():
    import coincli.api

    api_names = set(coincli.api.__all__)
    assert set(coincli.__all__) - {"__version__"} == api_names
    for name in api_names:
        assert getattr(coincli, name) is getattr(coincli.api, name), name
    assert issubclass(coincli.ParameterError, ValueError)


def test_enums_print_as_their_words_and_stay_numbers_inside():
    assert str(Status.SETTLED) == f"{Status.SETTLED}" == "settled"
    assert f"{Method.EVENT}" == "event" and f"{Certainty.NOT_COMPUTED}" == "not computed"
    assert f"{Status.BUDGET:d}" == "3" and int(Status.BUDGET) == 3
    assert f"{Status.SETTLED:>9}" == "  settled"
    assert str(coincli.StopReason.PRECISION) == "precision"


def test_results_print_in_one_short_line():
    scene = coincli.load_preset("paper").with_overrides(vy=1.197, vphi=3.508)
    run = coincli.simulate(scene, sample_dt=1e-3, record_events=True)
    assert repr(run) == ("Trajectory(n = 6 (lying), settled at 0.3623 s, certain at rtol = "
                         f"1e-08 with event_dop853, 72 steps, {len(run.samples):,} samples, "
                         f"{len(run.events):,} events)")
    result = coincli.fractions(scene, samples=256, batch=256)
    assert repr(result).startswith("Fractions(P(standing) = ") and "\n" not in repr(result)
    assert "256 samples" in repr(result) and "stopped: samples" in repr(result)
    over = coincli.fractions_over(scene, "k", [5e3, 1e4], samples=256, batch=256)
    assert repr(over).startswith("FractionsOver(k (N/m), 2 values, P(standing) 5000: ")
    assert len(repr(coincli.plan_sweep(scene, res=16))) < 200


@pytest.mark.parametrize("call, kind, match", [
    (lambda s: coincli.simulate("paper"), TypeError, "scene must be a coincli.Scene"),
    (lambda s: coincli.basin("paper", res=8), TypeError, "scene must be a coincli.Scene"),
    (lambda s: coincli.simulate(s, sample_dt=-0.01), ParameterError, "sample_dt must be"),
    (lambda s: coincli.simulate(s, engine="fast"), ParameterError, "engine must be one of"),
    (lambda s: coincli.simulate(s, sample_dt=1e-12), ParameterError, "at most 10,000,000"),
    (lambda s: coincli.basin(s, res=8, threads="2"), ParameterError, "whole number"),
    (lambda s: coincli.basin(s, res=8, progress=3), TypeError, "progress must be a function"),
    (lambda s: coincli.basin_stats({}), TypeError, "a basin must be an xarray Dataset"),
    (lambda s: coincli.render_fractions(None, "x.png"), TypeError, "draws a continuation"),
    (lambda s: coincli.load_preset(3), TypeError, "a preset is a name or the path"),
    (lambda s: s.with_overrides(foo=1), ParameterError, "known: g, diameter"),
])
def test_wrong_arguments_are_named_before_any_work(call, kind, match):
    with pytest.raises(kind, match=match):
        call(coincli.load_preset("paper"))


def test_analysis_settings_are_checked_before_any_work():
    ds = coincli.basin(coincli.load_preset("paper"), **SMALL)
    with pytest.raises(ParameterError, match="confidence must be between 0 and 1"):
        coincli.analyze(ds, confidence=2.0, points=0, bands=1)
    for direction in ("up", "1", 1.0, True, 2):
        with pytest.raises(ParameterError, match="direction must be 'random', 'axis' or an"):
            coincli.analyze(ds, direction=direction, points=0, bands=1)


def test_each_open_function_refuses_the_other_kind_of_store(tmp_path):
    coincli.basin(coincli.load_preset("paper"), store=tmp_path / "b.zarr", **SMALL)
    with pytest.raises(ParameterError, match="not a coin fractions store"):
        coincli.open_fractions(tmp_path / "b.zarr")
    coincli.fractions(coincli.load_preset("paper"), samples=8, batch=8,
                      store=tmp_path / "f.zarr")
    for read in (coincli.open_basin, coincli.basin_stats):
        with pytest.raises(ParameterError, match="not a coin basin store"):
            read(tmp_path / "f.zarr")
    (tmp_path / "file").write_text("x")
    for run in (lambda: coincli.basin(coincli.load_preset("paper"), store=tmp_path / "file",
                                      **SMALL),
                lambda: coincli.fractions(coincli.load_preset("paper"), samples=8,
                                          store=tmp_path / "file")):
        with pytest.raises(ParameterError, match="exists and is not a directory"):
            run()


def test_light_names_load_without_the_api():
    code = ("import sys, coincli; coincli.Scene, coincli.Status, coincli.ParameterError; "
            "print('coincli.api' in sys.modules, 'numpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "False"]


def test_simulate_keeps_no_states_for_sample_dt_zero_and_takes_an_engine_by_name():
    scene = coincli.load_preset("paper").with_overrides(vy=1.197, vphi=3.508)
    run = coincli.simulate(scene, sample_dt=0, engine="python")
    assert run.samples is None or len(run.samples) == 0
    assert run.quarter_turns == 6
