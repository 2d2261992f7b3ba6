"""The event method with Hairer's DOP853 in place of Dormand-Prince 5(4) (``event_dop853``): a
copy of the adaptive driver (:mod:`.adaptive`) whose ``ORDER``, ``FIRST_STEP``, ``step``,
``step_factor``, ``controller_memory``, ``dense_coefficients`` and ``dense_point`` are those of
:mod:`.dop853` (:func:`coincli.jit.derive`: one source, two compiled drivers). The verified
ladder runs its rungs past the first on it, from rtol 1e-8 (:mod:`.ladder`): from 1e-7 down
DOP853 costs 1.2 to 2.5 times less than Dormand-Prince 5(4) for the same tolerance (README,
"Higher-order pairs")."""

from __future__ import annotations

from ..jit import derive
from . import adaptive, dop853

PAIR_NAMES = ("ORDER", "FIRST_STEP", "step", "step_factor", "controller_memory",
              "dense_coefficients", "dense_point")

integrate_adaptive_dop853 = derive(
    adaptive, "_dop853", **{name: getattr(dop853, name) for name in PAIR_NAMES}
).integrate_adaptive

__all__ = ["PAIR_NAMES", "integrate_adaptive_dop853"]
