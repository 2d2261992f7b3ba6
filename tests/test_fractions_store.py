"""A `coin fractions` store loses nothing and is never reported complete when it is not:
faults injected into its batches (a gap, batches beyond the stop), several writers started at
once, and runs that cannot reach what was asked (a pilot's estimate first, exit 1 at the
budget). Each ends bit-identical to an uninterrupted run, or in one line that says why."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import local_cluster, store_files
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.montecarlo.tally import Tally, samples_needed
from coincli.stores.fractions_store import FractionsStore

PAPER = coincli.load_preset("paper")
ROOT = Path(__file__).parent.parent
RUN = dict(phi0="-pi:pi", batch=256)


def _files(path: Path) -> dict[str, bytes]:
    """The store's files but its records (runs.jsonl differs from run to run)."""
    return store_files(path)


def _remove_batch(store: Path, batch: int) -> None:
    """A batch that never made it to disk (its files gone, ``filled`` first)."""
    assert FractionsStore.open(store).trim(0, batch, lambda v, b: b != batch) == 1


def run_together(args: list[str], processes: int) -> list[dict]:
    """`coin ARGS --json` in several processes started at once: each one's JSON, once every
    one has exited 0."""
    command = [sys.executable, "-m", "coincli", *args, "--json"]
    procs = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
             for _ in range(processes)]
    outs = [p.communicate(timeout=240) for p in procs]
    for proc, (_, err) in zip(procs, outs, strict=True):
        assert proc.returncode == 0, err.decode()[-2000:]
    return [json.loads(out) for out, _ in outs]


def _computed(store: Path) -> list[int]:
    return [run["samples"] for run in FractionsStore(store).runs()]


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """An uninterrupted run of 24 batches, and its store."""
    store = tmp_path_factory.mktemp("whole") / "f.zarr"
    result = coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    return result, store


def test_a_gap_in_the_batches_is_filled_and_nothing_after_it_is_lost(tmp_path, whole):
    """Batches 0-13 and 15-23 written, 14 not (an interrupted run on several threads): the
    resume computes batch 14 alone and keeps every batch after it."""
    reference, clean = whole
    store = tmp_path / "gap.zarr"
    coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    _remove_batch(store, 14)
    assert int((FractionsStore(store).read_filled() > 0).sum()) == 23
    resumed = coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    assert resumed.cost["computed"] == 256 and resumed.cost["from_store"] == 23 * 256
    assert resumed.outcomes == reference.outcomes and resumed.standing == reference.standing
    assert _files(store) == _files(clean)
    again = coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    assert again.cost["computed"] == 0  # the store is whole: nothing recomputed


def test_a_dead_writers_temporary_files_go_with_the_resume(tmp_path, whole):
    """A writer killed midway leaves a chunk's temporary file (NAME.HOST-PID-THREAD.partial)
    in a batch it never finished: the resume that computes that batch removes it, and the
    store is the uninterrupted run's, file for file (a `kill -9` left `rung/c/4....partial`
    for good)."""
    reference, clean = whole
    store = tmp_path / "f.zarr"
    coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    _remove_batch(store, 4)
    orphans = [store / "rung" / "c" / "4.somehost-123-456.partial",
               store / "initial" / "c" / "4" / "0.somehost-123-456.partial"]
    for orphan in orphans:
        orphan.write_bytes(b"half a chunk")
    resumed = coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    assert resumed.cost["computed"] == 256 and resumed.standing == reference.standing
    assert not any(orphan.exists() for orphan in orphans)
    assert _files(store) == _files(clean)


def test_batches_beyond_the_stop_are_kept_until_the_goal_is_met_then_removed(tmp_path):
    """A precision run that finds more batches than its stop rule needs (an interrupted run's
    batches in flight, another writer's) counts up to its stop and leaves the store as an
    uninterrupted run does."""
    kw = dict(precision=0.03, of="standing", max_samples=16384, **RUN)
    clean = tmp_path / "clean.zarr"
    reference = coincli.fractions(PAPER, store=clean, **kw)
    assert reference.stopped == "precision"
    used = reference.samples // 256
    assert used < 64
    store = tmp_path / "more.zarr"
    coincli.fractions(PAPER, samples=256 * (used + 6), max_samples=16384, store=store,
                      phi0="-pi:pi", batch=256)
    assert int((FractionsStore(store).read_filled() > 0).sum()) == used + 6
    _remove_batch(store, used // 2)  # and a gap below the stop
    # and a dead writer's temporary file in a batch past the stop: removed with the batch
    (store / "rung" / "c" / f"{used + 3}.somehost-123-456.partial").write_bytes(b"half")
    resumed = coincli.fractions(PAPER, store=store, threads=1, **kw)
    assert resumed.cost["computed"] == 256  # the gap; on one thread, nothing past the stop
    assert resumed.standing == reference.standing and resumed.samples == reference.samples
    assert _files(store) == _files(clean)


def test_an_interrupted_precision_run_keeps_every_batch_it_computed(tmp_path):
    import threading

    stop = threading.Event()

    def halt(update):
        if update.computed >= 1024:
            stop.set()

    store = tmp_path / "f.zarr"
    part = coincli.fractions(PAPER, precision=0.004, of="standing", store=store, threads=2,
                             progress=halt, stop=stop, **RUN)
    assert part.stopped == "interrupted"
    written = int((FractionsStore(store).read_filled() > 0).sum())
    assert written * 256 == part.cost["computed"]  # the batches in flight were written too
    resumed = coincli.fractions(PAPER, precision=0.004, of="standing", store=store, **RUN)
    clean = coincli.fractions(PAPER, precision=0.004, of="standing",
                              store=tmp_path / "clean.zarr", **RUN)
    assert resumed.standing == clean.standing
    assert _files(store) == _files(tmp_path / "clean.zarr")


def test_a_watched_batch_written_as_it_is_claimed_is_not_computed_again():
    """Another process writes a batch this one watches and lets its claim go between this one's
    look and its claim: the claim succeeds, and the batch is found written, counted, not
    computed again (three writers on one store once computed 6,400 samples of 6,144)."""
    from types import SimpleNamespace

    from coincli.engines.claims import ClaimQueue
    from coincli.engines.fractions import BatchSource
    from coincli.montecarlo.tally import Goal, Progression, Tally

    written: set[tuple[int, int]] = set()

    class Claims:  # batch 0: held by the other process at the first try, let go at the next
        def __init__(self):
            self.held, self.tries = set(), 0

        def try_claim(self, key):
            if key == (0, 0):
                self.tries += 1
                if self.tries == 1:
                    return False
                written.add(key)  # the other process wrote it and let it go, just now
            self.held.add(key)
            return True

        def release(self, key):
            self.held.discard(key)

    def found(v, index):
        progs[v].add(index, Tally())
        return True

    goal = Goal(samples=512)
    progs = [Progression(goal, 256)]
    source = BatchSource(progs, lambda v, index: SimpleNamespace(value=v, batch=index),
                         lambda v, index: (v, index) in written, found)
    queue = ClaimQueue(source, Claims(), poll=0)
    task = queue.take()  # batch 0 is held by the other: watched; batch 1 is ours
    assert (task.value, task.batch) == (0, 1) and queue.watched == {(0, 0)}
    assert queue.take() is None  # claimed as it was written: found, not handed out
    assert 0 in progs[0].tallies and not queue.watched and (0, 0) not in queue.claims.held


def test_several_writers_started_at_once_share_the_batches(tmp_path, whole):
    """Three `coin fractions --store` started together: one creates the store, the batches are
    shared by claims (no sample computed twice), every process reports the same numbers, and
    the store is the one a single run makes."""
    reference, clean = whole
    store = tmp_path / "shared.zarr"
    args = ["fractions", "--samples", "6144", "--batch", "256", "--phi0", "-pi:pi",
            "--threads", "1", "--store", str(store), "-q"]
    for data in run_together(args, 3):
        assert data["standing"] == reference.standing
        assert data["samples"] == 6144
    assert sum(_computed(store)) == 6144  # each batch once
    assert not list(store.parent.glob(f".{store.name}.creating-*"))
    assert not FractionsStore(store).claims_dir.exists()
    assert _files(store) == _files(clean)


def test_a_precision_the_budget_cannot_reach_is_refused_before_any_work(tmp_path):
    store = tmp_path / "f.zarr"
    result = CliRunner().invoke(app, ["fractions", "--precision", "0.001%", "--of", "standing",
                                      "--store", str(store)])
    assert result.exit_code == 2, result.output
    err = " ".join(result.stderr.split())
    assert err.startswith("error: --precision needs about") and "--max-samples" in err
    assert "--yes" in err and not store.exists()


def test_a_run_that_spends_its_budget_before_the_precision_exits_1(tmp_path):
    result = CliRunner().invoke(app, ["fractions", "--precision", "0.002", "--of", "standing",
                                      "--max-samples", "1024", "--batch", "256", "--yes",
                                      "--store", str(tmp_path / "f.zarr")])
    assert result.exit_code == 1, result.output
    assert "stopped short:" in result.stderr and "budget" in result.stdout


def test_the_estimate_of_a_run_counts_what_the_store_holds(tmp_path, whole):
    _, clean = whole
    plan = coincli.plan_fractions(PAPER, samples=6144, **RUN)
    fresh = coincli.estimate_fractions(plan, threads=1)
    assert fresh.samples == 6144 and fresh.budget_suffices and fresh.cpu_per_sample > 0
    assert fresh.seconds == pytest.approx(6144 * fresh.cpu_per_sample)
    held = coincli.estimate_fractions(plan, threads=1, store=clean)
    assert held.samples == 0


def test_samples_needed_does_not_take_an_unseen_outcome_as_impossible():
    none_standing = Tally.of(np.zeros(1000, dtype=np.int16), np.zeros(1000, dtype=np.uint8),
                             np.ones(1000, dtype=np.uint8))
    assert none_standing.standing == 0
    # an outcome never seen in 1,000 counts as 1 in 2,000: p(1 - p) about 5e-4, not 0
    need = samples_needed(none_standing, 0.001, "standing")
    assert 1500 < need < 2500


def test_a_read_only_store_is_named_in_one_line(tmp_path, monkeypatch):
    import errno

    from test_store import Disk

    folder = tmp_path / "ro"
    folder.mkdir()
    args = ["fractions", "--samples", "512", "--batch", "256"]
    assert CliRunner().invoke(app, [*args, "--store", str(folder / "f.zarr")]).exit_code == 0
    Disk(monkeypatch, folder, errno.EROFS)
    for store in (folder / "f.zarr", folder / "new.zarr"):
        result = CliRunner().invoke(app, [*args, "--samples", "1024", "--store", str(store)])
        assert result.exit_code == 2, result.output
        err = result.stderr.strip()
        assert err.startswith("error:") and len(err.splitlines()) == 1, err
        assert str(store) in err and "read-only" in err and "creating" not in err, err


def test_a_precision_run_on_dask_makes_the_store_threads_make(tmp_path):
    kw = dict(precision=0.004, of="standing", **RUN)
    local = coincli.fractions(PAPER, store=tmp_path / "threads.zarr", **kw)
    with local_cluster(2) as cluster:
        remote = coincli.fractions(PAPER, store=tmp_path / "dask.zarr",
                                   scheduler=cluster.scheduler_address, **kw)
    assert remote.standing == local.standing and remote.samples == local.samples
    assert remote.cost["mode"] == "dask"
    assert _files(tmp_path / "dask.zarr") == _files(tmp_path / "threads.zarr")


@pytest.mark.parametrize("args", [["fractions", "--seed", "١"], ["fractions", "--batch", "٨"],
                                  ["fractions", "--threads", "٢"], ["basin", "x.zarr",
                                                                     "--threads", "٢"],
                                  ["basin", "analyze", "x.zarr", "--seed", "١"]])
def test_whole_number_options_take_ascii_digits_only(args):
    result = CliRunner().invoke(app, args)  # click's usage box here; `coin` makes it one line
    assert result.exit_code == 2, result.output
    assert "ASCII digits" in " ".join(result.stderr.replace("│", " ").split()), result.stderr


@pytest.mark.parametrize("array", ["status", "initial", "filled", "settle_time"])
def test_a_damaged_chunk_is_found_and_its_batch_computed_again(tmp_path, whole, array):
    """A bit flipped in any chunk of a stored batch (its labels, its initial states, its count)
    fails the chunk's CRC-32C: the resume computes that batch again, says so, and the store
    ends as the uninterrupted one."""
    reference, clean = whole
    store = tmp_path / "f.zarr"
    coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    chunk = store / array / "c" / "5"
    chunk = chunk / "0" if array == "initial" else chunk
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0x10
    chunk.write_bytes(bytes(data))
    resumed = coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    assert resumed.cost["computed"] == 256 and resumed.cost["damaged_batches"] == (
        0 if array == "filled" else 1)  # a damaged count reads as a batch never written
    assert resumed.standing == reference.standing
    assert _files(store) == _files(clean)


def test_fewer_samples_from_a_store_of_more_is_complete_and_keeps_them(tmp_path):
    """A store of 2,048 samples asked for 1,000 (a partial last batch): the run counts what it
    needs and is complete; asked again, nothing is computed, and the 2,048 stay."""
    store = tmp_path / "f.zarr"
    coincli.fractions(PAPER, samples=2048, batch=512, store=store, phi0="-pi:pi")
    fewer = coincli.fractions(PAPER, samples=1000, batch=512, store=store, phi0="-pi:pi")
    assert fewer.samples == 1000 and fewer.cost["computed"] == 0
    assert fewer.standing == coincli.fractions(PAPER, samples=1000, batch=512,
                                               phi0="-pi:pi").standing
    assert int((FractionsStore(store).read_filled() > 0).sum()) == 4
    # the estimate before such a run needs no pilot: the store holds the whole run
    plan = coincli.plan_fractions(PAPER, samples=1000, batch=512, phi0="-pi:pi")
    held = coincli.estimate_fractions(plan, store=store)
    assert (held.pilot_samples, held.samples, held.seconds) == (0, 0, 0.0)
    assert coincli.estimate_fractions(plan).pilot_samples > 0  # without the store, a pilot


def test_a_looser_precision_keeps_what_a_tighter_one_computed(tmp_path):
    store = tmp_path / "f.zarr"
    tight = coincli.fractions(PAPER, precision=0.004, of="standing", store=store, **RUN)
    loose = coincli.fractions(PAPER, precision=0.03, of="standing", store=store, **RUN)
    assert loose.samples < tight.samples and loose.cost["computed"] == 0
    assert int((FractionsStore(store).read_filled() > 0).sum()) * 256 == tight.samples


@pytest.mark.parametrize("array", ["quarter_turns", "certainty", "filled"])
def test_a_missing_chunk_is_damage_not_a_label(tmp_path, whole, array):
    reference, clean = whole
    store = tmp_path / "f.zarr"
    coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    (store / array / "c" / "0").unlink()
    resumed = coincli.fractions(PAPER, samples=6144, store=store, **RUN)
    assert resumed.cost["computed"] == 256 and resumed.outcomes == reference.outcomes
    assert _files(store) == _files(clean)


def test_damaged_store_metadata_is_one_line(tmp_path):
    store = tmp_path / "f.zarr"
    args = ["fractions", "--samples", "512", "--batch", "256", "--store", str(store)]
    assert CliRunner().invoke(app, args).exit_code == 0
    (store / "zarr.json").write_text("garbage")
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    err = " ".join(result.stderr.split())
    assert "metadata cannot be read" in err and "--overwrite" in err


def test_a_second_interrupt_stops_the_batches_in_flight_at_once(tmp_path):
    """A KeyboardInterrupt (a second Ctrl-C, SIGTERM) while a result is handled stops the
    batches in flight at once, unwritten, instead of waiting for them."""
    import time

    calls = []

    def interrupt(update):
        calls.append(time.perf_counter())
        raise KeyboardInterrupt

    store = tmp_path / "f.zarr"
    t0 = time.perf_counter()
    part = coincli.run_fractions(coincli.plan_fractions(PAPER, samples=8 * 65536, batch=65536,
                                                        phi0="-pi:pi"),
                                 store=store, threads=2, progress=interrupt)
    assert part.stopped == "interrupted" and len(calls) == 1
    # the other thread's batch of 65,536 throws (over a second) was stopped, not waited for
    assert time.perf_counter() - calls[0] < 0.5, time.perf_counter() - t0
    assert part.cost["computed"] == 65536


def test_the_estimate_counts_only_whole_batches_of_the_run(tmp_path):
    """A store of 5 batches, the second one lost: a run of 4 batches is not held whole (the
    estimate pilots it and counts the lost batch to compute), whatever lies beyond the run."""
    store = tmp_path / "f.zarr"
    coincli.fractions(PAPER, samples=2560, batch=512, store=store, phi0="-pi:pi")
    (store / "filled" / "c" / "1").unlink()
    plan = coincli.plan_fractions(PAPER, samples=2048, batch=512, phi0="-pi:pi")
    estimate = coincli.estimate_fractions(plan, store=store)
    assert estimate.held == 1536 and estimate.samples == 512 and estimate.pilot_samples > 0
    run = coincli.fractions(PAPER, samples=2048, batch=512, store=store, phi0="-pi:pi")
    assert run.cost["computed"] == 512
