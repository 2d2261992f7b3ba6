"""What work may cost before it starts, one rule for both engines (a basin sweep's,
:mod:`.basin`, and a Monte Carlo run's, :mod:`.fractions`).

Time: each engine estimates its work from a pilot of its own (a sweep's cells, a run's
samples) and hands the estimate to :func:`checked_estimate`, which refuses work estimated over
the caller's limit (``max_seconds``; :data:`coincli.defaults.MAX_SECONDS`, 12 hours, unless
the caller goes ahead with None) with :class:`WorkTooLong`, before anything is created.

Memory: work whose arrays this machine cannot hold is refused before they are allocated (a
sweep's tiles, :func:`coincli.engines.basin_plan.check_tile_memory`; a Monte Carlo grid's
points, :func:`coincli.montecarlo.plan.check_grid_memory`), from :func:`available_memory`, in
one line naming what to make smaller (:func:`memory_text`), where numpy or Python would end in
a MemoryError (or the kernel's OOM killer) after a while.

No numpy: the API's options (:mod:`coincli.api.options`) name these without loading it."""

from __future__ import annotations

import numbers
import os
from collections.abc import Callable
from typing import TypeVar

from ..defaults import MAX_SECONDS
from ..values import ParameterError, format_duration

Estimate = TypeVar("Estimate")


class WorkTooLong(ParameterError):
    """Work whose estimate is over the limit it was given (``max_seconds``), refused before it
    started: ``estimate`` (a :class:`coincli.engines.basin_plan.SweepEstimate` or a
    :class:`coincli.montecarlo.estimate.FractionsEstimate`: ``seconds``, ``workers``...) and
    ``limit`` (s). A ParameterError: the command line says it in one line."""

    what = "this run"  # how the message names the work (a sweep's: "this sweep")

    def __init__(self, estimate, limit: float, what: str | None = None):
        self.estimate = estimate
        self.limit = limit
        bound = "at least" if getattr(estimate, "at_least", False) else "about"
        super().__init__(f"{what or self.what} would take {bound} "
                         f"{format_duration(estimate.seconds)}, over the limit of "
                         f"{format_duration(limit)} (max_seconds=None starts it anyway)",
                         parameters=("max_seconds",))


def check_max_seconds(max_seconds) -> None:
    """ParameterError unless ``max_seconds`` is a positive number of seconds or None."""
    if max_seconds is None:
        return
    if isinstance(max_seconds, bool) or not isinstance(max_seconds, numbers.Real) \
            or not max_seconds > 0:
        raise ParameterError(f"max_seconds must be a positive number of seconds (or None: no "
                             f"limit), got {max_seconds!r}", parameters=("max_seconds",))


def checked_estimate(estimate: Callable[[], Estimate], max_seconds: float | None,
                     too_long: type[WorkTooLong] = WorkTooLong) -> Estimate:
    """``estimate()`` (the engine's pilot), refused with ``too_long`` (WorkTooLong or a kind of
    it) if its ``seconds`` are over ``max_seconds`` (None: never refused)."""
    check_max_seconds(max_seconds)
    found = estimate()
    if max_seconds is not None and found.seconds > max_seconds:
        raise too_long(found, max_seconds)
    return found


def available_memory() -> int | None:
    """Bytes of memory a new allocation can take here without swapping: Linux's MemAvailable
    (/proc/meminfo), elsewhere the free pages; None where neither is known."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def size_text(n_bytes: float) -> str:
    """'26 MiB', '3.5 GiB'."""
    return f"{n_bytes / 2**30:.1f} GiB" if n_bytes >= 2**30 else f"{n_bytes / 2**20:.0f} MiB"


def memory_text(need: float, available: int) -> str:
    """How a refusal for memory says it: 'about 69.0 GiB of memory, and this machine has
    21.3 GiB available'."""
    return (f"about {size_text(need)} of memory, and this machine has {size_text(available)} "
            "available")


__all__ = ["MAX_SECONDS", "WorkTooLong", "available_memory", "check_max_seconds",
           "checked_estimate", "memory_text", "size_text"]
