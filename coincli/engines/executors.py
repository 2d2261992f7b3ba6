"""Where work runs: on this machine's threads (:class:`Threads`) or as Dask distributed tasks
(:class:`Dask`), behind one interface that the basin sweep and the Monte Carlo runs both use:
``executor.run(task, queue, stop)`` yields ``task(item, control)`` for each item the queue hands
out, as each finishes.

A queue (:class:`coincli.engines.claims.ClaimQueue`: a sweep's tiles, or the batches of `coin
fractions`) has ``take()`` (an item, or None for now), ``settle(item)`` (its result is in),
``drop(item)`` (it will not be finished here), ``finished`` and ``pause()`` (wait for work
other processes hold).
Items are taken only when a thread or a worker is free for them, so that a queue may decide what
comes next from the results so far, and claims are held only for work in flight.

Stopping is in two steps, as Ctrl-C does it: ``stop`` set finishes the items in flight and hands
out no more; an exception in the runner (a second Ctrl-C, a KeyboardInterrupt thrown in with
:func:`hard_stop`, an error) stops the threads' items at once through their control flags
(:func:`coincli.integrators.batch.new_control`), and an item so stopped is never written. Dask is
imported only when it is used; its tasks must be picklable (``functools.partial`` of a function
of the package, which every worker imports: install coincli on each machine of the cluster).
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import signal
import time
import uuid
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

import numpy as np

from ..integrators.batch import new_control
from ..params import ParameterError

POLL = 0.2  # s between looks at the stop flag while work runs


def usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def check_where(threads, workers, scheduler, worker_timeout=None) -> None:
    """Refuse a contradictory or impossible choice of where to run (threads, a local Dask
    cluster of workers, or an existing scheduler; how long a Dask run waits without a
    worker)."""
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
    if worker_timeout is not None:
        if workers is None and scheduler is None:
            raise ParameterError("worker_timeout is for a Dask run (workers or scheduler)",
                                 parameters=("worker_timeout",))
        if (isinstance(worker_timeout, bool) or not isinstance(worker_timeout, int | float)
                or not 0 < worker_timeout < math.inf):
            raise ParameterError(f"worker_timeout must be a number of seconds > 0, got "
                                 f"{worker_timeout!r}", parameters=("worker_timeout",))


def executor_for(threads: int | None = None, workers: int | None = None,
                 scheduler: str | None = None,
                 worker_timeout: float | None = None) -> Threads | Dask:
    """The executor of a run's options (checked): Dask for ``workers`` or ``scheduler``
    (``worker_timeout``: see :class:`Dask`), else ``threads`` threads (default one per
    core)."""
    check_where(threads, workers, scheduler, worker_timeout)
    if workers is not None or scheduler is not None:
        return Dask(scheduler=scheduler, workers=workers, worker_timeout=worker_timeout)
    return Threads(threads)


def hard_stop(runner: Iterator) -> None:
    """Stop a runner at once (its items in flight unwritten), as a second Ctrl-C does."""
    try:
        runner.throw(KeyboardInterrupt())
    except (KeyboardInterrupt, StopIteration, ValueError):
        pass  # ValueError: the generator is running (cannot happen from its consumer)


class ItemQueue:
    """The queue of a plain iterable of items (any objects) for one process, without claims:
    an item is taken from the iterator only when a thread or a worker is free for it, so the
    iterator may decide what comes next from the results so far."""

    def __init__(self, items):
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


class Threads:
    """Items on ``threads`` threads of this process (default: one per core); the kernels
    release the GIL."""

    mode = "threads"
    dask = False

    def __init__(self, threads: int | None = None):
        check_where(threads, None, None)
        self.threads = threads or usable_cores()

    @property
    def workers(self) -> int:
        return self.threads

    def describe(self) -> str:
        return f"{self.threads} thread{'s' if self.threads != 1 else ''}"

    def run(self, task: Callable, queue, stop=None,
            name: Callable[[object], str] = str) -> Iterator:
        """Yield ``task(item, control)`` for each item of ``queue`` as it finishes, ``threads``
        at a time; an item is taken from the queue (claimed) only when a thread is free for it.
        ``stop`` set: the items in flight finish, no more start. An exception in here
        (KeyboardInterrupt) sets the control flag of every item in flight, which stops within
        microseconds, unwritten."""
        threads = self.threads
        pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="coin-work")
        running: dict = {}  # future -> (item, control)
        hard = False
        try:
            while True:
                stopping = stop is not None and stop.is_set()
                if not stopping:
                    while len(running) < threads:
                        item = queue.take()
                        if item is None:
                            break
                        control = new_control()
                        running[pool.submit(task, item, control)] = (item, control)
                if not running:
                    if stopping or queue.finished:
                        return
                    queue.pause()  # what is left is other processes': wait for it
                    continue
                finished, _ = wait(list(running), timeout=POLL, return_when=FIRST_COMPLETED)
                results = []
                for future in finished:
                    item, _ = running.pop(future)
                    try:
                        results.append(future.result())
                    finally:
                        queue.settle(item)
                yield from results
        except BaseException as exc:
            hard = not isinstance(exc, GeneratorExit)
            raise
        finally:
            _shut_down(pool, running, queue, hard)


def _shut_down(pool: ThreadPoolExecutor, running: dict, queue, hard: bool) -> None:
    def stop_all():
        for _, control in running.values():
            control[0] = 1

    if hard:
        stop_all()
    try:
        pool.shutdown(wait=True, cancel_futures=True)
    except KeyboardInterrupt:  # Ctrl-C while waiting for the items in flight
        stop_all()
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    finally:
        for item, _ in running.values():
            queue.drop(item)


# -- Dask -----------------------------------------------------------------------------------------
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


class NoWorkers(SchedulerLost):
    """The Dask cluster has had no worker for the run's ``worker_timeout``: its workers were
    lost (killed, out of memory, their machines gone) and none joined. What was finished is in
    the store, as after a lost scheduler."""

    def __init__(self, address: str | None, seconds: float):
        self.address = address
        self.reason = f"no worker for {seconds:g} s"
        where = f"at {address}" if address else "of the local cluster"
        RuntimeError.__init__(self, f"the Dask cluster {where} has had no worker for "
                                    f"{seconds:g} s")


# A call to the scheduler that meets it gone retries connecting for the client's whole
# timeout (20 s), while the client's own stream notices the loss at once: calls are cut short
# here, and the loss is then reported from the client's status.
SCHEDULER_CALL_TIMEOUT = 2.0  # s
# A cluster without a worker this long is said to be waited for (a local cluster's nanny
# restarts a worker that died within a second or two)
NO_WORKER_NOTICE = 5.0  # s
log = logging.getLogger("coincli.dask")


class Dask:
    """Items as Dask distributed tasks: on the cluster at ``scheduler`` (tcp://host:port), or on
    a LocalCluster of ``workers`` processes with one thread each. This process (the client)
    takes each item from the queue (claiming it) before submitting it; a task's result comes
    back to it (a tile's task writes the tile itself and returns only its cost).

    A cluster left without a worker (the last one lost) is waited for: after
    :data:`NO_WORKER_NOTICE` seconds, a warning on the logger ``coincli.dask`` says so (and
    another when a worker joins); with ``worker_timeout`` (seconds), the run stops after that
    long without a worker (:class:`NoWorkers`), else it waits until one joins."""

    mode = "dask"
    dask = True

    def __init__(self, scheduler: str | None = None, workers: int | None = None,
                 worker_timeout: float | None = None):
        check_where(None, workers, scheduler, worker_timeout)
        self.scheduler = scheduler
        self.local_workers = workers
        self.worker_timeout = worker_timeout
        self.seen: list[int] = []  # the cluster's workers, each time it was looked at
        self._alone_since: float | None = None  # when the cluster was last seen with workers
        self._said = False  # whether the wait for a worker was said

    @property
    def workers(self) -> int:
        return max(self.seen, default=self.local_workers or 0)

    def describe(self) -> str:
        return f"Dask ({self.scheduler or f'{self.workers} local workers'})"

    def run(self, task: Callable, queue, stop=None,
            name: Callable[[object], str] = str) -> Iterator:
        """Yield ``task(item)`` for each item of ``queue`` as its task finishes. Tasks are
        submitted in a window of twice the cluster's threads (re-read as workers come and go),
        so that stopping is clean: ``stop`` set cancels the tasks no worker has taken and waits
        for those being computed. (A task cut off anyway, say by a worker dying or a second
        Ctrl-C, is not written, and done again on resume.) ``name(item)`` names each task. A
        lost scheduler raises :class:`SchedulerLost` within a second."""
        from distributed import wait as dask_wait

        client, cluster = open_dask(self.scheduler, self.local_workers)
        run_id = uuid.uuid4().hex[:12]
        running: dict = {}  # future -> item
        hard = lost = False
        cancelled_queued = False
        limit = 2  # tasks kept submitted: the window, re-read as workers come and go

        def cancel_queued() -> None:
            busy = scheduler_processing(client)
            queued = [f for f in running if f.key not in busy and not f.done()]
            client.cancel(queued)
            for future in queued:
                queue.drop(running.pop(future))

        try:
            while True:
                with losing_scheduler(client, self.scheduler):
                    stopping = stop is not None and stop.is_set()
                    if stopping and not cancelled_queued:
                        cancel_queued()
                        cancelled_queued = True
                    if not stopping:
                        limit = self._window(client, limit)
                        while len(running) < limit:
                            item = queue.take()
                            if item is None:
                                break
                            future = client.submit(task, item, pure=False,
                                                   key=f"coin-{name(item)}-{run_id}")
                            running[future] = item
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
                for item in running.values():
                    queue.drop(item)
                close_dask(client, cluster, lost)

    def _window(self, client, previous: int) -> int:
        return cluster_window(client, self._count_workers, previous)

    def _count_workers(self, n: int) -> None:
        """Note the cluster's workers now: say a wait for one, or stop it (NoWorkers)."""
        self.seen.append(n)
        now = time.monotonic()
        if n:
            if self._said:
                log.warning("a Dask worker joined the cluster %s: the run goes on", self._where)
            self._alone_since, self._said = None, False
            return
        if self._alone_since is None:
            self._alone_since = now
        waited = now - self._alone_since
        if self.worker_timeout is not None and waited >= self.worker_timeout:
            raise NoWorkers(self.scheduler, self.worker_timeout)
        if waited >= NO_WORKER_NOTICE and not self._said:
            self._said = True
            limit = (f"stops if none has joined after {self.worker_timeout:g} s"
                     if self.worker_timeout is not None else "waits without a time-out")
            log.warning("waiting for a Dask worker: the cluster %s has had none for %.0f s; "
                        "the run goes on when one joins, and %s", self._where, waited, limit)

    @property
    def _where(self) -> str:
        return f"at {self.scheduler}" if self.scheduler else "on this machine"


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
    try:
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread
        previous = None
    try:
        # no dashboard; and the scheduler's HTTP server (health, metrics), which it starts
        # anyway, on a free port of this host rather than on 8787, which another cluster (a
        # second coin run, a notebook's) may hold: distributed warns on the terminal there
        cluster = LocalCluster(n_workers=workers or usable_cores(), threads_per_worker=1,
                               processes=True, dashboard_address=None,
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    return Client(cluster), cluster


__all__ = ["Dask", "ItemQueue", "NoWorkers", "POLL", "SchedulerLost", "Threads", "WorkersLost",
           "check_where", "cluster_window", "executor_for", "hard_stop", "usable_cores"]
