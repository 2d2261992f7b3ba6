"""Running a sweep's tiles: on local threads or as Dask distributed tasks.

Both ways call the same function, :func:`run_tile_task`, which computes one tile and writes it to
the store itself (the idiomatic pattern of ``dask.array.to_zarr``): no data travels back to the
client, only the tile's index and cost. It lives in the package so that the scheduler and every
worker can import it (install coincli on each machine of the cluster, and give every worker the
same path to the store, e.g. a shared file system). Dask is imported only when it is used.

Tiles come from a :class:`~coincli.io.claims.TileQueue`, which claims each one before it is
handed out, so several processes can work on one store. Stopping is in two steps, as Ctrl-C
does it: ``stop`` set finishes the tiles in flight and hands out no more; an exception in the
runner (a second Ctrl-C, a KeyboardInterrupt thrown in with ``runner.throw``, an error) stops
the tiles in flight at once through their control flags (:func:`coincli.integrators.batch.
new_control`), and an interrupted tile is never written.
"""

from __future__ import annotations

import contextlib
import os
import signal
import time
import uuid
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from typing import NamedTuple

import numpy as np

from ..enums import Status
from ..grid import SweepSpec, compute_tile, with_mirror
from ..integrators.batch import new_control
from ..params import ParameterError
from .claims import TileQueue

POLL = 0.2  # s between looks at the stop flag while tiles run


class SchedulerLost(RuntimeError):
    """The Dask scheduler, or this process's connection to it, went away mid-run: the tasks it
    held are gone. What the workers finished is in the store (each tile, or each batch the
    client had received, is written whole or not at all), so the same run resumes."""

    def __init__(self, address: str | None, reason: str):
        self.address = address
        self.reason = reason
        where = f"at {address}" if address else "of the local cluster"
        super().__init__(f"lost the Dask scheduler {where}: {reason}")


class WorkersLost(SchedulerLost):
    """The Dask workers kept dying on a task (distributed's KilledWorker: out of memory, a
    crash): the run cannot go on there, and what was finished is in the store, as after a lost
    scheduler."""

    def __init__(self, address: str | None, reason: str):
        self.address = address
        self.reason = reason
        RuntimeError.__init__(self, f"the Dask workers kept dying on a task: {reason}")


class TileDone(NamedTuple):
    """What a tile task reports back: no data, only what it cost and whether it was written."""

    tile: tuple[int, int]
    cells: int  # cells written (0 if interrupted), its mirror tile's included
    cpu_seconds: float
    written: bool  # False: stopped through its control flag, nothing written
    compute_seconds: float = 0.0  # wall time in the kernels
    write_seconds: float = 0.0  # wall time writing the tile(s) and cost record(s)
    tiles: int = 1  # tiles written: 2 when the tile's mirror image was written too


def run_tile_task(path: str, spec: SweepSpec, tile: tuple[int, int],
                  control: np.ndarray | None = None, *,
                  parameters: bytes | None = None) -> TileDone:
    """Compute one tile and write it to the store at ``path``, and its mirror tile if the
    sweep has one (:meth:`coincli.grid.Grid.task_tiles`), binding the digest ``parameters``
    of the parameters it was computed with (by default, the store's). ``control[0]`` set
    (from another thread) stops the computation; a tile so stopped is not written at all."""
    from .store import write_tile

    control = new_control() if control is None else control
    result = compute_tile(spec, tuple(tile), control)
    if control[0] or (result.arrays["status"] == Status.INTERRUPTED).any():
        return TileDone(tuple(tile), 0, result.cpu_seconds, False, result.wall_seconds)
    start = time.perf_counter()
    results = with_mirror(result, spec.grid)
    for each in results:
        write_tile(path, spec, each, parameters)
    return TileDone(tuple(tile), sum(r.cells for r in results), result.cpu_seconds, True,
                    result.wall_seconds, time.perf_counter() - start, len(results))


def usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class ItemQueue:
    """A :class:`TileQueue`'s interface over a lazy iterator of work items (any objects), for
    one process without claims: :func:`run_threads` takes an item only when a thread is free,
    so the iterator may decide what comes next from the results so far."""

    def __init__(self, items: Iterable):
        self._items = iter(items)
        self._exhausted = False
        self._out = 0

    def take(self):
        if not self._exhausted:
            item = next(self._items, None)
            if item is not None:
                self._out += 1
                return item
            self._exhausted = True
        return None

    def settle(self, item) -> None:
        self._out -= 1

    drop = settle

    @property
    def finished(self) -> bool:
        return self._exhausted and self._out == 0

    def pause(self) -> None:  # never waits on others: nothing is claimed elsewhere
        time.sleep(0.001)


def run_threads(task: Callable, queue: TileQueue | ItemQueue, threads: int,
                stop=None) -> Iterator:
    """Yield ``task(tile, control)`` for each tile of ``queue`` as it finishes, ``threads``
    tiles at a time (the kernels release the GIL); each tile is taken from the queue (claimed)
    only when a thread is free for it. ``stop`` set: the tiles in flight finish, no more start.
    An exception in here (KeyboardInterrupt) sets the control flag of every tile in flight,
    which stops within microseconds, unwritten."""
    threads = max(1, threads)
    pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="coin-tile")
    running: dict = {}  # future -> (tile, control)
    hard = False
    try:
        while True:
            stopping = stop is not None and stop.is_set()
            if not stopping:
                while len(running) < threads:
                    tile = queue.take()
                    if tile is None:
                        break
                    control = new_control()
                    running[pool.submit(task, tile, control)] = (tile, control)
            if not running:
                if stopping or queue.finished:
                    return
                queue.pause()  # the tiles left are other processes': wait for them
                continue
            finished, _ = wait(list(running), timeout=POLL, return_when=FIRST_COMPLETED)
            results = []
            for future in finished:
                tile, _ = running.pop(future)
                try:
                    results.append(future.result())
                finally:
                    queue.settle(tile)
            yield from results
    except BaseException as exc:
        hard = not isinstance(exc, GeneratorExit)
        raise
    finally:
        _shut_down(pool, running, queue, hard)


def _shut_down(pool: ThreadPoolExecutor, running: dict, queue: TileQueue, hard: bool) -> None:
    def stop_all():
        for _, control in running.values():
            control[0] = 1

    if hard:
        stop_all()
    try:
        pool.shutdown(wait=True, cancel_futures=True)
    except KeyboardInterrupt:  # Ctrl-C while waiting for the tiles in flight
        stop_all()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    finally:
        for tile, _ in running.values():
            queue.drop(tile)


def hard_stop(runner: Iterator) -> None:
    """Stop a runner at once (its tiles in flight unwritten), as a second Ctrl-C does."""
    try:
        runner.throw(KeyboardInterrupt())
    except (KeyboardInterrupt, StopIteration, ValueError):
        pass  # ValueError: the generator is running (cannot happen from its consumer)


def run_dask(path: str, spec: SweepSpec, queue: TileQueue, scheduler: str | None = None,
             workers: int | None = None, stop=None,
             on_workers: Callable[[int], None] | None = None,
             parameters: bytes | None = None) -> Iterator[TileDone]:
    """Yield each tile's :class:`TileDone` as its Dask task finishes: on the cluster at
    ``scheduler`` (tcp://host:port), or on a LocalCluster of ``workers`` processes with one
    thread each. This process (the client) claims each tile before submitting it; each task
    binds the parameters digest ``parameters`` (:func:`run_tile_task`).

    Tasks are submitted in a window of twice the cluster's threads (re-read as workers come and
    go), so that stopping is clean: ``stop`` set cancels the tasks no worker has taken and waits
    for those being computed, which write their tiles completely. (A tile cut off anyway, say
    by a worker dying or a second Ctrl-C, has no ``done`` digest and is recomputed on resume.)
    ``on_workers`` is told the cluster's number of workers each time it is read. A lost
    scheduler raises :class:`SchedulerLost` within a second (:func:`losing_scheduler`)."""
    from distributed import wait as dask_wait

    client, cluster = open_dask(scheduler, workers)
    run_id = uuid.uuid4().hex[:12]
    running: dict = {}  # future -> tile
    hard = lost = False
    cancelled_queued = False
    limit = 2  # tasks kept submitted: cluster_window's, re-read as workers come and go

    def cancel_queued() -> None:
        busy = scheduler_processing(client)
        queued = [f for f in running if f.key not in busy and not f.done()]
        client.cancel(queued)
        for future in queued:
            queue.drop(running.pop(future))

    try:
        while True:
            with losing_scheduler(client, scheduler):
                stopping = stop is not None and stop.is_set()
                if stopping and not cancelled_queued:
                    cancel_queued()
                    cancelled_queued = True
                if not stopping:
                    limit = cluster_window(client, on_workers, limit)
                    while len(running) < limit:
                        tile = queue.take()
                        if tile is None:
                            break
                        future = client.submit(
                            run_tile_task, path, spec, tuple(tile), parameters=parameters,
                            pure=False, key=f"coin-basin-tile-{tile[0]}-{tile[1]}-{run_id}")
                        running[future] = tuple(tile)
                if not running:
                    if stopping or queue.finished:
                        return
                    queue.pause()
                    continue
                try:
                    dask_wait(list(running), timeout=POLL, return_when="FIRST_COMPLETED")
                except TimeoutError:
                    continue
                finished = [(f, f.result()) for f in running if f.done()]
            for future, result in finished:
                queue.settle(running.pop(future))
                yield result
    except BaseException as exc:
        hard = not isinstance(exc, GeneratorExit)
        lost = isinstance(exc, SchedulerLost) or scheduler_gone(client)
        raise
    finally:
        try:
            if running and not lost:  # lost: nothing to cancel or wait for
                cancel_queued()
                if running and not hard:
                    dask_wait(list(running), timeout=600)
        finally:
            for tile in running.values():
                queue.drop(tile)
            close_dask(client, cluster, lost)


# A call to the scheduler that meets it gone retries connecting for the client's whole
# timeout (20 s), while the client's own stream notices the loss at once: calls are cut short
# here, and the loss is then reported from the client's status.
SCHEDULER_CALL_TIMEOUT = 2.0  # s


def cluster_window(client, on_workers: Callable[[int], None] | None = None,
                   previous: int = 2) -> int:
    """How many tasks to keep submitted: twice the cluster's threads (at least 2). Tells
    ``on_workers`` how many workers the scheduler has now. A scheduler too slow to answer
    within :data:`SCHEDULER_CALL_TIMEOUT` keeps the ``previous`` window; a lost one raises
    (:func:`losing_scheduler` turns that into :class:`SchedulerLost`)."""
    try:
        nthreads = client.nthreads(callback_timeout=SCHEDULER_CALL_TIMEOUT)
    except TimeoutError:
        if scheduler_gone(client):
            raise
        return previous
    if on_workers is not None:
        on_workers(len(nthreads))
    return max(2, 2 * sum(nthreads.values()))


def scheduler_processing(client) -> set:
    """The keys of the tasks workers are computing now; empty if the scheduler does not
    answer within :data:`SCHEDULER_CALL_TIMEOUT` (it may be gone already)."""
    try:
        keys = client.processing(callback_timeout=SCHEDULER_CALL_TIMEOUT)
    except Exception:  # noqa: BLE001 - the scheduler may be gone: nothing is processing
        return set()
    return {key for worker_keys in keys.values() for key in worker_keys}


def scheduler_gone(client) -> bool:
    """The client has lost its scheduler: distributed then cancels every future at once and
    tries to reconnect for the client's whole timeout (a new scheduler would not know the
    tasks anyway), so waiting for it only delays the news."""
    return client.status != "running"


@contextlib.contextmanager
def losing_scheduler(client, scheduler: str | None):
    """Turn the ways distributed reports a lost scheduler (the client no longer running,
    futures cancelled with reason scheduler-connection-lost, a CommClosedError from a call to
    the scheduler) into :class:`SchedulerLost`, raised at once; other errors (a task's own)
    go on as they are."""
    from distributed import KilledWorker
    from distributed.comm.core import CommClosedError

    if scheduler_gone(client):
        raise SchedulerLost(scheduler, "the connection to it closed")
    try:
        yield
    except KilledWorker as exc:
        raise WorkersLost(scheduler, str(exc).splitlines()[0][:200]) from exc
    except Exception as exc:
        # CommClosedError: a call to the scheduler (not a task: a task's OSError, say a full
        # disk, is its own) that met the loss before the client's stream did
        if (scheduler_gone(client) or isinstance(exc, CommClosedError)
                or "scheduler-connection-lost" in str(exc)):
            raise SchedulerLost(scheduler, f"the connection to it closed "
                                f"({type(exc).__name__})") from exc
        raise


def close_dask(client, cluster, lost: bool = False) -> None:
    """Close the client and the local cluster, if any; after a lost scheduler at once, without
    the goodbyes to it (they would wait for the connection's timeout)."""
    try:
        if lost:
            # distributed logs its reconnection, cut short here, as an error with tracebacks
            with _muted("distributed.client", "distributed.batched", "distributed.core"):
                client.close(timeout=2)
        else:
            client.close()
    except Exception:  # noqa: BLE001 - a lost scheduler: nothing left to close cleanly
        if not lost:
            raise
    finally:
        if cluster is not None:
            cluster.close()


@contextlib.contextmanager
def _muted(*loggers: str):
    import logging

    levels = {name: logging.getLogger(name).level for name in loggers}
    for name in loggers:
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for name, level in levels.items():
            logging.getLogger(name).setLevel(level)


def open_dask(scheduler: str | None, workers: int | None):
    """(client, cluster): a client of the cluster at ``scheduler`` (tcp://host:port; cluster
    None), or of a new LocalCluster of ``workers`` processes with one thread each. The caller
    closes both."""
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler, timeout="20s"), None
    # the workers must not get the terminal's Ctrl-C: this process decides when to stop
    previous = _ignore_sigint()
    try:
        cluster = LocalCluster(n_workers=workers or usable_cores(), threads_per_worker=1,
                               processes=True, dashboard_address=None)
    finally:
        _restore_sigint(previous)
    return Client(cluster), cluster


def _ignore_sigint():
    try:
        return signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread
        return None


def _restore_sigint(previous) -> None:
    if previous is not None:
        signal.signal(signal.SIGINT, previous)



def check_where(threads, workers, scheduler) -> None:
    """Refuse a contradictory or impossible choice of where to run (threads, a local Dask
    cluster of workers, or an existing scheduler)."""
    if workers is not None and scheduler is not None:
        raise ParameterError("give workers (a local cluster) or scheduler (an existing "
                             "one), not both", parameters=("workers", "scheduler"))
    for option, value in (("threads", threads), ("workers", workers)):
        if value is not None and (isinstance(value, bool) or
                                  not isinstance(value, int | np.integer) or value < 1):
            raise ParameterError(f"{option} must be a whole number >= 1, got {value!r}",
                                 parameters=(option,))
    if threads is not None and (workers is not None or scheduler is not None):
        raise ParameterError("threads is for a local run; a Dask run uses one thread per "
                             "worker", parameters=("threads",))
    if scheduler is not None and "://" not in scheduler:
        raise ParameterError(f"scheduler '{scheduler}' is not an address like "
                             "tcp://HOST:PORT", parameters=("scheduler",))


__all__ = ["ItemQueue", "SchedulerLost", "TileDone", "WorkersLost", "check_where", "close_dask",
           "cluster_window", "hard_stop", "losing_scheduler", "open_dask", "run_dask",
           "run_threads", "run_tile_task", "scheduler_gone", "scheduler_processing",
           "usable_cores"]
