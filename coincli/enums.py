"""The enumerations every layer shares: how a run ended (:class:`Status`) and how it was
integrated (:class:`Method`).

They are ``IntEnum`` so that numba kernels can use them (as ``Status.SETTLED.value``) and stores
can hold them as small integers; everything above the kernels uses the members, their names and
their messages, never bare numbers or hand-compared strings; printed, a member is its word.
"""

from __future__ import annotations

from enum import IntEnum, StrEnum


class _Named(IntEnum):
    """An IntEnum that prints as its word: ``str(Status.SETTLED)`` and ``f"{status}"`` give
    ``settled``, not ``0`` (``f"{status:d}"`` and ``int(status)`` still give the number)."""

    @property
    def label(self) -> str:
        return self.name.lower()

    def __str__(self) -> str:
        return self.label

    def __format__(self, spec: str) -> str:
        if spec and spec[-1] in "bcdoxXneEfFgG%":  # a number's presentation type
            return int.__format__(self, spec)
        return format(self.label, spec)

    @classmethod
    def parse(cls, value):
        """A member from its name (``"event"``, any case) or the member itself; ValueError
        otherwise, naming the members."""
        if isinstance(value, cls):
            return value
        if isinstance(value, str):
            try:
                return cls[value.strip().upper()]
            except KeyError:
                pass
        raise ValueError(f"unknown {cls.__name__.lower()} {value!r}; available: "
                         f"{', '.join(m.label for m in cls)}")


class Status(_Named):
    """How a run (or a basin cell) ended. Only SETTLED gives a final count of quarter turns."""

    SETTLED = 0
    UNSETTLED = 1
    NONFINITE = 2
    BUDGET = 3
    INTERRUPTED = 4
    NOT_COMPUTED = 255

    @property
    def label(self) -> str:
        """The word a user reads (CLI, JSON, stores)."""
        return _STATUS_LABELS[self]

    @property
    def message(self) -> str:
        return _STATUS_MESSAGES[self]

    @property
    def labelled(self) -> bool:
        """Whether the run has a count of quarter turns at all: a settled run has the final
        one, an unsettled run the paper's round(2 phi / pi) at t_end (not final)."""
        return self in (Status.SETTLED, Status.UNSETTLED)


_STATUS_LABELS = {
    Status.SETTLED: "settled",
    Status.UNSETTLED: "unsettled",
    Status.NONFINITE: "non-finite",
    Status.BUDGET: "budget",
    Status.INTERRUPTED: "interrupted",
    Status.NOT_COMPUTED: "not computed",
}
_STATUS_MESSAGES = {
    Status.SETTLED: "the energy fell below E_crit: the count of quarter turns is final",
    Status.UNSETTLED: "the energy is still above E_crit at t_end: the count may still change",
    Status.NONFINITE: "the run went non-finite: no outcome",
    Status.BUDGET: "the run used up its step budget (max_steps) before t_end: no outcome",
    Status.INTERRUPTED: "the run was interrupted: no outcome",
    Status.NOT_COMPUTED: "not computed",
}


class Method(_Named):
    """Integration methods; the value is the id the kernels dispatch on."""

    SYMPLECTIC_EULER = 0
    VERLET = 1
    RK4 = 2
    DOPRI5 = 3
    EVENT = 4
    EVENT_DOP853 = 5
    EVENT_RODAS = 6
    EVENT_DOP853_RODAS = 7


class Certainty(_Named):
    """Whether a label is converged (verification per cell, see coincli.integrators.ladder):
    CERTAIN when two successive rungs of the ladder of settings agree (same n, both settled),
    UNVERIFIED for a single pass (no ladder), and when no two agreed by the last rung, why:
    UNCERTAIN when the rungs compared last were both decided (settled) but disagree, so that
    the outcome is set by perturbations below what the ladder resolves (chaotic at this
    precision), UNDECIDED when one of them was not decided (it reached its horizon or step
    budget still able to pass an edge)."""

    UNCERTAIN = 0
    CERTAIN = 1
    UNVERIFIED = 2
    UNDECIDED = 3
    NOT_COMPUTED = 255

    @property
    def label(self) -> str:
        return self.name.lower().replace("_", " ")

    @property
    def message(self) -> str:
        return _CERTAINTY_MESSAGES[self]

    @property
    def unsure(self) -> bool:
        """A verified label that did not converge, for either cause."""
        return self in (Certainty.UNCERTAIN, Certainty.UNDECIDED)


_CERTAINTY_MESSAGES = {
    Certainty.UNCERTAIN: "decided at every rung compared, but no two successive rungs agree: "
                         "chaotic at this precision",
    Certainty.CERTAIN: "two successive rungs agree",
    Certainty.UNVERIFIED: "a single pass, not verified",
    Certainty.UNDECIDED: "a rung did not decide the outcome within its horizon or step budget",
    Certainty.NOT_COMPUTED: "not computed",
}


class Engine(_Named):
    """What runs a kernel: numba's compiled code, or CPython on the same source (the same
    result to rounding, no compilation or loading: the faster choice for one short run), or the
    choice of AUTO."""

    AUTO = 0
    PYTHON = 1
    NUMBA = 2


class StopReason(StrEnum):
    """Why a Monte Carlo run (`coin fractions`) ended: every interval narrow enough, the
    samples asked for done, the sample budget spent, or interrupted (its numbers are partial)."""

    PRECISION = "precision"
    SAMPLES = "samples"
    BUDGET = "budget"
    INTERRUPTED = "interrupted"

    @property
    def label(self) -> str:
        return self.value


__all__ = ["Certainty", "Engine", "Method", "Status", "StopReason"]
