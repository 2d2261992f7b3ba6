"""The labeller: the one door to the labelling kernels. A :class:`Labeller`, made from a scene
(its model, its parameters, its integration settings and their verification ladder) and a
backend, runs initial states to their outcome: a batch of them up the ladder, verified
(:meth:`Labeller.label`), or one state at one rung with its samples and contact events kept
(:meth:`Labeller.run`, what ``coin simulate`` records).

Every job that labels throws goes through it: a basin's tiles (:mod:`coincli.grid`), a Monte
Carlo batch (:mod:`coincli.montecarlo`), the boundary analysis, the minimal shock, the accuracy
study and the benchmark. So what a label is computed with (model, backend, ladder) is decided
in one place, and :meth:`Labeller.to_dict` says it for what a store's digest binds.

A labeller is made of plain values (the kernels' parameter tuples, the ladder) and pickles
small: a Dask worker rebuilds its kernels from the backend's name.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .integrators.batch import (
    VerifiedLabels,
    final_state,
    integrate_once,
    interruptible,
    new_control,
    verified_labels,
    warm_up,
)
from .integrators.common import RunResult
from .integrators.ladder import Ladder, ladder_of
from .params import ModelParams, RunSettings, Scene, model_params, run_settings


@dataclass(frozen=True)
class Labeller:
    """Labels the initial states of one scene (:meth:`of`): ``params`` and ``settings`` are
    what the kernels take, ``ladder`` the rungs a label climbs until two agree (one rung: a
    single pass, its labels unverified), ``backend`` what runs the kernels."""

    params: ModelParams
    settings: RunSettings
    ladder: Ladder
    backend: str = "cpu"

    @classmethod
    def of(cls, scene: Scene, *, sample_dt: float = 0.0, backend: str = "cpu") -> Labeller:
        """The labeller of ``scene``'s model, settings and ladder."""
        integ = scene.integration
        return cls(model_params(scene), run_settings(integ, sample_dt), ladder_of(integ),
                   backend)

    @property
    def verified(self) -> bool:
        return self.ladder.verified

    def to_dict(self) -> dict:
        """What labels computed by it depend on beyond the scene and the ladder: the backend."""
        return {"backend": self.backend}

    def with_settings(self, **changes) -> Labeller:
        """A copy whose run settings change (``t_end=``, ``stop_on_settle=``...)."""
        return replace(self, settings=self.settings._replace(**changes))

    # -- batches ---------------------------------------------------------------------------
    def label(self, states: np.ndarray, control=None) -> VerifiedLabels:
        """Every row of ``states`` (N x 6) up the ladder; releases the GIL, ``control[0]`` set
        (from another thread) stops it."""
        return verified_labels(self.params, self.settings, self.ladder, states, control)

    def load(self, state=None, *, trajectory: bool = False) -> None:
        """Load (or, the first time on this machine, compile) the kernels :meth:`label` runs
        (``trajectory``: those :meth:`run` and :meth:`final_state` run), before a clock
        starts."""
        state = np.array([0.0, self.params.r, 0.0, 0.0, 1.0, 3.0]) if state is None else state
        warm_up(self.params, self.settings._replace(sample_dt=0.0),
                np.asarray(state, dtype=np.float64),
                (final_state,) if trajectory else (verified_labels,))

    # -- one trajectory ---------------------------------------------------------------------
    def rung_settings(self, k: int) -> RunSettings:
        """The run settings of rung ``k`` of the ladder."""
        ladder = self.ladder
        return self.settings._replace(method=int(ladder.methods[k]), rtol=ladder.rtols[k],
                                      dt=ladder.dts[k],
                                      max_steps=ladder.budget(k, self.settings.max_steps))

    def run(self, settings: RunSettings, state, samples, events, final, control,
            compiled: bool = True) -> RunResult:
        """One trajectory from ``state`` with ``settings``, its samples and events written into
        the buffers given, its final state into ``final``; ``compiled=False`` runs the kernel
        as plain Python (a short throw needs no compiled code loaded). A compiled run takes
        Ctrl-C in this thread (the kernel stops through ``control``)."""
        if not compiled:
            return integrate_once(self.params, settings, state, samples, events, final,
                                  control, interpreted=True)
        return interruptible(lambda: integrate_once(self.params, settings, state, samples,
                                                    events, final, control), control)

    def final_state(self, state) -> tuple[np.ndarray, int]:
        """(final state, status) of one compiled run at the first rung, nothing recorded."""
        self.load(state, trajectory=True)
        return final_state(self.params, self.settings, state)


__all__ = ["Labeller", "VerifiedLabels", "new_control"]
