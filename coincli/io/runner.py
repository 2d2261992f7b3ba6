"""Running a sweep's tiles: on local threads or as Dask distributed tasks.

Both ways call the same function, :func:`run_tile_task`, which computes one tile and writes it to
the store itself (the idiomatic pattern of ``dask.array.to_zarr``): no data travels back to the
client, only the tile's index and cost. It lives in the package so that the scheduler and every
worker can import it (install coincli on each machine of the cluster, and give every worker the
same path to the store, e.g. a shared file system). Dask is imported only when it is used.
"""

from __future__ import annotations

import os
import signal
import uuid
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from ..grid import SweepSpec, compute_tile


def run_tile_task(path: str, spec: SweepSpec, tile: tuple[int, int]) -> tuple:
    """Compute one tile and write it to the store at ``path``; return (tile, cells, cpu s)."""
    from .store import write_tile

    result = compute_tile(spec, tuple(tile))
    write_tile(path, spec, result)
    return tuple(tile), result.cells, result.cpu_seconds


def usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def run_threads(task: Callable, tiles: Iterable[tuple[int, int]],
                threads: int) -> Iterator:
    """Yield ``task(tile)`` for each tile as it finishes, ``threads`` tiles at a time (the
    kernels release the GIL). Closing the iterator (or Ctrl-C while it waits) cancels the tiles
    not started and waits for those in flight, which finish completely."""
    pool = ThreadPoolExecutor(max_workers=max(1, threads), thread_name_prefix="coin-tile")
    try:
        # keep a bounded window in flight so an interrupt leaves few tiles to finish
        pending = set()
        queue = iter(tiles)
        for tile in queue:
            pending.add(pool.submit(task, tile))
            if len(pending) >= 2 * threads:
                break
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in finished:
                for tile in queue:
                    pending.add(pool.submit(task, tile))
                    break
                yield future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def run_dask(path: str, spec: SweepSpec, tiles: Iterable[tuple[int, int]],
             scheduler: str | None = None, workers: int | None = None) -> Iterator[tuple]:
    """Yield each tile's (tile, cells, cpu s) as its Dask task finishes: on the cluster at
    ``scheduler`` (tcp://host:port), or on a LocalCluster of ``workers`` processes with one
    thread each.

    Tasks are submitted in a window of twice the cluster's threads (re-read as workers come and
    go), so that stopping is clean: closing the iterator cancels the tasks no worker has taken
    and waits for those being computed, which write their tiles completely. (A tile cut off
    anyway, say by a worker dying, has no ``done`` flag and is recomputed on resume.)"""
    from distributed import Client, LocalCluster, as_completed
    from distributed import wait as dask_wait

    cluster = None
    if scheduler:
        client = Client(scheduler, timeout="20s")
    else:
        # the workers must not get the terminal's Ctrl-C: this process decides when to stop
        previous = _ignore_sigint()
        try:
            cluster = LocalCluster(n_workers=workers or usable_cores(), threads_per_worker=1,
                                   processes=True, dashboard_address=None)
        finally:
            _restore_sigint(previous)
        client = Client(cluster)
    run_id = uuid.uuid4().hex[:12]
    queue = iter(tiles)
    submitted = []
    completed = as_completed()
    hard_stop = False

    def submit(count: int) -> None:
        for _ in range(count):
            tile = next(queue, None)
            if tile is None:
                return
            future = client.submit(run_tile_task, path, spec, tuple(tile), pure=False,
                                   key=f"coin-basin-tile-{tile[0]}-{tile[1]}-{run_id}")
            submitted.append(future)
            completed.add(future)

    def window() -> int:
        return max(2, 2 * sum(client.nthreads().values()))

    try:
        submit(window())
        in_flight = len(submitted)
        for future in completed:
            in_flight -= 1
            yield future.result()
            more = max(0, window() - in_flight)
            before = len(submitted)
            submit(more)
            in_flight += len(submitted) - before
    except KeyboardInterrupt:
        hard_stop = True
        raise
    finally:
        unfinished = [f for f in submitted if not f.done()]
        if unfinished:
            processing = set()
            if not hard_stop:
                try:
                    processing = {k for keys in client.processing().values() for k in keys}
                except Exception:  # noqa: BLE001 - the scheduler may be gone already
                    processing = set()
            running = [f for f in unfinished if f.key in processing]
            client.cancel([f for f in unfinished if f.key not in processing])
            if running and not hard_stop:
                dask_wait(running, timeout=600)
        client.close()
        if cluster is not None:
            cluster.close()


def _ignore_sigint():
    try:
        return signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread
        return None


def _restore_sigint(previous) -> None:
    if previous is not None:
        signal.signal(signal.SIGINT, previous)


__all__ = ["run_dask", "run_threads", "run_tile_task", "usable_cores"]
