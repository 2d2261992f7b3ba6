"""One batch of samples: its scene's kernel inputs, the task and the verified labels."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..integrators.batch import verified_labels
from ..integrators.ladder import Ladder, ladder_of
from ..params import (
    ModelParams,
    RunSettings,
    Scene,
    model_params,
    run_settings,
)


@dataclass(frozen=True)
class FractionSpec:
    """What a batch of one scene needs, as plain picklable values (shipped to Dask workers)."""

    params: ModelParams
    settings: RunSettings
    ladder: Ladder


def make_fraction_spec(scene: Scene) -> FractionSpec:
    return FractionSpec(model_params(scene), run_settings(scene.integration),
                        ladder_of(scene.integration))


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


def compute_batch(spec: FractionSpec, task: BatchTask, control=None) -> BatchResult:
    """Run every sample of a batch up the verification ladder (compiled; releases the GIL)."""
    cpu0 = time.thread_time()
    states = np.ascontiguousarray(task.states[:task.count], dtype=np.float64)
    out = verified_labels(spec.params, spec.settings, spec.ladder, states, control)
    labels = {name: getattr(out, name) for name in LABEL_NAMES}
    return BatchResult(task.value, task.batch, task.count, states, labels,
                       time.thread_time() - cpu0)
