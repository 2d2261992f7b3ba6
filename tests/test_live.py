"""Rerun streams of sweeps, stores and estimates (coincli.recordings.basin_view, fractions_view,
analysis_view; `coin basin --rrd`, `coin basin show`, `coin fractions --rrd`): the recordings
are read back with Rerun's own reader and compared with the store and the printed result;
--spawn without a display."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
from conftest import default_signals, outputs_in_a_kernel, shows_a_widget
from typer.testing import CliRunner

from coincli.charts.basin_render import n_range, ramp_colours
from coincli.cli import app
from coincli.enums import Certainty, Status
from coincli.integrators import NO_LABEL
from coincli.recordings import basin_view, sweep_recording
from coincli.recordings import stream as rerun_stream
from coincli.stores.basin_store import BasinStore

rr = pytest.importorskip("rerun")
from rerun.chunk import RrdReader  # noqa: E402

runner = CliRunner()
CHANNEL_DTYPES = {6: np.uint8, 8: np.uint16}  # Rerun's ChannelDatatype U8, U16
SMALL = ["--res", "16", "--chunk", "8", "-q", "--threads", "1"]


pytestmark = pytest.mark.usefixtures("strict_rerun")  # conftest.py


@pytest.fixture(autouse=True)
def strict_recording_process(monkeypatch):
    """A sweep's recording process is as strict as this one (Rerun reads RERUN_STRICT)."""
    monkeypatch.setenv("RERUN_STRICT", "1")


def read_basin(path):
    return BasinStore.open(path).read()


def rows(path) -> dict:
    """{(entity, static): pyarrow table of its rows in the order logged} of a recording."""
    parts = defaultdict(list)
    for chunk in RrdReader(path).store().stream().to_chunks():
        parts[(chunk.entity_path, chunk.is_static)].append(chunk.to_record_batch())
    return {key: pa.concat_tables([pa.Table.from_batches([b]) for b in batches],
                                  promote_options="default")
            for key, batches in parts.items()}


def last_image(tables: dict, entity: str, static: bool) -> np.ndarray:
    """The last SegmentationImage logged at ``entity`` (the latest on sweep_time), decoded."""
    table = tables[(entity, static)]
    if not static:
        table = table.sort_by("sweep_time")
    fmt = [f for f in table.column("SegmentationImage:format").to_pylist() if f][-1][0]
    data = [b for b in table.column("SegmentationImage:buffer").to_pylist() if b][-1][0]
    buffer = np.frombuffer(bytes(data),
                           dtype=CHANNEL_DTYPES[fmt["channel_datatype"]])
    # image rows from the top: the second swept axis, highest first; back to cells [i, j]
    return buffer.reshape(fmt["height"], fmt["width"])[::-1].T


def class_labels(tables: dict, entity: str) -> dict[int, str]:
    """Class id -> label of the last annotation context at ``entity``."""
    logged = tables[(entity, True)].column("AnnotationContext:context").to_pylist()
    context = [c for c in logged if c is not None][-1][0]
    return {c["class_id"]: c["class_description"]["info"]["label"] for c in context}


def check_map(tables: dict, basin, static: bool) -> None:
    """The recording's map equals the store, cell for cell: n where there is a label (its
    class named after it), nothing elsewhere; the certainty layer from status and certainty."""
    n_ids = last_image(tables, "/basin/n", static).astype(np.int64)
    flags = last_image(tables, "/basin/certainty", static)
    q = basin.arrays["quarter_turns"].astype(np.int64)
    st = basin.arrays["status"]
    labelled = ((st == Status.SETTLED) | (st == Status.UNSETTLED)) & (q != NO_LABEL)
    assert n_ids.shape == q.shape
    assert np.array_equal(np.where(n_ids > 0, n_ids - 32768, NO_LABEL), np.where(labelled, q,
                                                                                  NO_LABEL))
    labels = class_labels(tables, "/basin/n")
    for n in np.unique(q[labelled]):
        assert labels[int(n) + 32768] == f"n = {n}, {'standing' if n % 2 else 'lying'}"
    assert np.array_equal(flags == 4, st == Status.NOT_COMPUTED)
    assert np.array_equal(flags == 3, st == Status.NONFINITE)
    assert np.array_equal(flags == 2, st == Status.UNSETTLED)
    uncertain = labelled & (basin.arrays["certainty"] == Certainty.UNCERTAIN) & (
        st != Status.UNSETTLED)
    assert np.array_equal(flags == 1, uncertain)
    assert class_labels(tables, "/basin/certainty")[4] == "not computed"


def test_basin_rrd_reads_back_as_the_store(tmp_path):
    store, rrd = tmp_path / "s.zarr", tmp_path / "s.rrd"
    result = runner.invoke(app, ["basin", str(store), *SMALL, "--rrd", str(rrd)])
    assert result.exit_code == 0, result.output
    assert f"wrote {rrd}" in " ".join(result.output.split())  # wrapped to the console's width
    tables = rows(rrd)
    check_map(tables, read_basin(store), static=False)
    # the progress series: cells done grow to the whole map, one point at most per tile
    cells = tables[("/progress/cells", False)].sort_by("sweep_time")
    done = [r[0] for r in cells.column("Scalars:scalars").to_pylist()]
    assert done == sorted(done) and done[-1] == 16 * 16 and len(done) <= 4
    assert ("/progress/rate", False) in tables


def test_basin_rrd_of_a_resumed_sweep_holds_the_tiles_done_before(tmp_path):
    """A resumed sweep sends what the store holds first, then the rest: the last map is the
    whole store, also the tiles this run did not compute."""
    store, rrd = tmp_path / "s.zarr", tmp_path / "s.rrd"
    assert runner.invoke(app, ["basin", str(store), *SMALL]).exit_code == 0
    (store / "done" / "c" / "1" / "1").unlink()  # the tile (1, 1) is to be done again
    result = runner.invoke(app, ["basin", str(store), *SMALL, "--rrd", str(rrd)])
    assert result.exit_code == 0, result.output
    check_map(rows(rrd), read_basin(store), static=False)


def test_basin_show_opens_a_partial_store(tmp_path):
    store, rrd = tmp_path / "s.zarr", tmp_path / "show.rrd"
    assert runner.invoke(app, ["basin", str(store), *SMALL]).exit_code == 0
    (store / "done" / "c" / "0" / "1").unlink()  # a tile not computed (yet)
    result = runner.invoke(app, ["basin", "show", str(store), "--rrd", str(rrd)],
                           env={"COLUMNS": "400"})
    assert result.exit_code == 0, result.output
    assert "3 of 4 tiles computed" in result.output
    basin = read_basin(store)
    assert (basin.arrays["status"][0:8, 8:16] == Status.NOT_COMPUTED).all()
    tables = rows(rrd)
    assert ("/basin/n", False) not in tables  # a static recording
    check_map(tables, basin, static=True)
    n_ids = last_image(tables, "/basin/n", True)
    assert (n_ids[0:8, 8:16] == 0).all() and (n_ids[8:, :] > 0).any()


def test_fractions_rrd_has_the_running_estimates_with_bands(tmp_path):
    rrd = tmp_path / "f.rrd"
    result = runner.invoke(app, ["fractions", "--samples", "2000", "--batch", "500",
                                 "--threads", "1", "-q", "--json", "--rrd", str(rrd)])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    tables = rows(rrd)
    for name in ("standing", "lying", "uncertain", "leading"):
        series = tables[(f"/estimate/{name}", False)].sort_by("samples")
        samples = series.column("samples").to_pylist()
        assert samples == [500, 1000, 1500, 2000]
        p = np.array([r[0] for r in series.column("Scalars:scalars").to_pylist()])
        low, high = (np.array([r[0] for r in tables[(f"/estimate/{name}/{side}", False)]
                               .sort_by("samples").column("Scalars:scalars").to_pylist()])
                     for side in ("low", "high"))
        assert np.all(low <= p) and np.all(p <= high)
        if name != "leading":
            final = out[name]
            assert p[-1] == pytest.approx(100 * final["probability"])
            assert (low[-1], high[-1]) == pytest.approx((100 * final["low"],
                                                        100 * final["high"]))
    leading = max(out["outcomes"], key=lambda row: row["count"])
    n = tables[("/leading_n", False)].sort_by("samples").column("Scalars:scalars").to_pylist()
    assert n[-1][0] == leading["n"]


def test_fractions_over_rrd_has_one_point_a_value(tmp_path):
    rrd = tmp_path / "o.rrd"
    result = runner.invoke(app, ["fractions", "--samples", "500", "--batch", "500",
                                 "--threads", "1", "-q", "--json", "--over",
                                 "thickness=0.001:0.003:3", "--rrd", str(rrd)])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    series = rows(rrd)[("/over/standing", False)]
    timeline = "thickness [1e-3 m]"
    series = series.sort_by(timeline)
    assert series.column(timeline).to_pylist() == [1, 2, 3]
    assert [r[0] for r in series.column("Scalars:scalars").to_pylist()] == pytest.approx(
        [100 * r["standing"]["probability"] for r in out["results"]])


@pytest.mark.parametrize("command", [["basin", "STORE", *SMALL],
                                     ["fractions", "--samples", "500", "--batch", "500",
                                      "--threads", "1", "-q"]])
def test_spawn_without_a_display(tmp_path, monkeypatch, command):
    """One warning line before the work; the work and its result as usual; the --rrd file
    written; exit 1 (as coin simulate)."""
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    rrd = tmp_path / "x.rrd"
    args = [str(tmp_path / "s.zarr") if a == "STORE" else a for a in command]
    result = runner.invoke(app, [*args, "--spawn", "--rrd", str(rrd)], env={"COLUMNS": "400"})
    assert result.exit_code == 1, result.output
    warnings = [line for line in result.stderr.splitlines() if "--spawn" in line]
    assert len(warnings) == 1 and "no display" in warnings[0]
    assert ("tiles done" if command[0] == "basin" else "P(standing)") in result.stdout \
        or "standing" in result.stdout
    assert rrd.stat().st_size > 0 and RrdReader(rrd).recordings()


def test_basin_show_without_a_display_or_file_says_so(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    store = tmp_path / "s.zarr"
    assert runner.invoke(app, ["basin", str(store), *SMALL]).exit_code == 0
    result = runner.invoke(app, ["basin", "show", str(store)])
    assert result.exit_code == 1
    err = result.stderr.strip()  # one message: "error:" once, however wide the console
    assert err.startswith("error:") and err.count("error:") == 1 and "--rrd FILE" in err


def test_an_unwritable_recording_is_refused_before_any_work(tmp_path):
    store = tmp_path / "s.zarr"
    result = runner.invoke(app, ["basin", str(store), *SMALL, "--rrd",
                                 str(tmp_path / "missing" / "s.rrd")], env={"COLUMNS": "400"})
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1 and "does not exist" in result.stderr
    assert not store.exists()


def test_the_written_out_colours_are_those_of_coin_basin_render():
    assert basin_view.RAMP == {n: basin_view.rgb(colour)
                         for n, colour in ramp_colours(n_range(None)).items()}


def test_a_recording_process_that_dies_is_said_and_the_sweep_goes_on(tmp_path, monkeypatch):
    """The recording process killed (here at once, by itself): the sweep is done and its
    result printed, then one error line and exit 2 (as coin simulate's); no recording file,
    complete or not."""
    monkeypatch.setattr(sweep_recording, "RECORDER", "import os, signal; os.kill(os.getpid(), "
                                                     "signal.SIGKILL)")
    store, rrd = tmp_path / "s.zarr", tmp_path / "s.rrd"
    result = runner.invoke(app, ["basin", str(store), *SMALL, "--rrd", str(rrd)],
                           env={"COLUMNS": "400"})
    assert result.exit_code == 2, result.output
    assert "4/4 tiles done" in result.stdout
    assert result.stderr.strip() == ("error: could not write the recording: the recording "
                                     "process ended before it was done (killed by SIGKILL)")
    assert read_basin(store).done.all()
    assert list(tmp_path.glob("*.rrd")) == []


def _gone(pid: int) -> bool:
    import psutil  # a dependency of Rerun's

    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


@pytest.mark.parametrize("how, code", [("Ctrl-C", 130), ("SIGTERM", 143), ("SIGKILL", -9)])
def test_a_sweep_ended_by_a_signal_leaves_the_recording_of_its_store(tmp_path, how, code):
    """Ctrl-C at the terminal (SIGINT to the whole process group), SIGTERM, even SIGKILL to
    the sweep: the recording process ends the recording with the map of what the store holds
    (it has a session of its own: the Ctrl-C is the sweep's alone), and ends too."""
    import psutil

    store, rrd = tmp_path / "s.zarr", tmp_path / "s.rrd"
    sweep = subprocess.Popen([sys.executable, "-m", "coincli", "basin", str(store), "--res",
                              "512", "--chunk", "16", "--threads", "1", "-q", "--rrd", str(rrd)],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             start_new_session=True, preexec_fn=default_signals,
                             cwd=Path(__file__).parent.parent)
    try:
        deadline = time.monotonic() + 60
        while not any(f.is_file() and f.suffix != ".partial"
                      for f in (store / "done" / "c").rglob("*")):  # a tile done
            assert sweep.poll() is None, sweep.stderr.read()
            assert time.monotonic() < deadline, "no tile was written in time"
            time.sleep(0.005)
        recorder, = psutil.Process(sweep.pid).children()
        if how == "Ctrl-C":
            os.killpg(sweep.pid, signal.SIGINT)
        else:
            sweep.send_signal(getattr(signal, how))
        assert sweep.wait(timeout=60) == code, sweep.stderr.read()
    finally:
        if sweep.poll() is None:
            sweep.kill()
    deadline = time.monotonic() + 30
    while not _gone(recorder.pid):
        assert time.monotonic() < deadline, "the recording process is still running"
        time.sleep(0.01)
    basin = read_basin(store)
    assert 0 < basin.done.sum() < basin.done.size  # stopped on the way
    check_map(rows(rrd), basin, static=False)


# -- the recording's process ends with its command -----------------------------------------
def _processes_marked(mark: str) -> list:
    import psutil

    found = []
    for process in psutil.process_iter():
        try:
            if process.environ().get("COIN_TEST_MARK") == mark:
                found.append(process)
        except (psutil.AccessDenied, psutil.NoSuchProcess, psutil.ZombieProcess):
            pass
    return found


@pytest.mark.parametrize("case", ["recorded", "bad option", "unparsable"])
def test_a_recorded_sweep_leaves_no_process(tmp_path, case):
    """`python -m coincli` (as the `coin` script): the recording is the store's, cell for cell;
    a command that fails first (an option refused by the sweep, or by the parser) leaves no
    process behind."""
    store, rrd = tmp_path / "s.zarr", tmp_path / "s.rrd"
    args = {"recorded": [*SMALL, "--rrd", str(rrd)],
            "bad option": [*SMALL, "--res", "1", "--rrd", str(rrd)],
            "unparsable": [*SMALL, "--no-such-option", "--rrd", str(rrd)]}[case]
    mark = f"{os.getpid()}-{tmp_path.name}"
    done = subprocess.run([sys.executable, "-m", "coincli", "basin", str(store), *args],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "COIN_TEST_MARK": mark, "COLUMNS": "200"})
    if case == "recorded":
        assert done.returncode == 0, done.stderr
        check_map(rows(rrd), read_basin(store), static=False)
    else:
        assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
        assert not rrd.exists() and not store.exists()
    deadline = time.monotonic() + 10
    while _processes_marked(mark):
        assert time.monotonic() < deadline, "a recording process outlived its command"
        time.sleep(0.02)


# -- live recordings from Python --------------------------------------------------------------
def test_python_basin_streams_the_map_as_the_cli_does(tmp_path):
    import coincli

    store, rrd = tmp_path / "s.zarr", tmp_path / "s.rrd"
    seen = []
    ds = coincli.basin(coincli.load_preset("paper"), res=16, chunk=8, threads=1, store=store,
                       rrd=rrd, progress=seen.append)
    assert ds.quarter_turns.shape == (16, 16) and seen  # the caller's progress still called
    tables = rows(rrd)
    check_map(tables, read_basin(store), static=False)
    cells = tables[("/progress/cells", False)].sort_by("sweep_time")
    assert cells.column("Scalars:scalars").to_pylist()[-1][0] == 16 * 16


def test_python_live_recordings_are_checked_before_any_work(tmp_path, monkeypatch):
    import coincli

    base = coincli.load_preset("paper")
    with pytest.raises(coincli.ParameterError, match="reads its tiles from the store"):
        coincli.basin(base, res=8, rrd=tmp_path / "s.rrd")
    with pytest.raises(coincli.ParameterError, match=r"rrd must be a file name ending in \.rrd"):
        coincli.basin(base, res=8, store=tmp_path / "s.zarr", rrd=tmp_path / "s.txt")
    with pytest.raises(OSError):
        coincli.fractions(base, samples=500, rrd=tmp_path / "missing" / "f.rrd")
    with pytest.raises(coincli.ParameterError, match="connect must be the URL"):
        coincli.fractions(base, samples=500, connect="http://localhost:1")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(coincli.ParameterError, match="spawn: no display"):
        coincli.basin(base, res=8, store=tmp_path / "s.zarr", spawn=True)
    with pytest.raises(coincli.ParameterError, match="needs a destination"):
        coincli.show_basin(tmp_path / "s.zarr")
    assert not (tmp_path / "s.zarr").exists() and list(tmp_path.iterdir()) == []


def test_python_fractions_stream_their_estimates(tmp_path):
    import coincli

    rrd = tmp_path / "f.rrd"
    result = coincli.fractions(coincli.load_preset("paper"), samples=1000, batch=500,
                               threads=1, rrd=rrd)
    series = rows(rrd)[("/estimate/standing", False)].sort_by("samples")
    assert series.column("samples").to_pylist() == [500, 1000]
    last = series.column("Scalars:scalars").to_pylist()[-1][0]
    assert last == pytest.approx(100 * result.standing["probability"])


def test_a_python_recording_that_fails_warns_and_keeps_the_result(tmp_path, monkeypatch):
    """The run's result is what was asked for: a recording lost on the way (here its process
    killed at once) is a RuntimeWarning, not an exception that would lose the result."""
    import coincli

    monkeypatch.setattr(sweep_recording, "RECORDER", "import os, signal; os.kill(os.getpid(), "
                                                     "signal.SIGKILL)")
    store = tmp_path / "s.zarr"
    with pytest.warns(RuntimeWarning, match="the live recording failed: the recording "
                                            "process ended before it was done") as warned:
        ds = coincli.basin(coincli.load_preset("paper"), res=16, chunk=8, threads=1,
                           store=store, rrd=tmp_path / "s.rrd")
    assert ds.quarter_turns.shape == (16, 16) and read_basin(store).done.all()
    assert warned[0].filename == __file__  # the caller's line, not the package's


def test_python_show_basin_is_coin_basin_show(tmp_path):
    import coincli

    store = tmp_path / "s.zarr"
    assert runner.invoke(app, ["basin", str(store), *SMALL]).exit_code == 0
    rrd = tmp_path / "show.rrd"
    coincli.show_basin(coincli.open_basin(store), rrd=rrd)
    check_map(rows(rrd), read_basin(store), static=True)


# -- coin basin analyze ---------------------------------------------------------------------------
def test_analyze_rrd_has_each_band_f_of_eps_the_fits_and_the_map(tmp_path):
    import math

    store, rrd = tmp_path / "s.zarr", tmp_path / "a.rrd"
    assert runner.invoke(app, ["basin", str(store), "--res", "64", "--chunk", "32", "-q",
                               "--threads", "1"]).exit_code == 0
    result = runner.invoke(app, ["basin", "analyze", str(store), "--points", "400", "--bands",
                                 "2", "--eps-values", "3", "--threads", "1", "-q", "--json",
                                 "--rrd", str(rrd)])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    tables = rows(rrd)
    check_map(tables, read_basin(store), static=True)  # the map analysed
    timeline = "log10 eps [1e-1]"  # eps 1e-9, 10**-6.5, 1e-4
    for key, region in [("whole", out), *((f"band_{i + 1}", b)
                                          for i, b in enumerate(out["bands"]))]:
        fraction = region["perturbation"]["fraction"]
        expected = [(s, math.log10(f)) for s, f in zip([-90, -65, -40], fraction, strict=True)
                    if f > 0]  # log10: no point where no throw is uncertain
        if not expected:
            assert (f"/analysis/f/{key}", False) not in tables
            continue
        got = tables[(f"/analysis/f/{key}", False)].sort_by(timeline)
        assert got.column(timeline).to_pylist() == [s for s, _ in expected]
        assert [r[0] for r in got.column("Scalars:scalars").to_pylist()] == pytest.approx(
            [v for _, v in expected])
        if region["uncertainty_exponent"] is not None:  # the fitted line's ends
            fit = tables[(f"/analysis/fit/{key}", False)].sort_by(timeline)
            ends = [r[0] for r in fit.column("Scalars:scalars").to_pylist()]
            assert (ends[1] - ends[0]) / 5.0 == pytest.approx(region["uncertainty_exponent"])
    edge, = tables[("/basin/bands", True)].column("LineStrips2D:strips").to_pylist()[-1]
    assert edge == [[out["bands"][1]["rows"][0], 0.0], [out["bands"][1]["rows"][0], 64.0]]
    text = tables[("/analysis/info", True)].column("TextDocument:text").to_pylist()[-1][0]
    assert f"{out['uncertainty_exponent']:.2f}" in text and "| whole map |" in text


def test_python_analyze_records_and_calls_on_band(tmp_path):
    import coincli

    store, rrd = tmp_path / "s.zarr", tmp_path / "a.rrd"
    coincli.basin(coincli.load_preset("paper"), res=32, chunk=32, threads=1, store=store)
    seen = []
    analysis = coincli.analyze(store, points=200, bands=2, threads=1, rrd=rrd,
                               on_band=lambda i, band_rows, f: seen.append((i, band_rows)))
    assert seen == [(i, b.rows) for i, b in enumerate(analysis.bands)]
    assert ("/analysis/info", True) in rows(rrd)


# -- in a notebook's cell -------------------------------------------------------------------------
def test_a_sweep_in_a_notebook_draws_its_map_in_this_process(tmp_path, monkeypatch):
    """notebook=: the map is made in the kernel's process (its viewer belongs there), by the
    same StoreMap as a recording process: the last map is the store's. (The notebook's viewer
    is replaced by a file here; the next tests send to a viewer.)"""
    import coincli
    from coincli.recordings.stream import open_stream

    pytest.importorskip("rerun_notebook")
    inline = tmp_path / "inline.rrd"
    monkeypatch.setattr(rerun_stream, "in_notebook", lambda: True)
    monkeypatch.setattr(rerun_stream.Destination, "stream",
                        lambda self, name: open_stream(name, rrd=inline))
    monkeypatch.setattr(sweep_recording.SweepRecorder, "start",
                        lambda self: pytest.fail("no recording process in a notebook"))
    store = tmp_path / "s.zarr"
    coincli.basin(coincli.load_preset("paper"), res=16, chunk=8, threads=1, store=store,
                  notebook=True)
    check_map(rows(inline), read_basin(store), static=False)


def test_a_viewer_of_an_earlier_cell_receives_the_work_of_a_later_one(tmp_path, monkeypatch):
    """coincli.viewer() shows a viewer at once; notebook=viewer sends to it (no new viewer):
    by the time a later cell runs, it is ready and shows the work as it comes."""
    import coincli

    pytest.importorskip("rerun_notebook")
    from rerun.notebook import Viewer

    shown, sent = [], []
    monkeypatch.setattr(rerun_stream, "in_notebook", lambda: True)
    monkeypatch.setattr(Viewer, "display", lambda self, **options: shown.append(self))
    monkeypatch.setattr(Viewer, "_flush_hook", lambda self, data: sent.append((self, len(data))))
    viewer = coincli.viewer(width=600, height=400)
    assert shown == [viewer]
    store = tmp_path / "s.zarr"
    coincli.basin(coincli.load_preset("paper"), res=16, chunk=8, threads=1, store=store,
                  notebook=viewer)
    assert shown == [viewer] and sum(n for v, n in sent if v is viewer) > 10_000
    with pytest.raises(coincli.ParameterError, match="notebook must be True or a viewer"):
        coincli.show_basin(store, notebook="cell")


def test_a_notebook_stream_shows_the_viewer_then_sends_to_it(monkeypatch):
    pytest.importorskip("rerun_notebook")
    from rerun.notebook import Viewer

    from coincli.recordings.stream import open_stream

    shown, sent = [], []
    monkeypatch.setattr(Viewer, "display", lambda self, **options: shown.append(options))
    monkeypatch.setattr(Viewer, "_flush_hook", lambda self, data: sent.append(len(data)))
    with open_stream("coin test", notebook=True) as rec:
        assert shown == [{}]  # at once, not waited for (see open_stream)
        rec.log("x", rr.Scalars(1.0))
    assert sum(sent) > 0


def test_notebook_true_is_checked_before_any_work(tmp_path, monkeypatch):
    import coincli

    pytest.importorskip("rerun_notebook")
    base = coincli.load_preset("paper")
    with pytest.raises(RuntimeError, match=r"notebook=True draws in a notebook .*rrd="):
        coincli.fractions(base, samples=500, notebook=True)
    monkeypatch.setattr(rerun_stream, "in_notebook", lambda: True)
    with pytest.raises(coincli.ParameterError, match="goes alone"):
        coincli.analyze(tmp_path / "none.zarr", notebook=True, rrd=tmp_path / "a.rrd")
    with pytest.raises(coincli.ParameterError, match="goes alone"):
        coincli.show_basin(tmp_path / "none.zarr", notebook=True, spawn=True)
    assert list(tmp_path.iterdir()) == []


def test_fractions_live_in_a_real_notebook_kernel(tmp_path):
    """Executed by a Jupyter kernel: the estimates go to Rerun's widget in the cell, no
    error."""
    outputs = outputs_in_a_kernel(
        "import coincli\n"
        "r = coincli.fractions(coincli.load_preset('paper'), samples=1000, batch=500, "
        "threads=1, notebook=True)\n"
        "print(r.samples)", tmp_path)
    assert shows_a_widget(outputs)
    assert any(o.get("text", "").strip() == "1000" for o in outputs if o["output_type"] == "stream")


def test_a_sweep_refused_before_any_work_records_nothing(tmp_path):
    """The recording process is told what to record with the sweep's first progress: a sweep
    refused at once (a store of another sweep) writes no recording and opens no viewer."""
    store, rrd = tmp_path / "s.zarr", tmp_path / "s.rrd"
    assert runner.invoke(app, ["basin", str(store), *SMALL]).exit_code == 0
    result = runner.invoke(app, ["basin", str(store), *SMALL, "--k", "999", "--rrd", str(rrd)],
                           env={"COLUMNS": "400"})
    assert result.exit_code == 2 and "holds a different sweep" in result.stderr, result.output
    assert not rrd.exists() and list(tmp_path.glob("*.rrd")) == []


def test_a_store_complete_already_is_still_recorded(tmp_path):
    store, rrd = tmp_path / "s.zarr", tmp_path / "s.rrd"
    assert runner.invoke(app, ["basin", str(store), *SMALL]).exit_code == 0
    result = runner.invoke(app, ["basin", str(store), *SMALL, "--rrd", str(rrd)])
    assert result.exit_code == 0 and "every tile is done already" in result.output
    check_map(rows(rrd), read_basin(store), static=False)


def test_the_answer_of_the_recording_process_does_not_wait_for_its_children():
    """A viewer spawned by the recording process inherits its stdout: the answer goes to a
    copy no child inherits, so reading it to its end does not wait for the viewer."""
    code = ("import os, subprocess, sys\n"
            "from coincli.recordings.sweep_recording import answer_line\n"
            "out = answer_line()\n"
            "subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(30)'])\n"
            "out.write('{\"error\": null}\\n'); out.flush(); os._exit(0)")
    start = time.monotonic()
    done = subprocess.run([sys.executable, "-P", "-c", code], stdout=subprocess.PIPE,
                          stderr=subprocess.DEVNULL, text=True, timeout=25)
    assert done.stdout == '{"error": null}\n' and time.monotonic() - start < 10


def test_api_errors_quoted_values_are_left_as_given():
    from coincli.cli.common import in_cli_words
    from coincli.params import ParameterError

    error = ParameterError("rrd must be a file name ending in .rrd, got 'rrd/out.txt'",
                           parameters=("rrd",))
    assert in_cli_words(error) == ("--rrd must be a file name ending in .rrd, got "
                                   "'rrd/out.txt'")
