"""Any picklable function over a stream of items as Dask distributed tasks, results back to the
client in the order they finish (`coin fractions` on Dask: each batch of samples is a task that
returns its labels; the client keeps the store).

The pattern is :func:`coincli.io.runner.run_dask`'s: tasks are submitted in a window of twice
the cluster's threads (re-read as workers come and go), so that stopping is clean: closing the
iterator cancels the tasks no worker has taken and waits for those being computed. A lost
scheduler raises :class:`~coincli.io.runner.SchedulerLost` within a second, as there.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Iterable, Iterator

from .runner import (
    SchedulerLost,
    close_dask,
    cluster_window,
    losing_scheduler,
    open_dask,
    scheduler_gone,
    scheduler_processing,
)


def run_dask_tasks(fn: Callable, items: Iterable[tuple], key: Callable[[tuple], str],
                   scheduler: str | None = None, workers: int | None = None,
                   on_workers: Callable[[int], None] | None = None) -> Iterator:
    """Yield ``fn(*item)`` for each item as its task finishes: on the cluster at ``scheduler``
    (tcp://host:port), or on a LocalCluster of ``workers`` processes with one thread each.
    ``items`` is consumed lazily, as the window frees; ``key(item)`` names each task.
    ``on_workers`` is told the cluster's number of workers each time it is read."""
    from distributed import as_completed
    from distributed import wait as dask_wait

    client, cluster = open_dask(scheduler, workers)
    run_id = uuid.uuid4().hex[:12]
    queue = iter(items)
    submitted = []
    completed = as_completed()
    hard_stop = lost = False
    limit = 2  # tasks kept submitted: cluster_window's, re-read as workers come and go

    def submit(count: int) -> None:
        for _ in range(count):
            item = next(queue, None)
            if item is None:
                return
            future = client.submit(fn, *item, pure=False, key=f"{key(item)}-{run_id}")
            submitted.append(future)
            completed.add(future)

    def window() -> int:
        nonlocal limit
        limit = cluster_window(client, on_workers, limit)
        return limit

    try:
        with losing_scheduler(client, scheduler):
            submit(window())
        in_flight = len(submitted)
        # a lost scheduler cancels every future at once, so this wakes up at once
        for future in completed:
            in_flight -= 1
            with losing_scheduler(client, scheduler):
                result = future.result()
            yield result
            with losing_scheduler(client, scheduler):
                before = len(submitted)
                submit(max(0, window() - in_flight))
                in_flight += len(submitted) - before
    except KeyboardInterrupt:
        hard_stop = True
        raise
    except SchedulerLost:
        lost = True
        raise
    finally:
        lost = lost or scheduler_gone(client)
        unfinished = [f for f in submitted if not f.done()]
        if unfinished and not lost:  # lost: nothing to cancel or wait for
            processing = set() if hard_stop else scheduler_processing(client)
            running = [f for f in unfinished if f.key in processing]
            client.cancel([f for f in unfinished if f.key not in processing])
            if running and not hard_stop:
                dask_wait(running, timeout=600)
        close_dask(client, cluster, lost)


__all__ = ["run_dask_tasks"]
