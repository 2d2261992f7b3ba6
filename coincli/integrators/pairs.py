"""The adaptive driver (:mod:`.adaptive`) with each Runge-Kutta pair it runs: a copy of the
driver whose ``ORDER``, ``FIRST_STEP``, ``step``, ``step_factor``, ``controller_memory``,
``dense_coefficients`` and ``dense_point`` are the pair's (:func:`coincli.jit.derive`: one
source, one compiled driver a pair). The driver as written runs Dormand-Prince 5(4) (``dopri5``,
``event``); here:

- Hairer's DOP853 (``event_dop853``): the verified ladder runs its rungs past the first on it,
  from rtol 1e-8 (:mod:`.ladder`): from 1e-7 down DOP853 costs 1.2 to 2.5 times less than
  Dormand-Prince 5(4) for the same tolerance (README, "Higher-order pairs");
- the switching pairs (:mod:`.switching`): Dormand-Prince 5(4) or DOP853 where the model's law is
  not stiff, Rodas5P where it is (``event_rodas``, ``event_dop853_rodas``), what a friction
  scene's ladder climbs on.

Which method runs on which driver is the registry's (:data:`.registry.DRIVER_OF`).
"""

from __future__ import annotations

from ..jit import derive
from . import adaptive, dop853, dopri, switching

PAIR_NAMES = ("ORDER", "FIRST_STEP", "step", "step_factor", "controller_memory",
              "dense_coefficients", "dense_point")

integrate_adaptive_dop853 = derive(
    adaptive, "_dop853", **{name: getattr(dop853, name) for name in PAIR_NAMES}
).integrate_adaptive

integrate_adaptive_rodas = derive(
    adaptive, "_rodas", ORDER=switching.ORDER5, step=switching.step5,
    step_factor=dopri.step_factor, controller_memory=dopri.controller_memory,
    dense_coefficients=switching.dense_coefficients5, dense_point=dopri.dense_point,
).integrate_adaptive

integrate_adaptive_dop853_rodas = derive(
    adaptive, "_dop853_rodas", ORDER=switching.ORDER8, FIRST_STEP=dop853.FIRST_STEP,
    step=switching.step8, step_factor=dop853.step_factor,
    controller_memory=dop853.controller_memory,
    dense_coefficients=switching.dense_coefficients8, dense_point=dop853.dense_point,
).integrate_adaptive

__all__ = ["PAIR_NAMES", "integrate_adaptive_dop853", "integrate_adaptive_dop853_rodas",
           "integrate_adaptive_rodas"]
