"""The ladder of settings behind a verified label.

Every initial condition is computed at rung 0, 1, ... until two successive rungs agree (both
runs settled, with the same count of quarter turns, having entered that final well at the same
moment to within CHANGE_TOLERANCE and settled at the same moment to within SETTLE_TOLERANCE, see
:func:`coincli.integrators.batch.rungs_agree`): the
label is then *certain*, converged at that rung. A cell whose label has not converged by the
last rung is *uncertain*. Cells that agree at once cost two runs; only the disagreeing ones
climb.

Adaptive methods climb in tolerance, rtol, rtol / 10, ... down to the floor; fixed-step methods
in step, dt / 10^(1/p) (a tenfold smaller error for a method of order p) for FIXED_RUNGS rungs,
each rung with the step budget of its own step (t_end / dt, or ``max_steps`` times the first
rung's step over its own): a finer step needs more steps to reach the same time.
The ``event`` method climbs on DOP853 (``event_dop853``, the same driver with an 8th-order pair)
past its first rung, starting two decades below it (rtol 1e-6, then 1e-8, 1e-9, ...): DOP853 at
rtol 1e-8 costs less than Dormand-Prince 5(4) at 1e-7 and is far more accurate, so the first
comparison, which decides most labels, is against a nearly converged run computed by another
pair. On the README's 5-D box that ladder is certain with another n than the event method at
rtol 1e-11 and 1e-12 on 2 of 262,121 paper-coin throws (17 with Dormand-Prince 5(4) alone) and
74 of 57,922 thick-coin throws (103), at 1.07-1.14 and 2.0-2.1 times less CPU (README, "Verified
labels").
A single pass (``verify=False``) is a ladder of one rung: its labels are UNVERIFIED.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ..enums import Method
from ..models import model_of
from ..params import Integration
from .registry import info, setting_text, step_budget

RTOL_FLOOR = 1e-12  # the tightest tolerance a ladder climbs to (README: "Verified labels")
FIXED_RUNGS = 3
CHANGE_TOLERANCE = 1e-3  # s: two agreeing runs enter their final well this close in time
SETTLE_TOLERANCE = 1e-2  # s: and fall below E_crit this close in time


@dataclass(frozen=True)
class Ladder:
    """The rungs of one integration's verification, coarse to fine."""

    methods: tuple[Method, ...]
    rtols: tuple[float, ...]
    dts: tuple[float, ...]
    adaptive: bool
    change_tolerance: float = CHANGE_TOLERANCE
    settle_tolerance: float = SETTLE_TOLERANCE
    budgets: tuple[int, ...] = ()  # each rung's step budget; () gives each the run's own

    def budget(self, k: int, default: int) -> int:
        """Rung k's step budget (``default``, the run's, if the ladder sets none)."""
        return self.budgets[k] if self.budgets else default

    @property
    def verified(self) -> bool:
        return len(self.rtols) > 1

    def __len__(self) -> int:
        return len(self.rtols)

    def rung_text(self, k: int) -> str:
        """``rtol = 1e-06`` or ``dt = 5e-07 s``: what rung k sets, and its method if it is not
        the first rung's (``rtol = 1e-08 with event_dop853``)."""
        text = f"rtol = {self.rtols[k]:g}" if self.adaptive else f"dt = {self.dts[k]:g} s"
        return text if self.methods[k] == self.methods[0] else f"{text} with {self.methods[k]}"

    def gaps(self, a, b) -> list[str]:
        """Why two settled runs with the same n (each with ``settle_time`` and ``last_change``,
        s) fail this ladder's rule (:func:`coincli.integrators.batch.rungs_agree`), in words:
        ``settled 0.0323 s apart``, ``entered its well 4.1 ms apart``, or that only one of them
        changed well; [] where they agree."""
        gaps = []
        if abs(a.settle_time - b.settle_time) > self.settle_tolerance:
            gaps.append(f"settled {abs(a.settle_time - b.settle_time):.3g} s apart")
        if math.isnan(a.last_change) != math.isnan(b.last_change):
            gaps.append("only one of the two changed well")
        elif abs(a.last_change - b.last_change) > self.change_tolerance:
            gaps.append(f"entered its well {abs(a.last_change - b.last_change) * 1e3:.3g} ms "
                        "apart")
        return gaps

    def to_dict(self) -> dict:
        knob = "rtol" if self.adaptive else "dt"
        return {"rungs": [{"method": self.methods[k].label,
                           knob: (self.rtols if self.adaptive else self.dts)[k],
                           **({"max_steps": self.budgets[k]} if self.budgets else {})}
                          for k in range(len(self))],
                "change_tolerance": self.change_tolerance,
                "settle_tolerance": self.settle_tolerance,
                "rule": "a label is certain when two successive rungs both settle with the "
                        "same count of quarter turns, having passed into that final well "
                        "within change_tolerance seconds of each other and settled within "
                        "settle_tolerance seconds of each other; uncertain if no two do"}


def ladder_of(integration: Integration, *, stiff: bool = False) -> Ladder:
    """The ladder of an integration's settings (one rung if it does not verify); ``stiff``: of
    a stiff model's scene (:attr:`coincli.models.Model.stiff`), whose rungs climb on the
    method's switching pair where it has one (the registry's ``stiff_variant``)."""
    method = info(integration.method)
    if stiff and method.stiff_variant is not None:
        method = info(method.stiff_variant)
    first = method.method
    if not integration.verify:
        return Ladder((first,), (integration.rtol,), (integration.dt,), method.adaptive,
                      budgets=(step_budget(integration),))
    if method.adaptive:
        rtol = integration.rtol
        # the rungs past the first: the registry's method and start, or the method itself a
        # decade below
        upper, start = method.upper_rungs or (first, 10.0)
        # the second rung: `start` below the first, but not below the floor unless the first is
        # within a decade of it
        rtols = [rtol, max(rtol / start, min(rtol / 10.0, RTOL_FLOOR))]
        while rtols[-1] / 10.0 >= RTOL_FLOOR * (1 - 1e-9):
            rtols.append(rtols[-1] / 10.0)
        return Ladder((first,) + (upper,) * (len(rtols) - 1), tuple(rtols),
                      (integration.dt,) * len(rtols), True,
                      budgets=(step_budget(integration),) * len(rtols))
    dts = tuple(integration.dt / 10.0 ** (k / method.order) for k in range(FIXED_RUNGS))
    return Ladder((first,) * FIXED_RUNGS, (integration.rtol,) * FIXED_RUNGS, dts, False,
                  budgets=fixed_budgets(integration, dts))


def scene_ladder(scene) -> Ladder:
    """The ladder of a scene's settings under its model (:func:`ladder_of`)."""
    return ladder_of(scene.integration, stiff=model_of(scene).stiff)


def fixed_budgets(integration: Integration, dts: tuple[float, ...]) -> tuple[int, ...]:
    """The step budgets of fixed-step rungs: each the t_end / dt its own step takes (exactly
    the steps its run makes), or, with ``max_steps`` given (or no horizon), that budget of the
    first rung scaled by dt_0 / dt, so that every rung may reach the same time."""
    if integration.max_steps is None and integration.t_end is not None:
        return tuple(step_budget(replace(integration, dt=dt)) for dt in dts)
    first = step_budget(integration)  # max_steps, or without a horizon FIXED_MAX_STEPS
    return tuple(math.ceil(first * dts[0] / dt - 1e-9) for dt in dts)


def describe(integration: Integration, *, stiff: bool = False) -> str:
    """The method and setting of a run as a user reads it, with its verification:
    ``event, rtol = 1e-06, verified up to rtol = 1e-12`` (``stiff``: as :func:`ladder_of`)."""
    ladder = ladder_of(integration, stiff=stiff)
    first = ladder.methods[0]
    base = f"{first.label}, {setting_text(first, integration.dt, integration.rtol)}"
    if not ladder.verified:
        return f"{base}, single pass"
    return f"{base}, verified up to {ladder.rung_text(len(ladder) - 1)}"


def describe_scene(scene) -> str:
    """:func:`describe` of a scene's settings under its model."""
    return describe(scene.integration, stiff=model_of(scene).stiff)


__all__ = ["FIXED_RUNGS", "Ladder", "RTOL_FLOOR", "describe", "describe_scene", "fixed_budgets",
           "ladder_of", "scene_ladder"]
