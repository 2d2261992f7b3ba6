"""The labeller: the one door to the labelling kernels. A :class:`Labeller`, made from a scene
(its model, that model's parameters, the integration settings and their verification ladder)
and a backend, runs initial states to their outcome: a batch of them up the ladder, verified
(:meth:`Labeller.label`), or one state at one rung with its samples and contact events kept
(:meth:`Labeller.run`, what ``coin simulate`` records).

Every job that labels throws goes through it: a basin's tiles (:mod:`coincli.grid`), a Monte
Carlo batch (:mod:`coincli.montecarlo`), the boundary analysis, the minimal shock, the accuracy
study, the benchmark and one throw. So what a label is computed with (model, backend, ladder)
is decided in one place, and :meth:`Labeller.to_dict` says it for what a store's digest binds.

A labeller is made of plain values (its model's and backend's names, the kernels' parameter
tuple, the ladder) and pickles small: a Dask worker builds its kernel set from the names
(:func:`coincli.jit.kernels`, once per process).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from . import jit
from .enums import Method
from .integrators.batch import (
    VerifiedLabels,
    integrate,
    interruptible,
    new_control,
    run_ladder,
    unrecorded,
)
from .integrators.common import RunResult
from .integrators.ladder import Ladder, ladder_of
from .integrators.pairs import integrate_adaptive_dop853, integrate_adaptive_dop853_rodas
from .integrators.registry import run_settings
from .models import MODELS, model_of
from .params import RunSettings, Scene


@dataclass(frozen=True)
class Labeller:
    """Labels the initial states of one scene (:meth:`of`): ``model`` names its model,
    ``params`` and ``settings`` are what the kernels take, ``ladder`` the rungs a label climbs
    until two agree (one rung: a single pass, its labels unverified), ``backend`` names what
    runs the kernels (:data:`coincli.jit.BACKENDS`)."""

    model: str
    params: NamedTuple
    settings: RunSettings
    ladder: Ladder
    backend: str = jit.NUMBA.name

    @classmethod
    def of(cls, scene: Scene, *, sample_dt: float = 0.0,
           backend: str = jit.NUMBA.name) -> Labeller:
        """The labeller of ``scene``'s model, settings and ladder."""
        model, integ = model_of(scene), scene.integration
        return cls(model.name, model.params(scene), run_settings(integ, sample_dt),
                   ladder_of(integ, stiff=model.stiff), jit.backend_named(backend).name)

    @property
    def kernels(self) -> jit.KernelSet:
        """The kernel set of the model and backend (built once per process)."""
        return jit.kernels(MODELS[self.model], self.backend)

    @property
    def python(self) -> jit.KernelSet:
        """The model's kernels as plain Python (formulas applied to a few values, or arrays)."""
        return jit.kernels(MODELS[self.model], jit.PYTHON)

    @property
    def verified(self) -> bool:
        return self.ladder.verified

    def to_dict(self) -> dict:
        """What labels computed by it depend on beyond the scene's values and the ladder."""
        return {"model": self.model, "backend": self.backend}

    def with_backend(self, backend) -> Labeller:
        return replace(self, backend=jit.backend_named(backend).name)

    # -- batches ---------------------------------------------------------------------------
    def label(self, states: np.ndarray, control=None) -> VerifiedLabels:
        """Every row of ``states`` (N x 6) up the ladder; releases the GIL (compiled),
        ``control[0]`` set (from another thread) stops it."""
        n = states.shape[0]
        ladder, settings = self.ladder, self.settings
        out = VerifiedLabels(np.empty(n, np.int16), np.empty(n, np.uint8),
                             np.empty(n, np.float32), np.empty(n, np.int64),
                             np.empty(n, np.uint8), np.empty(n, np.int8))
        self.kernels[run_ladder](
            self.params, settings, np.asarray(ladder.methods, dtype=np.int64),
            np.asarray(ladder.rtols, dtype=np.float64), np.asarray(ladder.dts, dtype=np.float64),
            np.asarray([ladder.budget(k, settings.max_steps) for k in range(len(ladder))],
                       dtype=np.int64),
            float(ladder.change_tolerance), float(ladder.settle_tolerance),
            np.ascontiguousarray(states, dtype=np.float64), *unrecorded(), *out,
            new_control() if control is None else control)
        return out

    # -- one trajectory ---------------------------------------------------------------------
    def rung_settings(self, k: int) -> RunSettings:
        """The run settings of rung ``k`` of the ladder."""
        ladder = self.ladder
        return self.settings._replace(method=int(ladder.methods[k]), rtol=ladder.rtols[k],
                                      dt=ladder.dts[k],
                                      max_steps=ladder.budget(k, self.settings.max_steps))

    def run(self, settings: RunSettings, state, samples, events, final,
            control) -> RunResult:
        """One trajectory from ``state`` with ``settings``, its samples and events written into
        the buffers given, its final state into ``final``. A compiled run takes Ctrl-C in this
        thread (the kernel stops through ``control``)."""
        kernel = self.kernels[integrate]
        if not jit.backend_named(self.backend).compiled:
            return kernel(self.params, settings, state, samples, events, final, control)
        return interruptible(lambda: kernel(self.params, settings, state, samples, events,
                                            final, control), control)

    def final_state(self, state) -> tuple[np.ndarray, int]:
        """(final state, status) of one run with the first rung's settings, nothing recorded."""
        self.load(state, trajectory=True)
        no_samples, no_events, final = unrecorded()
        result = self.kernels[integrate](self.params, self.settings,
                                         np.ascontiguousarray(state, dtype=np.float64),
                                         no_samples, no_events, final, new_control())
        return final, result.status

    # -- loading ----------------------------------------------------------------------------
    def load(self, state=None, *, trajectory: bool = False) -> None:
        """Load from numba's cache the kernels :meth:`label` runs (``trajectory``: those
        :meth:`run` and :meth:`final_state` run), before a clock starts. Each is loaded by a
        short call whose arrays have the same types as in every real call, so that the same
        specialisations load (the first load also imports what numba needs to load machine
        code, 0.3 s; each after it 0.03 s). The first time these sources run on this machine,
        every kernel of the model compiles at once (:func:`compile_all`) and is marked
        compiled (:func:`coincli.jit.kernels_cached`)."""
        if not jit.backend_named(self.backend).compiled:
            return
        state = np.array([0.0, self.params.r, 0.0, 0.0, 1.0, 3.0]) if state is None else state
        state = np.ascontiguousarray(state, dtype=np.float64)
        if not jit.kernels_cached(self.model):
            self.compile_all(state)
            return
        short = self.settings._replace(t_end=self.settings.dt * 4, sample_dt=0.0)
        if trajectory:
            self._run_short(integrate, short._replace(stop_on_settle=False), state)
        else:
            replace(self, settings=short).label(state[None, :])

    def compile_all(self, state=None) -> None:
        """Compile (or load) every kernel of the model this labeller's calls run, and mark
        them compiled: the DOP853 driver the model runs first (the largest: its switching
        pair's with friction), while the process holds the least (the lowest peak memory:
        docs/performance.md, "First compile")."""
        state = np.array([0.0, self.params.r, 0.0, 0.0, 1.0, 3.0]) if state is None else state
        state = np.ascontiguousarray(state, dtype=np.float64)
        short = self.settings._replace(t_end=self.settings.dt * 4, sample_dt=0.0)
        largest = (integrate_adaptive_dop853_rodas if self.kernels.FRICTION
                   else integrate_adaptive_dop853)
        self._run_short(largest, short._replace(method=int(Method.EVENT_DOP853)), state)
        self._run_short(integrate, short._replace(stop_on_settle=False), state)
        one_rung = Ladder((self.ladder.methods[0],) * 2, (self.settings.rtol,) * 2,
                          (self.settings.dt,) * 2, True)
        replace(self, settings=short, ladder=one_rung).label(state[None, :])
        jit.mark_cached(self.model)

    def _run_short(self, driver, settings, state) -> None:
        """One run of ``driver`` (integrate, or a driver it calls: they take the same
        arguments), nothing recorded: the specialisation integrate calls."""
        no_samples, no_events, final = unrecorded()
        self.kernels[driver](self.params, settings, state, no_samples, no_events, final,
                             new_control())


__all__ = ["Labeller", "VerifiedLabels", "new_control"]
