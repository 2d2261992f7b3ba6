"""The public functions of the measures of basin boundaries: :func:`analyze` (the one call of
:func:`coincli.analysis.analyze_basin`, recorded to Rerun as it goes if asked) and its chart."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from ..engines.basin import check_progress
from ..params import ParameterError
from .basins import as_basin
from .recording import both, live_destination, warn_if_failed


def analyze(basin, *, box: int = 5, bands: int = 4, points: int | None = None,
            eps: tuple[float, ...] | None = None, seed: int = 0, threads: int | None = None,
            radius: float = 5.0, balls: int = 1000, max_dilation: int = 6,
            direction: str = "random", confidence: float = 0.95,
            progress: Callable[[str, int, int], None] | None = None, stop=None,
            on_band: Callable | None = None, rrd: str | os.PathLike | None = None,
            spawn: bool = False, connect: str | None = None, notebook=False):
    """How fractal the boundaries of a basin (Dataset or store path) are, on the whole map and
    per band of its first swept axis: a :class:`coincli.analysis.BasinAnalysis`
    (``.whole``, ``.bands``; ``.to_dict()`` is what ``coin basin analyze --json`` prints).

    On the map (``box`` cells per box, uncertain and not-computed cells left out): basin entropy
    S_b and boundary basin entropy S_bb with the log-2 criterion, the ball test for fractal
    boundaries (balls of ``radius`` cells, ``balls`` of them), box-counting alpha, the Wada
    merging test (up to ``max_dilation`` cells). With the simulator: the uncertainty exponent
    alpha by the perturbation method from ``points`` random initial conditions (default 150,000;
    0 skips it) perturbed by each of ``eps`` (relative to each axis's range; default 6 values,
    1e-9 to 1e-4), classified with verified labels on ``threads`` threads (default: one per
    core); D = 2 - alpha. ``seed`` makes it reproducible. ``progress(stage, done, total)``;
    ``on_band(index, rows, f)`` as each band's f(eps) (a
    :class:`coincli.boundary.UncertainFraction`) is measured, ``rows`` its first row and the
    one past its last along the first axis;
    ``stop`` (an Event) or Ctrl-C interrupts it (KeyboardInterrupt). ``rrd``, ``spawn`` and
    ``connect`` (or ``notebook``, alone: in the notebook's cell, shown once the cell ends)
    record it for Rerun as it goes (as `coin basin analyze --rrd FILE`): the map
    with its bands, each band's f(eps) as it is measured, the fits and the measures; a
    recording that fails is a RuntimeWarning, the analysis is returned all the same."""
    from ..analysis import DEFAULT_POINTS, AnalysisOptions, analyze_basin
    from ..engines.executors import usable_cores

    check_progress(progress)
    where = live_destination(rrd, spawn, connect, notebook)
    view = as_basin(basin)
    opts = AnalysisOptions(box=int(box), bands=int(bands),
                           points=DEFAULT_POINTS if points is None else int(points),
                           seed=int(seed), threads=int(threads or usable_cores()),
                           radius=float(radius), balls=int(balls),
                           max_dilation=int(max_dilation), direction=direction,
                           confidence=float(confidence),
                           **({} if eps is None else {"eps": tuple(float(e) for e in eps)}))
    a = view.arrays
    if on_band is not None and not callable(on_band):
        raise TypeError(f"on_band must be a function (or None), got {type(on_band).__name__}")
    if where is None:
        return analyze_basin(a["quarter_turns"], a["status"], a["certainty"], view.attrs,
                             options=opts, progress=progress, on_band=on_band, stop=stop)
    from ..recordings.analysis_view import AnalysisRecorder

    with AnalysisRecorder(view, where, bands=opts.bands, eps=opts.eps) as recorder:
        result = analyze_basin(a["quarter_turns"], a["status"], a["certainty"], view.attrs,
                               options=opts, progress=progress,
                               on_band=both(on_band, recorder.band), stop=stop)
        recorder.result(result)
    warn_if_failed(recorder)
    return result


def render_analysis(analysis, out: str | os.PathLike | None = None, *, ax=None,
                    panels=("fractions", "entropy", "alpha"), title: str | None = None,
                    dpi: int = 150):
    """Draw an analysis (of :func:`analyze`) and return the matplotlib Figure: the panels
    "fractions" (f(eps) on log-log axes with the fits), "entropy" (S_b and S_bb by band) and
    "alpha" (alpha by band), side by side in a new Figure, or into ``ax`` (one Axes a panel:
    ``render_analysis(a, ax=ax, panels=["alpha"])``). ``out``: also write it to a PNG, SVG
    or PDF (by the extension)."""
    from ..charts.analysis import plot_analysis

    try:
        return plot_analysis(analysis, None if out is None else Path(out), title=title,
                             dpi=dpi, ax=ax, panels=panels)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None
