"""Run a planned Monte Carlo run (:mod:`coincli.montecarlo`): batches on threads or Dask, counted
in order by the stop rule, written in order to the store, resumed from it."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from functools import partial

import numpy as np

from ..enums import StopReason
from ..montecarlo import (
    BatchTask,
    Draws,
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
from ..montecarlo.estimate import (
    PILOT_SAMPLES,
    FractionsEstimate,
    estimate_fractions,
    pilot_values,
)
from ..montecarlo.over import Continuation
from ..montecarlo.plan import FractionsPlan, FractionsProgress
from ..params import ParameterError, state_array
from .claims import ClaimQueue
from .executors import SchedulerLost, executor_for, hard_stop, usable_cores
from .work import check_max_seconds, checked_estimate


class BatchSource:
    """The batches of a run for the one claim queue (:class:`coincli.engines.claims.ClaimQueue`):
    next, the lowest batch (over every value) that the stop rules may still need and that has
    not been tried; a batch is done elsewhere once another process wrote it whole and it reads
    back (``written``, ``found``: it is then counted here); a watched batch is needed while its
    value's goal is not met."""

    release_on_settle = False  # a batch's claim goes once the engine has written its result

    def __init__(self, progs, make_task: Callable,
                 written: Callable[[int, int], bool] | None = None,
                 found: Callable[[int, int], bool] | None = None):
        self.progs = progs
        self.make_task = make_task
        self.written = written
        self.found = found

    def next(self):
        best = None
        for v, prog in enumerate(self.progs):
            index = prog.peek()
            if index is not None and (best is None or index < best[1]):
                best = (v, index)
        if best is not None:
            self.progs[best[0]].next_batch()  # handed out, or watched: not peeked again
        return best

    def needed(self, key) -> bool:
        return not self.progs[key[0]].done

    def done_elsewhere(self, key) -> bool:
        return self.written is not None and self.written(*key) and self.found(*key)

    def held(self, key) -> None:
        pass

    def task(self, key):
        return self.make_task(*key)

    def key(self, task):
        return (task.value, task.batch)

    def dropped(self, key) -> None:
        self.progs[key[0]].issued.discard(key[1])

    def exhausted(self) -> bool:
        return all(p.peek() is None for p in self.progs)


def compute_value_batch(specs, task: BatchTask, control=None):
    """One batch of a run over several values: with the spec of its value (a picklable task
    for Dask, with the specs bound by ``functools.partial``)."""
    return compute_batch(specs[task.value], task, control)


def run_fractions(plan: FractionsPlan, *, target=None, overwrite: bool = False,
                  threads: int | None = None,
                  workers: int | None = None, scheduler: str | None = None,
                  progress: Callable[[FractionsProgress], None] | None = None, stop=None,
                  worker_timeout: float | None = None, max_seconds: float | None = None,
                  on_start: Callable[[FractionsEstimate | None], None] | None = None,
                  estimate: bool = False):
    """Run a planned Monte Carlo run (see :func:`coincli.fractions`) into ``target`` (a
    :class:`coincli.stores.fractions_store.FractionsStore`, or None: in memory); a Fractions for
    a plain run, a Continuation for a continuation (along one parameter, or over a grid of two:
    every point is a value, counted flat, the first parameter outermost). Several processes may
    run the same plan on one store at once: they share the batches by claims, and each ends
    with the same results and store.

    With ``max_seconds`` (or ``estimate``) the run is first estimated (:func:`estimate_run`)
    and, over ``max_seconds``, refused with :class:`coincli.engines.work.WorkTooLong` before
    anything is created, as a sweep is (:func:`coincli.engines.work.checked_estimate`); a run
    no larger than its pilot is estimated only if ``estimate`` asks (the pilot would cost as
    much as the run). ``on_start`` receives the estimate (a FractionsEstimate, None if there
    was none) before any work."""
    check_max_seconds(max_seconds)
    if target is not None and not overwrite:
        target.check_run(plan)  # a store of other samples: refused before the pilot runs
    executor = executor_for(threads, workers, scheduler, worker_timeout)
    found = None
    if estimate or (max_seconds is not None and not _smaller_than_pilot(plan)):
        found = checked_estimate(
            lambda: estimate_run(plan, executor, None if overwrite else target), max_seconds)
    if on_start is not None:
        on_start(found)
    run = FractionsRun(plan, executor)
    try:
        if target is not None:
            run.open_store(target, overwrite)
        lost = run.compute(progress, stop)
    finally:
        run.close()
    run.record()
    if lost is not None:
        raise lost  # after recording the run: the batches received are written already
    return run.results()


def estimate_run(plan: FractionsPlan, executor, target=None) -> FractionsEstimate:
    """How long ``plan`` should take on ``executor`` (its threads, or its Dask workers; on a
    cluster of unknown size, CPU time) and how many samples its stop rule likely needs, from
    the pilot of :func:`coincli.montecarlo.estimate.estimate_fractions`; the samples that
    ``target`` (a FractionsStore, or None) holds already for this run are not counted."""
    if executor.dask:
        workers = None if executor.scheduler is not None else executor.local_workers
    else:
        workers = min(executor.threads, usable_cores())
    held = None
    if target is not None and target.exists():
        held = target.held_samples(plan)
    return estimate_fractions(plan, workers, held)


def _smaller_than_pilot(plan: FractionsPlan) -> bool:
    """Whether the whole run computes no more samples than its pilot would (then the pilot,
    which computes the run's first samples, would cost as much as the run)."""
    goal, size = plan.goal, plan.sampling.batch
    budget = goal.samples or goal.batches(size) * size
    pilot = min(PILOT_SAMPLES, size, budget) * len(pilot_values(plan.shape))
    return budget * len(plan.scenes) <= pilot


class FractionsRun:
    """One run of a plan in this process: each value's progression (what its stop rule has
    counted), the store if the run has one (resumed, claimed, written, sealed), and what this
    process computed and what it found computed (in the store when it started, or by other
    processes since)."""

    def __init__(self, plan: FractionsPlan, executor):
        self.plan, self.executor = plan, executor
        self.goal, self.size = plan.goal, plan.sampling.batch
        self.specs = [make_fraction_spec(s) for s in plan.scenes]
        self.verified = self.specs[0].ladder.verified
        self.progs = [Progression(self.goal, self.size, self.verified) for _ in plan.scenes]
        self.draws = Draws(plan.sampling)
        self.target = self.claims = None
        self.path: str | None = None  # the store as the caller named it
        self.damaged: list[tuple[int, int]] = []
        values = len(plan.scenes)
        self.kept = [0] * values  # batches the store held whole from batch 0 when the run started
        self.cpu = [0.0] * values
        self.started = time.time()
        self.wall = 0.0
        self.computed = self.from_store = self.from_others = 0
        self.interrupted = False

    def open_store(self, target, overwrite: bool) -> None:
        """Create the store, or resume it: count every whole batch it holds (also those past a
        gap), note the damaged ones (computed again) and the whole prefix of each value."""
        plan = self.plan
        self.target, self.path = target, target.name
        filled = target.prepare_run(plan, overwrite).reshape(len(plan.scenes), -1)
        self.damaged = _resume(plan, self.progs, self.draws, self.target, filled)
        self.kept = _whole_prefix(plan, filled, self.damaged)
        self.from_store = sum(t.samples for p in self.progs for t in p.tallies.values())

    def count(self, v: int, index: int, labels) -> None:
        """A batch's labels counted in its value's progression."""
        self.progs[v].add(index, Tally.of(labels["quarter_turns"], labels["status"],
                                          labels["certainty"], self.verified))

    def make_task(self, v: int, index: int) -> BatchTask:
        count = self.goal.count(index, self.size)
        states = initial_states(self.plan.scenes[v], self.plan.sampling,
                                self.draws.batch(index)[:count])
        return BatchTask(v, index, count, states)

    def found(self, v: int, index: int) -> bool:
        """Whether a batch another process wrote reads back whole; if so it is counted here
        (if not, it is computed again)."""
        count = self.goal.count(index, self.size)
        if self.target.filled_count(v, index) != count:
            return False
        labels, _ = self.target.read_batches(v, [index], [count])
        if index not in labels:
            return False
        self.count(v, index, labels[index])
        self.from_others += count
        return True

    def queue(self) -> ClaimQueue:
        if self.target is None:
            return ClaimQueue(BatchSource(self.progs, self.make_task))
        self.claims = self.target.claims()
        return ClaimQueue(BatchSource(self.progs, self.make_task, self.target.batch_written,
                                      self.found), self.claims)

    def compute(self, progress, stop) -> SchedulerLost | None:
        """Compute the batches the stop rules still need, each written to the store as it
        comes back (an interrupted run keeps it), then seal the store if every goal is met.
        Returns the lost scheduler of a Dask run that lost it, else None."""
        queue = self.queue()
        if not self.executor.dask and any(p.peek() is not None for p in self.progs):
            for spec, scene in zip(self.specs, self.plan.scenes, strict=True):
                spec.load(np.asarray(state_array(scene)))
        runner = self.executor.run(partial(compute_value_batch, self.specs), queue, stop,
                                   name=lambda t: f"fractions-{t.value}-{t.batch}")
        wall0 = time.perf_counter()
        lost = None
        try:
            for result in runner:
                self.take(result)
                if progress is not None:
                    progress(_progress(self.progs, result.value, self.goal, self.size,
                                       self.computed, wall0))
            # ``stop`` set: the runner hands out nothing more and ends with the batches in
            # flight, which are written above
            runner.close()
        except KeyboardInterrupt:
            self.interrupted = True
            hard_stop(runner)  # the batches in flight stop now, unwritten (a second Ctrl-C)
        except SchedulerLost as exc:  # the batches received are written already
            self.interrupted, lost = True, exc
        self.wall = time.perf_counter() - wall0
        self.interrupted = self.interrupted or not all(p.done for p in self.progs)
        if self.target is not None and not self.interrupted:
            _seal(self.target, self.progs, self.goal, self.size,
                  lambda v, index: self.claims.path((v, index)).exists(), self.kept)
        return lost

    def take(self, result) -> None:
        """A computed batch: written to the store (its claim released), then counted."""
        v = result.value
        self.computed += result.count
        self.cpu[v] += result.cpu_seconds
        if self.target is not None:
            self.target.write_batch(v, result.batch, result.states, result.labels)
            self.claims.release((v, result.batch))
        self.count(v, result.batch, result.labels)

    def close(self) -> None:
        if self.claims is not None:
            self.claims.close()

    def record(self) -> None:
        """The run's line beside the store, if it computed anything."""
        if self.target is not None and self.computed:
            self.target.record_run(run_record(
                self.started, self.wall, sum(self.cpu), self.computed, self.executor.mode,
                self.executor.workers, self.interrupted))

    def cost(self) -> dict:
        computed, cpu, wall = self.computed, sum(self.cpu), self.wall
        return {"computed": computed, "cpu_seconds": cpu, "wall_seconds": wall,
                "trajectories_per_second": computed / wall if wall > 0 else math.nan,
                "cpu_ms_per_trajectory": 1e3 * cpu / computed if computed else math.nan,
                "mode": self.executor.mode, "workers": self.executor.workers,
                "from_store": self.from_store, "from_others": self.from_others,
                "damaged_batches": len(self.damaged)}

    def results(self):
        """A Fractions for a plain run; a Continuation for a continuation."""
        plan = self.plan
        total = self.cost()
        results = []
        for v, (prog, scene) in enumerate(zip(self.progs, plan.scenes, strict=True)):
            stopped = prog.reason if prog.done else StopReason.INTERRUPTED
            cost = {"cpu_seconds": self.cpu[v]} if plan.parameters else total
            results.append(make_result(prog, plan.sampling, scene, stopped, cost, self.path,
                                       plan.at(v)))
        if not plan.parameters:
            return results[0]
        return Continuation(plan.parameters, plan.axes, results, plan.note, total, self.path)


def _progress(progs, v: int, goal, size: int, computed: int, wall0: float) -> FractionsProgress:
    t = progs[v].tally
    lo, hi = wilson_arrays([t.standing], [t.n_counted])
    p = t.standing / t.n_counted if t.n_counted else math.nan
    expected = goal.samples or (
        progs[v].samples if progs[v].done else min(
            max(samples_needed(t, goal.precision, goal.of), progs[v].samples + size),
            goal.batches(size) * size))
    return FractionsProgress(v, len(progs), sum(p.done for p in progs), t.samples,
                             (p, float(lo[0]), float(hi[0])), widest(t, goal.of),
                             goal.precision, int(expected), computed,
                             time.perf_counter() - wall0, t)


def run_record(started: float, wall: float, cpu: float, samples: int, mode: str, workers: int,
               interrupted: bool) -> dict:
    """One run's record beside its store: when, how long, what it computed."""
    return {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(started)),
            "wall_seconds": round(wall, 3), "cpu_seconds": round(cpu, 3), "samples": samples,
            "mode": mode, "workers": workers, "interrupted": interrupted}


class StoreIncomplete(RuntimeError):
    """A run that met its goal, but whose store does not hold every batch it counted."""


def _seal(target, progs, goal, size: int, held: Callable[[int, int], bool],
          kept: list[int]) -> None:
    """Once every value's goal is met: remove the batches beyond each value's stop (so the
    store is the same whoever computed what; not those another process is computing, which it
    removes itself once written: ``held``), then prove that the store holds every batch the
    results counted, whole; StoreIncomplete names what is missing."""
    for v, prog in enumerate(progs):
        # what the store held whole from batch 0 when this run started stays: an earlier run
        # (a tighter precision, more samples) needed it
        target.trim(v, max(prog.prefix, kept[v]), held)
    filled = target.read_filled().reshape(len(progs), -1)
    missing = []
    for v, prog in enumerate(progs):
        missing += [(v, b) for b in range(prog.prefix) if filled[v][b] < goal.count(b, size)]
    if missing:
        v, b = missing[0]
        where = f"batch {b}" + ("" if len(progs) == 1 else f" of value {v}")
        raise StoreIncomplete(f"{target.path}: {len(missing)} batch(es) counted in the results "
                              f"are not in the store ({where} first); rerun the same command "
                              "to compute them")


def _whole_prefix(plan: FractionsPlan, filled, damaged) -> list[int]:
    """Per value, the batches from 0 on that the store holds whole (none damaged)."""
    goal, size = plan.goal, plan.sampling.batch
    out = []
    for v in range(len(plan.scenes)):
        have = filled[v]
        index = 0
        while index < have.shape[0] and have[index] >= goal.count(index, size) > 0 and \
                (v, index) not in damaged:
            index += 1
        out.append(index)
    return out


def _resume(plan: FractionsPlan, progs, draws, target, filled) -> list[tuple[int, int]]:
    """Count the batches a store holds already (each value's, in its progression), after
    checking that this installation draws the same samples as the one that wrote them; the
    (value, batch) of those that do not read back (damaged: they are computed again)."""
    goal, size = plan.goal, plan.sampling.batch
    checked = False
    damaged: list[tuple[int, int]] = []
    for v, prog in enumerate(progs):
        have = filled[v]
        batches, counts = [], []
        for index in range(min(prog.limit, have.shape[0])):
            need = goal.count(index, size)
            if need and have[index] >= need:
                batches.append(index)
                counts.append(need)
        if not batches:
            continue
        labels, bad = target.read_batches(v, batches, counts)
        damaged += [(v, index) for index in bad]
        if labels and not checked:
            index = min(labels)
            count = goal.count(index, size)
            drawn = initial_states(plan.scenes[v], plan.sampling, draws.batch(index)[:count])
            stored = target.read_initial(v, index, count)
            if not np.array_equal(drawn[:, 1:], stored):
                raise ParameterError(f"{target.path}: the samples drawn here differ from the "
                                     "ones in the store (numpy or scipy changed?); overwrite "
                                     "starts it again", parameters=("overwrite",))
            checked = True
        for index, lab in labels.items():
            prog.add(index, Tally.of(lab["quarter_turns"], lab["status"], lab["certainty"],
                                     prog.verified))
    return damaged
