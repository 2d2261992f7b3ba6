"""Every exception the API raises on purpose, in one place, for a caller to catch by name:
bad input (:class:`ParameterError` and its kinds), work refused for its cost
(:class:`WorkTooLong`, a sweep's :class:`SweepTooLong`), a store that is damaged or incomplete,
an output that cannot be written, and a Dask cluster lost on the way.

Light: the engines' exceptions load when first named (:mod:`.lazy`), so that a front end can
name them in an ``except`` clause without loading the engines at start-up."""

from __future__ import annotations

from ..params import ParameterError  # noqa: F401 - a value that makes no sense, one line
from .lazy import lazy_names


def _work():
    from ..engines import work

    return work


def _basin_plan():
    from ..engines import basin_plan

    return basin_plan


def _executors():
    from ..engines import executors

    return executors


def _fractions_engine():
    from ..engines import fractions

    return fractions


def _store_layout():
    from ..stores import basin_layout

    return basin_layout


def _files():
    from .. import files

    return files


def _stream():
    from ..recordings import stream

    return stream


# name: (its module, its name there)
_LAZY = {
    # work estimated over max_seconds (ParameterErrors: ``estimate``, ``limit``)
    "WorkTooLong": (_work, "WorkTooLong"),
    "SweepTooLong": (_basin_plan, "SweepTooLong"),
    # a basin store whose metadata are damaged (a ParameterError: no tile can be checked)
    "StoreDamaged": (_store_layout, "StoreDamaged"),
    # a Monte Carlo store missing batches its results counted (rerun to compute them)
    "StoreIncomplete": (_fractions_engine, "StoreIncomplete"),
    # an output found unwritable before any work (an OSError)
    "NotWritable": (_files, "NotWritable"),
    # a Dask run's scheduler (or every worker) lost; NoWorkers: none for worker_timeout s
    "SchedulerLost": (_executors, "SchedulerLost"),
    "NoWorkers": (_executors, "NoWorkers"),
    # a notebook's viewer asked for without the extra coincli[notebook] (an ImportError)
    "NotebookMissing": (_stream, "NotebookMissing"),
}
__getattr__ = lazy_names(globals(), _LAZY)


__all__ = ["ParameterError", *_LAZY]
