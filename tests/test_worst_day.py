"""The worst day, part three (issue 40): a full disk under an export and a recording, a killed
recorded sweep, a store of a newer coin, a lost root zarr.json, a tile too large for memory, a
read-only store that needs no write, a Dask cluster without a worker, and the count a SIGTERM
leaves. Each test makes the fault (a fault injected at the write, a tiny tmpfs where this
process may mount one, a killed process, an edited format number) and checks what
docs/robustness.md promises: one line, the right exit code, no temporary file, no traceback,
the good data kept."""

from __future__ import annotations

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import default_signals, local_cluster
from test_live import check_map, rows
from test_signals import free_port
from test_store import (
    ARGS,
    Disk,
    assert_identical,
    coin,
    coin_ok,
    copy_store,
    files_of,
    leftovers,
    one_line_error,
)
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.engines import basin_plan as plan_module
from coincli.engines import executors
from coincli.params import ParameterError
from coincli.recordings import stream as rerun_stream
from coincli.stores.basin_schema import FORMAT
from coincli.stores.basin_store import BasinStore
from coincli.stores.fractions_store import FORMAT as FRACTIONS_FORMAT

runner = CliRunner()
ROOT = Path(__file__).parent.parent
FRACTIONS = ["fractions", "--samples", "512", "--batch", "256", "--threads", "1"]


@pytest.fixture(scope="module")
def clean(tmp_path_factory) -> Path:
    """An uninterrupted 8 x 8 store (4 tiles), computed once."""
    path = tmp_path_factory.mktemp("clean") / "clean.zarr"
    coin_ok(path, *ARGS)
    return path


def one_warning(result) -> str:
    """The one line a command that worked printed on stderr (exit 0)."""
    assert result.exit_code == 0, result.output
    err = result.stderr.strip()
    assert err.startswith("warning:") and len(err.splitlines()) == 1, err
    return " ".join(err.split())


def coin_in_a_process(*args, fault: str = "", timeout: float = 120, cwd=None):
    """`coin ARGS` in a process of its own (its stderr whole: what Rerun or h5py print below
    Python goes there too), with ``fault`` (Python source) run first."""
    code = f"{fault}\nimport sys\nsys.argv = ['coin', *{list(map(str, args))!r}]\n" \
           "from coincli.cli import main\nmain()\n"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd or ROOT, env={**os.environ, "COLUMNS": "200"})


def assert_one_error_line(proc, *fragments: str, code: int = 2) -> str:
    err = proc.stderr.strip()
    assert proc.returncode == code, (proc.returncode, err)
    assert err.startswith("error:") and len(err.splitlines()) == 1, err
    assert "Traceback" not in err and "\x1b[" not in err, err  # nothing of Rerun's, no colour
    for fragment in fragments:
        assert fragment in err, err
    return err


# A full disk, injected at Python's own writes: every file whose name has the temporary mark
# of an output (`.NAME.tmp-PID.SUFFIX`) takes LIMIT bytes, then ENOSPC
FULL_DISK = """
import builtins, errno, os
LIMIT = 4096
real_open = builtins.open

class Full:
    def __init__(self, f):
        self.f, self.n = f, 0
    def write(self, data):
        self.n += len(data)
        if self.n > LIMIT:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return self.f.write(data)
    def __enter__(self):
        return self
    def __exit__(self, *exc):
        self.f.close()
    def __getattr__(self, name):
        return getattr(self.f, name)

def fake_open(file, mode="r", *args, **kwargs):
    f = real_open(file, mode, *args, **kwargs)
    return Full(f) if ".tmp-" in os.fspath(file) and "w" in mode else f

builtins.open = fake_open
"""


# -- 1. a full disk during an export ----------------------------------------------------------
def test_a_full_disk_during_a_netcdf_export_is_one_line_and_leaves_nothing(tmp_path, clean):
    """The NetCDF file is made in memory and written by us: a full disk is our one-line
    error, never h5py's tracebacks and a segfault (exit 139) with `.e.tmp-PID.nc` left."""
    out = tmp_path / "e.nc"
    out.write_text("the previous export\n")
    proc = coin_in_a_process("basin", "export", clean, out, fault=FULL_DISK)
    assert_one_error_line(proc, f"cannot write {out}", "no space left on device (ENOSPC)")
    assert out.read_text() == "the previous export\n"  # untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e.nc"]  # no temporary file
    result = runner.invoke(app, ["basin", "export", str(clean), str(out)])  # room again
    assert result.exit_code == 0, result.output
    assert coincli.basin_stats(coincli.open_basin(out))["computed"] == 64


def test_a_netcdf_export_is_whole_when_written_from_memory(tmp_path, clean):
    import xarray as xr

    out = tmp_path / "m.nc"
    coincli.export_basin(coincli.open_basin(clean), out)
    with xr.open_dataset(out, engine="h5netcdf") as ds:
        assert ds.identical(coincli.open_basin(clean))


# -- 2. a full disk under a recording -----------------------------------------------------------
def test_a_recording_that_meets_a_full_disk_is_our_one_line(tmp_path, clean):
    """Rerun writes into a pipe that this process drains into the file: a full disk is one
    line of ours, never Rerun's ERROR and WARN lines nor a hang, and no file is left."""
    for rrd, args in ((tmp_path / "e.rrd", ["basin", "show", clean]),
                      (tmp_path / "t.rrd", ["simulate"]),
                      (tmp_path / "f.rrd", [*FRACTIONS, "-q"])):
        proc = coin_in_a_process(*args, "--rrd", rrd, fault=FULL_DISK, timeout=60)
        assert_one_error_line(proc, f"could not write the recording: '{rrd}': no space left "
                                    "on device (ENOSPC)")
    assert list(tmp_path.iterdir()) == []  # no recording, no temporary file


def test_a_recording_is_written_as_it_is_made(tmp_path):
    """A long recording (a sweep's, a Monte Carlo run's) is not held in memory: what Rerun
    encodes reaches the file as it comes, through a pipe of 64 KiB."""
    import rerun as rr

    rrd = tmp_path / "long.rrd"
    image = np.random.default_rng(0).integers(0, 60000, (512, 512), dtype=np.uint16)
    with rerun_stream.open_stream("long", rrd=rrd) as rec:
        for step in range(40):
            rec.set_time("step", sequence=step)
            rec.log("image", rr.SegmentationImage(image))
        rec.flush(timeout_sec=30)
        deadline = time.monotonic() + 10
        while sum(f.stat().st_size for f in tmp_path.glob(".long.tmp-*")) < 40 * 512 * 512:
            assert time.monotonic() < deadline, "the data did not reach the file as they came"
            time.sleep(0.05)
    assert [p.name for p in tmp_path.iterdir()] == ["long.rrd"]
    assert len(rows(rrd)[("/image", False)]) == 40


@pytest.fixture
def full_disk(tmp_path):
    """A 6 MB tmpfs filled to 20 KB free, where this process may mount one (root, `mount`
    allowed); the test is skipped elsewhere."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("mounting a tmpfs needs root")
    mnt = tmp_path / "tiny"
    mnt.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=6m", "tmpfs", str(mnt)],
                             capture_output=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.strip()}")
    try:
        st = os.statvfs(mnt)
        fd = os.open(mnt / "filler", os.O_CREAT | os.O_WRONLY)
        try:
            os.posix_fallocate(fd, 0, st.f_bavail * st.f_frsize - 20 * 1024)
        finally:
            os.close(fd)
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def test_a_real_full_disk_under_an_export_and_a_recording(full_disk, clean):
    """As issue 40 found them, on a 6 MB tmpfs with 20 KB free: the export ended in a segfault
    after h5py's tracebacks, `show --rrd` in Rerun's log lines (or a hang). Now: one line each,
    exit 2, nothing left but the filler."""
    proc = coin_in_a_process("basin", "export", clean, full_disk / "e.nc")
    assert_one_error_line(proc, "no space left on device")
    for args in (["basin", "show", clean, "--rrd", full_disk / "e.rrd"],
                 ["simulate", "--rrd", full_disk / "t.rrd"]):
        proc = coin_in_a_process(*args, timeout=60)
        assert_one_error_line(proc, "could not write the recording", "no space left on device")
    assert [p.name for p in full_disk.iterdir()] == ["filler"]


# -- 3. kill -9 of a recorded sweep -----------------------------------------------------------
@pytest.mark.parametrize("run", range(3))
def test_kill_9_of_a_recorded_sweep_leaves_no_traceback_and_a_whole_recording(tmp_path, run):
    """The sweep's process killed (SIGKILL) at a tile: its recording process, whose answer
    nobody reads any more, prints nothing (it printed BrokenPipeError's traceback in 8 of 10
    runs), and its recording is whole and the store's map. (10 of 10 runs, see the report.)"""
    import psutil

    store, rrd = tmp_path / "s.zarr", tmp_path / "live.rrd"
    with open(tmp_path / "stderr.txt", "wb") as err:
        sweep = subprocess.Popen([sys.executable, "-m", "coincli", "basin", str(store), "--res",
                                  "512", "--chunk", "64", "--threads", "1", "-q", "--rrd",
                                  str(rrd)], stdout=subprocess.DEVNULL, stderr=err,
                                 start_new_session=True, preexec_fn=default_signals, cwd=ROOT)
    try:
        deadline = time.monotonic() + 60
        while not any(f.is_file() and f.suffix != ".partial"
                      for f in (store / "done" / "c").rglob("*")):
            assert sweep.poll() is None and time.monotonic() < deadline
            time.sleep(0.005)
        time.sleep(0.1 * run)  # a tile or two later
        recorder, = psutil.Process(sweep.pid).children()
        sweep.kill()
        assert sweep.wait(timeout=30) == -signal.SIGKILL
    finally:
        if sweep.poll() is None:
            sweep.kill()
    recorder.wait(timeout=30)
    said = (tmp_path / "stderr.txt").read_text()
    assert said == "", said
    basin = BasinStore.open(store).read()
    assert 0 < basin.done.sum() < basin.done.size
    check_map(rows(rrd), basin, static=False)


# -- 4. a store of a newer coin -----------------------------------------------------------------
def _set_format(path: Path, mark: str, fmt: int) -> None:
    f = path / "zarr.json"
    document = json.loads(f.read_text())
    document["attributes"][mark]["format"] = fmt
    f.write_text(json.dumps(document, indent=2))


def test_a_basin_store_of_a_newer_coin_is_never_advised_away(tmp_path, clean):
    path = copy_store(clean, tmp_path / "s.zarr")
    _set_format(path, "coin_basin", FORMAT + 1)
    before = files_of(path)
    for args in ([path, *ARGS], [path, *ARGS, "--threads", "1"], ["stats", path],
                 ["render", path, "-o", tmp_path / "m.png"], ["export", path, tmp_path / "m.nc"],
                 ["verify", path], ["inspect", path, "--cell", "1,2"],
                 ["show", path, "--rrd", tmp_path / "m.rrd"]):
        err = one_line_error(coin(*args))
        assert f"a basin store of format {FORMAT + 1}" in err and "newer coin" in err, err
        assert "upgrade coincli" in err and "overwrite" not in err, err
    assert files_of(path) == before  # its data kept, nothing written
    _set_format(path, "coin_basin", FORMAT - 1)  # an older one: recomputing it is the way
    assert "--overwrite" in one_line_error(coin(path, *ARGS))


def test_a_fractions_store_of_a_newer_coin_is_never_advised_away(tmp_path):
    store = tmp_path / "f.zarr"
    assert runner.invoke(app, [*FRACTIONS, "--store", str(store)]).exit_code == 0
    _set_format(store, "coin_fractions", FRACTIONS_FORMAT + 1)
    err = one_line_error(runner.invoke(app, [*FRACTIONS, "--store", str(store)]))
    assert "newer coin" in err and "upgrade coincli" in err and "overwrite" not in err, err
    _set_format(store, "coin_fractions", FRACTIONS_FORMAT - 1)
    assert "--overwrite" in one_line_error(runner.invoke(app, [*FRACTIONS, "--store",
                                                                str(store)]))


# -- 5. a lost root zarr.json, 7. metadata damage said by the commands that read ----------------
def test_a_lost_root_zarr_json_is_recovered_from_the_other_copies(tmp_path, clean):
    """Its tiles are intact and prove the parameters that done/zarr.json keeps: every command
    reads it with them (one warning line), `verify` lists it, a resume rewrites it and the
    store is the uninterrupted one, byte for byte."""
    import xarray as xr

    path = copy_store(clean, tmp_path / "s.zarr")
    (path / "zarr.json").unlink()
    result = coin("verify", path)
    assert result.exit_code == 1 and "metadata zarr.json" in result.stdout, result.output
    for args in (["render", path, "-o", tmp_path / "m.png"], ["export", path, tmp_path / "m.nc"],
                 ["inspect", path, "--cell", "1,2"], ["show", path, "--rrd", tmp_path / "m.rrd"]):
        warning = one_warning(coin(*args))
        assert f"{path}: damaged metadata (zarr.json cannot be read" in warning, warning
        assert "read with the parameters its computed tiles prove" in warning, warning
    assert coincli.basin_stats(tmp_path / "m.nc")["computed"] == 64  # every tile
    assert "parameters changed in zarr.json" in coin("stats", path).output
    resumed = coin_ok(path, *ARGS)
    assert "repaired:" in resumed.stderr and "zarr.json" in resumed.stderr
    assert_identical(path, clean)
    xr.open_zarr(path).load()


def test_metadata_damage_is_said_by_the_commands_that_read_the_store(tmp_path, clean):
    path = copy_store(clean, tmp_path / "s.zarr")
    f = path / "vy" / "zarr.json"
    document = json.loads(f.read_text())
    document["shape"] = [7]
    f.write_text(json.dumps(document))
    warning = one_warning(coin("render", path, "-o", tmp_path / "m.png"))
    assert "1 metadata file differs from its parameters: vy/zarr.json" in warning, warning
    assert "its copies agree on" in warning and "coin basin verify" in warning, warning
    assert coin("verify", path).exit_code == 1


# -- 6. a tile too large for memory -------------------------------------------------------------
def test_a_tile_too_large_for_memory_is_refused_before_any_work(tmp_path, monkeypatch):
    """A tile of 65536 x 65536 cells would ask for about 390 GiB (issue 40's 20000 x 20000
    asked numpy for 17.9 GiB, and ended in _ArrayMemoryError): refused in one line naming
    --chunk, nothing created."""
    path = tmp_path / "h.zarr"
    err = one_line_error(coin(path, "--res", "65536", "--chunk", "65536", "--yes"))
    assert err.startswith("error: --chunk 65536x65536: a tile of 4,294,967,296 cells needs")
    assert "give a smaller --chunk (at most" in err, err
    assert list(tmp_path.iterdir()) == []
    # the API names the parameter; with threads, the tiles computed at once count
    scene = coincli.load_preset("paper")
    with pytest.raises(ParameterError) as refused:
        coincli.plan_sweep(scene, res=65536, chunk=65536)
    assert refused.value.parameters == ("chunk",)
    plan = coincli.plan_sweep(scene, res=64, chunk=64)
    one_tile = 64 * 64 * plan_module.TILE_BYTES_PER_CELL
    monkeypatch.setattr(plan_module, "available_memory", lambda: int(1.5 * one_tile))
    coincli.plan_sweep(scene, res=64, chunk=64)  # one tile fits
    with pytest.raises(ParameterError, match="2 tiles at once") as refused:
        coincli.sweep(plan, path, threads=2)
    assert refused.value.parameters == ("chunk",)
    assert list(tmp_path.iterdir()) == []


# -- 7. what the report counts after an interrupt -------------------------------------------
def test_the_count_after_an_interrupt_is_what_the_store_holds(tmp_path, monkeypatch):
    """A tile cut off by the stop after it was computed is written whole all the same (its
    mirror image too): the report counts the tiles in the store, not the tiles it was told of
    (a SIGTERM run printed 56/64 tiles done while the store held 58)."""
    plan = coincli.plan_sweep(coincli.load_preset("paper"), res=8, chunk=4)  # 2 mirror pairs
    gate, at_gate, first, lock = threading.Event(), threading.Event(), [], threading.Lock()
    write = BasinStore.write_tile

    def slow_second(self, result, parameters=None):
        task = result.mirror_of or result.tile  # the tile its task computed
        with lock:
            first[:] = first or [task]
        if task != first[0]:  # the second task's tiles: written once the stop has come
            at_gate.set()
            gate.wait(10)
        return write(self, result, parameters)

    def stop(update):
        # the first task's tiles are written: the stop comes once the second has computed its
        # own and is writing them, however loaded the machine (else the stop would cut it off
        # before its write, and nothing would be left to count)
        assert at_gate.wait(10)
        gate.set()
        raise KeyboardInterrupt

    monkeypatch.setattr(BasinStore, "write_tile", slow_second)
    path = tmp_path / "s.zarr"
    report = coincli.sweep(plan, path, threads=2, progress=stop)
    held = BasinStore.open(path).check().tiles_done
    assert held > report.tiles_computed  # a task the stop cut off wrote its tiles
    assert report.tiles_done == held


# -- 7. a full disk under `coin fractions --store` names the store --------------------------
def test_a_full_disk_under_a_fractions_store_names_it(tmp_path, monkeypatch):
    store = tmp_path / "f.zarr"
    Disk(monkeypatch, tmp_path, errno.ENOSPC, after=12, match=".partial")
    err = one_line_error(runner.invoke(app, [*FRACTIONS, "--samples", "4096", "--store",
                                             str(store)]))
    assert err.startswith(f"error: cannot write {store}: no space left on device"), err
    assert "the batches written so far are kept" in err
    monkeypatch.undo()
    assert leftovers(tmp_path) == []
    assert runner.invoke(app, [*FRACTIONS, "--samples", "4096", "--store",
                               str(store)]).exit_code == 0  # room again: it resumes


# -- 7. a complete store on a read-only mount -----------------------------------------------------
def test_a_complete_store_on_a_read_only_mount_needs_no_write(tmp_path, clean, monkeypatch):
    ro = tmp_path / "ro"
    ro.mkdir()
    path = copy_store(clean, ro / "s.zarr")
    partial = copy_store(clean, ro / "p.zarr")
    (partial / "done" / "c" / "1" / "1").unlink()
    before = files_of(ro)
    Disk(monkeypatch, ro, errno.EROFS)
    assert "every tile is done already" in coin_ok(path, *ARGS).stdout
    for args in (["stats", path], ["verify", path], ["render", path, "-o", tmp_path / "m.png"],
                 ["export", path, tmp_path / "m.nc"], ["inspect", path, "--cell", "1,2"]):
        result = coin(*args)
        assert result.exit_code == 0 and result.stderr == "", result.output
    err = one_line_error(coin(partial, *ARGS))  # it has a tile to write
    assert err == (f"error: the store {partial} is read-only (read-only file system): a sweep "
                   "cannot write to it here"), err
    assert "read-only" in one_line_error(coin(path, *ARGS, "--overwrite"))
    assert files_of(ro) == before


# -- 7. a Dask cluster without a worker ---------------------------------------------------------
def test_a_cluster_without_a_worker_is_said_and_ends_at_the_time_out(tmp_path):
    """Its only worker lost (or none joined): the run says what it waits for, and stops at
    --worker-timeout (exit 3, the store kept), where it waited in silence."""
    from distributed import Client

    address = f"tcp://127.0.0.1:{free_port()}"
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                                  "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                                  "--no-dashboard"], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)
    try:
        with Client(address, timeout="30s"):
            pass  # it answers
        start = time.monotonic()
        proc = coin_in_a_process("basin", tmp_path / "s.zarr", *ARGS, "--scheduler", address,
                                 "--worker-timeout", "7")
        took = time.monotonic() - start
    finally:
        scheduler.kill()
        scheduler.wait()
    err = proc.stderr.strip().splitlines()
    assert proc.returncode == 3, proc.stderr
    assert err[0].startswith(f"waiting for a Dask worker: the cluster at {address} has had "
                             "none for 5 s; the run goes on when one joins, and stops if none "
                             "has joined after 7 s"), err
    assert err[1].startswith(f"error: the Dask cluster at {address} has had no worker for 7 s; "
                             "the store keeps every finished tile: resume with coin basin"), err
    assert len(err) == 2 and 7 < took < 30, (err, took)


def test_a_local_cluster_beside_another_says_nothing_of_ports(tmp_path):
    """Port 8787, where distributed puts a scheduler's HTTP server by default, held by another
    cluster (a second coin run, a notebook's): coin's local cluster takes a free port quietly,
    not with distributed's four-line warning on the terminal."""
    import socket
    import warnings

    holder = socket.socket()
    try:
        holder.bind(("", 8787))
        holder.listen()
    except OSError:
        pass  # held already, as the test wants
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            client, cluster = executors.open_dask(None, 1)
            client.close()
            cluster.close()
    finally:
        holder.close()
    assert not [w for w in caught if "8787" in str(w.message)], [str(w.message) for w in caught]


def test_a_worker_that_joins_ends_the_wait(tmp_path, monkeypatch, caplog):
    monkeypatch.setattr(executors, "NO_WORKER_NOTICE", 0.5)
    plan = coincli.plan_sweep(coincli.load_preset("paper"), res=8, chunk=4)
    with local_cluster(0) as cluster:
        def join_later():
            while "waiting for a Dask worker" not in caplog.text:
                time.sleep(0.05)
            cluster.scale(1)

        threading.Thread(target=join_later, daemon=True).start()
        with caplog.at_level("WARNING", logger="coincli.dask"):
            report = coincli.sweep(plan, tmp_path / "s.zarr", scheduler=cluster.scheduler_address,
                                   worker_timeout=120)
    assert report.complete
    assert "has had none for 0 s" in caplog.text or "has had none for 1 s" in caplog.text
    assert "and stops if none has joined after 120 s" in caplog.text
    assert "a Dask worker joined the cluster" in caplog.text
    with pytest.raises(ParameterError, match="worker_timeout is for a Dask run"):
        coincli.sweep(plan, tmp_path / "t.zarr", worker_timeout=5)
    assert "--worker-timeout must be" in one_line_error(coin(
        tmp_path / "t.zarr", *ARGS, "--workers", "1", "--worker-timeout", "0"))
