"""One batch of samples: its scene's kernel inputs, the task and the verified labels."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..labeller import Labeller
from ..params import Scene

FractionSpec = Labeller  # what a batch of one scene needs (picklable: shipped to Dask workers)


def make_fraction_spec(scene: Scene) -> Labeller:
    return Labeller.of(scene)


@dataclass(frozen=True)
class BatchTask:
    """One unit of work: ``count`` samples of batch ``batch`` for value ``value`` (0 for a
    plain run), from these initial states."""

    value: int
    batch: int
    count: int
    states: np.ndarray


@dataclass
class BatchResult:
    value: int
    batch: int
    count: int
    states: np.ndarray  # count x 6
    labels: dict  # name -> array of count (quarter_turns, status, settle_time, steps, ...)
    cpu_seconds: float


LABEL_NAMES = ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung")


def compute_batch(spec: Labeller, task: BatchTask, control=None) -> BatchResult:
    """Run every sample of a batch up the verification ladder (compiled; releases the GIL)."""
    cpu0 = time.thread_time()
    states = np.ascontiguousarray(task.states[:task.count], dtype=np.float64)
    out = spec.label(states, control)
    labels = {name: getattr(out, name) for name in LABEL_NAMES}
    return BatchResult(task.value, task.batch, task.count, states, labels,
                       time.thread_time() - cpu0)
