"""Run a planned Monte Carlo run (:mod:`coincli.montecarlo`): batches on threads or Dask, counted
in order by the stop rule, written in order to the store, resumed from it."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable

import numpy as np

from ..enums import StopReason
from ..integrators.batch import verified_labels, warm_up
from ..montecarlo import (
    BatchResult,
    BatchTask,
    Draws,
    FractionsOver,
    Progression,
    Tally,
    compute_batch,
    initial_states,
    make_fraction_spec,
    make_result,
    samples_needed,
    widest,
    wilson_arrays,
)
from ..montecarlo.plan import FractionsPlan, FractionsProgress
from ..params import ParameterError, state_array


def run_fractions(plan: FractionsPlan, *, store: str | os.PathLike | None = None,
                  overwrite: bool = False, threads: int | None = None,
                  workers: int | None = None, scheduler: str | None = None,
                  progress: Callable[[FractionsProgress], None] | None = None, stop=None):
    """Run a planned Monte Carlo run (see :func:`coincli.fractions`); a Fractions for a plain run, a
    FractionsOver for a continuation."""
    from . import fractions_store as fstore
    from .runner import ItemQueue, check_where, run_threads, usable_cores

    check_where(threads, workers, scheduler)
    started = time.time()
    sampling, goal = plan.sampling, plan.goal
    size = sampling.batch
    specs = [make_fraction_spec(s) for s in plan.scenes]
    verified = specs[0].ladder.verified
    progs = [Progression(goal, size, verified) for _ in plan.scenes]
    draws = Draws(sampling)
    n_values = len(plan.scenes)
    layout = fstore.Layout(size, goal.batches(size),
                           None if plan.parameter is None else n_values, plan.parameter)
    writer = None
    if store is not None:
        filled = fstore.prepare(store, plan.attrs, layout, None if plan.values is None
                                else np.asarray(plan.values), overwrite=overwrite)
        _resume(plan, progs, draws, layout, store, filled)
        writer = fstore.Writer(store, layout)
    from_store = sum(p.samples for p in progs)  # counted already, as the store holds them

    def tasks():
        while True:
            best = None
            for v, prog in enumerate(progs):
                index = prog.peek()
                if index is not None and (best is None or index < best[1]):
                    best = (v, index)
            if best is None:
                return
            v, index = best
            progs[v].next_batch()
            count = goal.count(index, size)
            states = initial_states(plan.scenes[v], sampling, draws.batch(index)[:count])
            yield BatchTask(v, index, count, states)

    if scheduler is not None or workers is not None:
        from .dask_tasks import run_dask_tasks

        mode, n_workers = "dask", workers or 0
        runner = run_dask_tasks(compute_batch, ((specs[t.value], t) for t in tasks()),
                                key=lambda item: f"coin-fractions-{item[1].value}-"
                                                 f"{item[1].batch}",
                                scheduler=scheduler, workers=workers)
    else:
        mode, n_workers = "threads", threads or usable_cores()
        if any(p.peek() is not None for p in progs):
            for spec, s in zip(specs, plan.scenes, strict=True):
                warm_up(spec.params, spec.settings, np.asarray(state_array(s)),
                        (verified_labels,))
        runner = run_threads(lambda t, control: compute_batch(specs[t.value], t, control),
                             ItemQueue(tasks()), n_workers)
    pending: list[dict[int, BatchResult]] = [{} for _ in plan.scenes]
    written = [p.prefix for p in progs]  # batches below are in the store (or need no store)
    cpu = [0.0] * n_values
    computed = 0
    wall0 = time.perf_counter()
    interrupted = False

    def flush(v: int, upto: int) -> None:
        while written[v] < upto:
            result = pending[v].pop(written[v], None)
            if result is None:
                return
            if writer is not None:
                writer.write(v, result.batch, result.states, result.labels)
            written[v] += 1

    try:
        for result in runner:
            v = result.value
            computed += result.count
            cpu[v] += result.cpu_seconds
            lab = result.labels
            progs[v].add(result.batch, Tally.of(lab["quarter_turns"], lab["status"],
                                                lab["certainty"], verified))
            pending[v][result.batch] = result
            flush(v, progs[v].prefix)
            if progs[v].done:
                pending[v].clear()
            if progress is not None:
                t = progs[v].tally
                lo, hi = wilson_arrays([t.standing], [t.n_counted])
                p = t.standing / t.n_counted if t.n_counted else math.nan
                expected = goal.samples or (
                    progs[v].samples if progs[v].done else min(
                        max(samples_needed(t, goal.precision, goal.of), progs[v].samples + size),
                        goal.batches(size) * size))
                progress(FractionsProgress(v, n_values, sum(p.done for p in progs), t.samples,
                                           (p, float(lo[0]), float(hi[0])),
                                           widest(t, goal.of), goal.precision, int(expected),
                                           computed, time.perf_counter() - wall0))
            if stop is not None and stop.is_set():
                interrupted = True
                break
        runner.close()
    except KeyboardInterrupt:
        interrupted = True
        runner.close()
    if interrupted and goal.samples is not None:  # every batch is in the final prefix
        for v in range(n_values):
            for result in sorted(pending[v].values(), key=lambda r: r.batch):
                if writer is not None:
                    writer.write(v, result.batch, result.states, result.labels)
    wall = time.perf_counter() - wall0
    if store is not None and computed:
        fstore.record_run(store, fstore.run_record(started, wall, sum(cpu), computed, mode,
                                                   n_workers, interrupted))
    total_cost = {"computed": computed, "cpu_seconds": sum(cpu), "wall_seconds": wall,
                  "trajectories_per_second": computed / wall if wall > 0 else math.nan,
                  "cpu_ms_per_trajectory": 1e3 * sum(cpu) / computed if computed else math.nan,
                  "mode": mode, "workers": n_workers, "from_store": from_store}
    path = None if store is None else str(store)
    results = []
    for v, (prog, s) in enumerate(zip(progs, plan.scenes, strict=True)):
        stopped = prog.reason if prog.done else StopReason.INTERRUPTED
        cost = total_cost if plan.parameter is None else {"cpu_seconds": cpu[v]}
        results.append(make_result(prog, sampling, s, stopped, cost, path, plan.parameter,
                                   None if plan.values is None else plan.values[v]))
    if plan.parameter is None:
        return results[0]
    return FractionsOver(plan.parameter, list(plan.values), results, plan.note, total_cost,
                         path)


def _resume(plan: FractionsPlan, progs, draws, layout, store, filled) -> None:
    """Count the batches a store holds already (each value's, in its progression), after
    checking that this installation draws the same samples as the one that wrote them."""
    from . import fractions_store as fstore

    goal, size = plan.goal, plan.sampling.batch
    checked = False
    for v, prog in enumerate(progs):
        have = np.asarray(filled[v] if plan.parameter is not None else filled)
        batches, counts = [], []
        for index in range(min(prog.limit, have.shape[0])):
            need = goal.count(index, size)
            if need and have[index] >= need:
                batches.append(index)
                counts.append(need)
        if not batches:
            continue
        if not checked:
            index, count = batches[0], counts[0]
            drawn = initial_states(plan.scenes[v], plan.sampling, draws.batch(index)[:count])
            stored = fstore.read_initial(store, layout, v, index, count)
            if not np.array_equal(drawn[:, 1:], stored):
                raise ParameterError(f"{store}: the samples drawn here differ from the ones "
                                     "in the store (numpy or scipy changed?); --overwrite "
                                     "starts it again")
            checked = True
        labels = fstore.read_batches(store, layout, v, batches, counts)
        for index in batches:
            lab = labels[index]
            prog.add(index, Tally.of(lab["quarter_turns"], lab["status"], lab["certainty"],
                                     prog.verified))
