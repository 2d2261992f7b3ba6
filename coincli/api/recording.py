"""Live recordings to Rerun, as the public functions make them and as a front end asks for
them: the checked destination of a recording (:func:`live_destination`; :class:`Destination`,
:func:`display_available`), the recorders a front end runs beside its own progress display (a
sweep's, a Monte Carlo run's, an analysis's: each a context manager with ``progress`` for the
work's callback and ``error`` if it failed), chaining a caller's callback with a recorder's,
and the warning of a recording that failed (a recording never fails the work it shows).

Light: Rerun and the recordings' modules load when a recording is asked for."""

from __future__ import annotations

import warnings

from .lazy import lazy_names


def live_destination(rrd, spawn: bool, connect, notebook=False):
    """The checked destination of a live recording (None if none is asked for): ParameterError
    (naming ``rrd``, ``spawn``, ``connect`` or ``notebook``) for a file name that does not end
    in .rrd, ``spawn`` without a display, a ``connect`` that is no viewer's URL; OSError for
    an ``rrd`` that cannot be written, ConnectionError when no viewer answers at
    ``connect``."""
    if rrd is None and not spawn and connect is None and notebook is False:
        return None  # Rerun's code is not even imported
    from ..recordings.stream import check_destination

    return check_destination(rrd, spawn, connect, notebook)


def sweep_recorder(plan, store, where):
    """The live recording of the sweep of ``plan`` (a SweepPlan) into ``store`` to ``where``
    (of :func:`live_destination`; None: no recorder), whose process starts now: a context
    manager around the sweep, ``begin()`` when its work starts (its ``on_start``), its
    ``progress`` chained with the sweep's; ``cancel()`` if the sweep never runs."""
    from ..recordings.sweep_recording import sweep_recorder as make

    return make(plan, store, where)


def fractions_recorder(plan, where):
    """The live recording of the Monte Carlo run of ``plan`` (a FractionsPlan) to ``where``
    (None: no recorder): a context manager around the run, its ``progress`` chained with the
    run's, ``result(result)`` once it is done."""
    if where is None:
        return None
    from ..recordings.fractions_view import FractionsRecorder

    return FractionsRecorder(plan, where)


def analysis_recorder(basin, where, *, bands: int, eps):
    """The live recording of :func:`coincli.analyze` of ``basin`` (a Basin, as
    ``coincli.api.basins.open_store(path).read()`` gives it) to ``where`` (None: no recorder)
    with ``bands`` bands and perturbations ``eps``: a context manager around the analysis,
    ``band`` its ``on_band``, ``result(a)`` once it is done."""
    if where is None:
        return None
    from ..recordings.analysis_view import AnalysisRecorder

    return AnalysisRecorder(basin, where, bands=bands, eps=eps)


def both(first, second):
    """A callback calling ``first`` then ``second`` with the same arguments (either may be
    None)."""
    if first is None or second is None:
        return first or second
    return lambda *args: (first(*args), second(*args))


def warn_if_failed(recorder, stacklevel: int = 3) -> None:
    """A RuntimeWarning if ``recorder``'s recording failed, attributed to the line that
    called the public function that calls this (``stacklevel``)."""
    if recorder is None or recorder.error is None:
        return
    from ..files import explain

    warnings.warn(f"the live recording failed: {explain(recorder.error)}", RuntimeWarning,
                  stacklevel=stacklevel)


def _stream():
    from ..recordings import stream

    return stream


# name: (its module, its name there)
_LAZY = {
    # where a recording goes: .rrd, spawn, connect, notebook (falsy when nowhere)
    "Destination": (_stream, "Destination"),
    # whether a spawned viewer has a display here, and the words for when it has not
    "display_available": (_stream, "display_available"),
    "NO_DISPLAY": (_stream, "NO_DISPLAY"),
}
__getattr__ = lazy_names(globals(), _LAZY)


__all__ = ["analysis_recorder", "both", "fractions_recorder", "live_destination",
           "sweep_recorder", "warn_if_failed", *_LAZY]
