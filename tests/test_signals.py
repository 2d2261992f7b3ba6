"""Ending a run early by fault injection: SIGTERM and SIGHUP mid-sweep (taken as Ctrl-C: claims
released, run recorded, exit 143 and 129), and a Dask scheduler killed mid-run (one line, exit
3, within a second); each resumed to a store bit-identical to an uninterrupted one."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import default_signals
from test_basin import KILL_ARGS, assert_same_store, coin_ok, start_sweep, wait_for_tiles

from coincli.cli import interruptions
from coincli.engines.executors import SchedulerLost
from coincli.stores.basin_store import BasinStore


@pytest.fixture(scope="module")
def clean(tmp_path_factory) -> Path:
    """The sweep of KILL_ARGS, uninterrupted."""
    path = tmp_path_factory.mktemp("clean") / "clean.zarr"
    coin_ok(str(path), *KILL_ARGS)
    return path


def runs(path: Path) -> list[dict]:
    """The run records of a store (basin or fractions: the same records folder)."""
    return BasinStore(path).runs()


def claims_left(path: Path) -> list[str]:
    folder = BasinStore(path).claims_dir
    return sorted(p.name for p in Path(folder).iterdir()) if Path(folder).exists() else []


# -- SIGTERM and SIGHUP --------------------------------------------------------------------------
@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_termination_signal_stops_like_ctrl_c(tmp_path, clean, signum, code):
    path = tmp_path / "s.zarr"
    proc = start_sweep(str(path), *KILL_ARGS)
    wait_for_tiles(proc, path, 3)
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=30)
    err = err.decode()
    assert proc.returncode == code, err
    assert "Traceback" not in err
    assert f"stopped: {signum.name}: " in err and "resume" in err
    assert 3 <= BasinStore.open(path).read().done.sum() < BasinStore.open(path).read().done.size
    assert runs(path)[-1]["interrupted"] is True
    assert claims_left(path) == []  # another host need not wait for them to go stale
    coin_ok(str(path), *KILL_ARGS)  # resume
    assert_same_store(path, clean)


# one thread, so that the signal comes mid-run however fast the machine
FRACTIONS = ["fractions", "--samples", "60000", "--threads", "1", "--yes", "-q", "--json"]


def test_sigterm_mid_fractions_records_and_resumes(tmp_path):
    """`coin fractions --store` as `coin basin`: exit 143, the batches done kept and recorded,
    no claim left; the resumed store holds what an uninterrupted run's does."""
    import numpy as np

    from coincli import api
    from coincli.stores.fractions_store import FractionsStore

    def coin(path: Path) -> subprocess.Popen:
        return subprocess.Popen([sys.executable, "-m", "coincli", *FRACTIONS, "--store",
                                 str(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                cwd=Path(__file__).parent.parent)

    path = tmp_path / "f.zarr"
    proc = coin(path)
    end = time.monotonic() + 60
    while not batches_written(path):
        assert proc.poll() is None and time.monotonic() < end, proc.communicate()[1].decode()
        time.sleep(0.005)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 143, err.decode()
    assert b"Traceback" not in err
    assert runs(path)[-1]["interrupted"] is True
    assert 0 < runs(path)[-1]["samples"] < 60000
    assert not FractionsStore(path).claims_dir.exists()
    for target in (path, tmp_path / "clean.zarr"):  # resume; an uninterrupted run
        proc = coin(target)
        _, err = proc.communicate(timeout=60)  # its JSON is larger than a pipe holds
        assert proc.returncode == 0, err.decode()
    resumed, clean = (api.open_fractions(p) for p in (path, tmp_path / "clean.zarr"))
    for name in clean.data_vars:
        np.testing.assert_array_equal(resumed[name].values, clean[name].values, name)


def batches_written(path: Path) -> bool:
    from coincli.stores.fractions_store import FractionsStore

    try:
        return bool(FractionsStore(path).read_filled().any())
    except Exception:  # noqa: BLE001 - not created yet, or being created
        return False


def test_a_second_signal_during_the_first_ones_clean_up_still_ends_it():
    """KeyboardInterrupt out of the command (the second signal) ends quietly with the code."""
    interruptions._received[:] = [signal.SIGTERM]
    try:
        def interrupted_twice() -> int:
            raise KeyboardInterrupt

        def terminal_gone() -> int:
            raise OSError(5, "Input/output error")

        assert interruptions.ended_by_signal(interrupted_twice) == 143
        assert interruptions.ended_by_signal(terminal_gone) == 143
        assert interruptions.ended_by_signal(lambda: 130) == 143
        assert interruptions.ended_by_signal(lambda: 0) == 143
        assert interruptions.ended_by_signal(lambda: 2) == 2  # an error of its own stays
    finally:
        interruptions._received.clear()
    assert interruptions.ended_by_signal(lambda: 130) == 130  # Ctrl-C as before
    with pytest.raises(KeyboardInterrupt):
        interruptions.ended_by_signal(interrupted_twice)


def test_handlers_are_the_commands_only_and_nohup_is_kept():
    """Importing coincli (a notebook, a program) leaves Python's handlers; the command keeps
    an ignored SIGHUP ignored. The child starts with the dispositions of a terminal's process,
    whatever this runner inherited (``nohup make test`` ignores SIGHUP)."""
    code = ("import signal, coincli.api, coincli.cli\n"
            "assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL\n"
            "assert signal.getsignal(signal.SIGHUP) is signal.SIG_DFL\n"
            "signal.signal(signal.SIGHUP, signal.SIG_IGN)\n"
            "from coincli.cli.interruptions import stop_on_termination\n"
            "stop_on_termination()\n"
            "assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN\n"
            "assert signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60,
                   preexec_fn=default_signals)


def test_a_sweep_started_under_nohup_goes_on_after_a_hang_up(tmp_path, clean):
    """`nohup coin basin ...` (SIGHUP ignored when the command starts): a hang-up neither stops
    the sweep nor is recorded; it ends as an uninterrupted one, exit 0."""
    def as_nohup_leaves_it():
        default_signals()
        signal.signal(signal.SIGHUP, signal.SIG_IGN)

    path = tmp_path / "s.zarr"
    proc = subprocess.Popen([sys.executable, "-m", "coincli", "basin", str(path), *KILL_ARGS],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=as_nohup_leaves_it, cwd=Path(__file__).parent.parent)
    wait_for_tiles(proc, path, 3)
    proc.send_signal(signal.SIGHUP)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err.decode()
    assert "stopped" not in err.decode()
    assert [run["interrupted"] for run in runs(path)] == [False]
    assert_same_store(path, clean)


# -- a Dask scheduler lost -----------------------------------------------------------------------
def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def dask_cluster(workers: int = 1):
    """A scheduler and ``workers`` one-thread workers as processes of their own (so that the
    scheduler can be killed): (address, scheduler process)."""
    from distributed import Client

    address = f"tcp://127.0.0.1:{free_port()}"
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                               "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                               "--no-dashboard"], **quiet)]
    try:
        procs += [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker",
                                    address, "--nthreads", "1", "--no-dashboard"], **quiet)
                  for _ in range(workers)]
        with Client(address, timeout="30s") as client:
            client.wait_for_workers(workers, timeout=30)
        yield address, procs[0]
    finally:
        for proc in procs:
            proc.kill()
            proc.wait()


def test_scheduler_killed_mid_sweep_is_one_line_and_resumes(tmp_path, clean):
    path = tmp_path / "s.zarr"
    with dask_cluster() as (address, scheduler):
        proc = start_sweep(str(path), *KILL_ARGS[:-3], "-q", "--scheduler", address)
        wait_for_tiles(proc, path, 3)
        scheduler.kill()
        killed = time.monotonic()
        out, err = proc.communicate(timeout=30)
        took = time.monotonic() - killed
    err = err.decode().strip()
    assert proc.returncode == interruptions.SCHEDULER_LOST, err
    assert err.startswith(f"error: lost the Dask scheduler at {address}: "), err
    assert len(err.splitlines()) == 1, err
    assert "the store keeps every finished tile: resume with coin basin" in err
    assert took < 5, f"{took:.1f} s from the scheduler's end to the command's"
    record = runs(path)[-1]
    assert record["interrupted"] is True and record["mode"] == "dask"
    assert record["workers"] == 1  # the cluster's, not 0
    assert claims_left(path) == []
    assert 3 <= BasinStore.open(path).read().done.sum() < BasinStore.open(path).read().done.size
    coin_ok(str(path), *KILL_ARGS)  # resumed on threads: the same store wherever it runs
    assert_same_store(path, clean)


def test_dask_executor_reports_a_lost_scheduler_and_the_workers():
    from coincli.engines.executors import Dask, ItemQueue

    with dask_cluster() as (address, scheduler):
        executor = Dask(scheduler=address)
        tasks = executor.run(time.sleep, ItemQueue(0.05 for _ in range(400)),
                             name=lambda item: "test-sleep")
        with pytest.raises(SchedulerLost, match=f"lost the Dask scheduler at {address}"):
            for done, _ in enumerate(tasks):
                if done == 3:
                    scheduler.kill()
                    killed = time.monotonic()
        assert time.monotonic() - killed < 5
    assert executor.seen and set(executor.seen) == {1}


def test_a_call_that_meets_the_scheduler_gone_is_cut_short():
    """distributed retries connecting to a gone scheduler for the client's whole timeout (20 s):
    the window and the processing calls must give up within SCHEDULER_CALL_TIMEOUT, so that a
    scheduler killed during one is reported in seconds (a CI run once took 20 s here)."""
    from distributed import Client

    from coincli.engines.executors import (
        SCHEDULER_CALL_TIMEOUT,
        close_dask,
        cluster_window,
        losing_scheduler,
        scheduler_gone,
        scheduler_processing,
    )

    with dask_cluster() as (address, scheduler):
        client = Client(address, timeout="20s")
        assert cluster_window(client) == 2
        os.kill(scheduler.pid, signal.SIGSTOP)  # alive but not answering: keep the window
        try:
            assert cluster_window(client, previous=7) == 7
        finally:
            os.kill(scheduler.pid, signal.SIGCONT)
        scheduler.kill()
        scheduler.wait()
        deadline = time.monotonic() + 10
        while not scheduler_gone(client) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert scheduler_gone(client)
        start = time.monotonic()
        with pytest.raises(TimeoutError):
            cluster_window(client, previous=7)
        assert scheduler_processing(client) == set()
        took = time.monotonic() - start
        with pytest.raises(SchedulerLost):
            with losing_scheduler(client, address):
                cluster_window(client)
        close_dask(client, None, lost=True)
    assert took < 2 * SCHEDULER_CALL_TIMEOUT + 2, f"{took:.1f} s"


def test_a_claim_made_as_a_signal_came_is_released_too(tmp_path):
    """A signal between a claim file's creation and its record as held (the window of
    Claims.try_claim) must not leave the claim for other hosts to wait out."""
    from coincli.engines.claims import Claims

    claims = Claims(tmp_path / "claims", heartbeat=3600)
    assert claims.try_claim((0, 1)) and claims.try_claim((2, 3))
    with claims._lock:
        del claims.held[(2, 3)]  # as if interrupted before it was recorded
    other = Claims(tmp_path / "claims", heartbeat=3600)
    assert other.try_claim((4, 5))
    claims.close()
    assert sorted(p.name for p in (tmp_path / "claims").iterdir()) == ["tile_4_5"]
    other.close()
    assert not (tmp_path / "claims").exists()


@pytest.mark.parametrize("when", ["writing", "before", "after"])
def test_a_claim_interrupted_as_it_is_made_leaves_no_file(tmp_path, monkeypatch, when):
    """A signal (the `coin` command raises KeyboardInterrupt for each) while a claim's draft is
    written, just before or just after the claim is linked into place: no claim is ever empty
    (one created, then left unwritten by a SIGHUP, was nobody's to remove), and the process's
    close removes what is its own, an empty draft too (our token names it)."""
    import os

    from coincli.engines import claims as module

    link = os.link

    def interrupted(source, target):
        if when == "after":
            link(source, target)
        raise KeyboardInterrupt

    def draft_cut_off(self, data):  # the draft created, its content never written
        self.touch()
        raise KeyboardInterrupt

    folder = tmp_path / "claims"
    claims = module.Claims(folder, heartbeat=3600)
    monkeypatch.setattr(module.os, "link", interrupted)
    if when == "writing":
        monkeypatch.setattr(module.Path, "write_bytes", draft_cut_off)
    with pytest.raises(KeyboardInterrupt):
        claims.try_claim((0, 1))
    monkeypatch.undo()
    left = [p for p in folder.iterdir() if not p.name.startswith(".")]  # claims, not drafts
    assert [p.name for p in left] == (["tile_0_1"] if when == "after" else [])
    assert all(module.read_claim(p)[0]["token"] == claims.token for p in left)
    claims.close()
    assert not folder.exists()


def test_claims_without_hard_links_are_made_in_place(tmp_path, monkeypatch):
    """A file system without hard links (exFAT, some shares): the claim is created exclusively,
    then written; still one owner a tile."""
    import errno

    from coincli.engines import claims as module

    def refused(source, target):
        raise OSError(errno.EPERM, "Operation not permitted")

    monkeypatch.setattr(module.os, "link", refused)
    folder = tmp_path / "claims"
    first, second = module.Claims(folder, heartbeat=3600), module.Claims(folder, heartbeat=3600)
    assert first.try_claim((0, 1)) and not second.try_claim((0, 1))
    assert module.read_claim(folder / "tile_0_1")[0]["token"] == first.token
    assert [p.name for p in folder.iterdir()] == ["tile_0_1"]  # no draft left
    first.close()
    assert second.try_claim((0, 1))
    second.close()
    assert not folder.exists()


def _die(code: int, control=None) -> None:
    import os

    os._exit(code)  # a worker killed by its task (out of memory, a crash)


def test_workers_that_keep_dying_are_one_error_not_a_traceback():
    # distributed's defaults into dask's config before the set below: were they loaded inside
    # it, its exit would remove the whole "distributed" section it found missing, and every
    # later Dask run in this process would fail on a missing key
    import dask
    import distributed  # noqa: F401

    from coincli.engines.executors import Dask, ItemQueue, WorkersLost

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        tasks = Dask(workers=1).run(_die, ItemQueue([3]), name=lambda item: "test-die")
        with pytest.raises(WorkersLost, match="the Dask workers kept dying on a task"):
            list(tasks)
