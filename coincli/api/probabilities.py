"""The public functions of outcome probabilities (`coin fractions`): a Monte Carlo run over the
initial conditions, its continuation along one or two parameters, the run of a plan (the one
engine, :func:`coincli.engines.fractions.run_fractions`), its estimate, its store and its chart."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable
from pathlib import Path

from ..charts.fractions_over import FractionsOver
from ..defaults import MAX_SECONDS
from ..engines.basin import check_progress
from ..engines.executors import executor_for
from ..montecarlo import DEFAULT_BATCH, DEFAULT_MAX_SAMPLES, Fractions
from ..montecarlo.estimate import FractionsEstimate
from ..montecarlo.over import Continuation
from ..montecarlo.plan import FractionsPlan, FractionsProgress, plan_fractions
from ..params import ParameterError, Scene
from .recording import live_destination, warn_if_failed


def fractions(scene: Scene, *, y0=None, phi0=None, vx=None, vy=None, vphi=None,
              samples: int | None = None, precision: float | None = None, of: str = "all",
              max_samples: int = DEFAULT_MAX_SAMPLES, seed: int = 0, sampler: str = "sobol",
              batch: int = DEFAULT_BATCH, store: str | os.PathLike | None = None,
              overwrite: bool = False, threads: int | None = None, workers: int | None = None,
              scheduler: str | None = None, force: bool = False,
              progress: Callable[[FractionsProgress], None] | None = None,
              stop=None, rrd: str | os.PathLike | None = None, spawn: bool = False,
              connect: str | None = None, notebook=False,
              max_seconds: float | None = MAX_SECONDS, **overrides) -> Fractions:
    """The outcome probabilities of throws whose initial conditions are drawn at random.
    ``overrides`` change the scene's physical parameters and settings, by the flat names of
    :meth:`Scene.with_overrides` (``mu=0.3``, ``k=5000``), as :func:`simulate` takes them.

    Each of ``y0, phi0, vx, vy, vphi`` is a fixed value, a uniform range ``(lo, hi)`` or
    ``'LO:HI'``, a ``'normal(MEAN,SD)'`` (truncated: ``'normal(MEAN,SD,LO,HI)'``), or a
    :class:`coincli.montecarlo.Dist`; numbers may be written ``'2pi'``, ``'pi/2'``, and y0 in
    multiples of the coin's half diagonal, ``'r:5r'``. Not given: the scene's values, except
    vy and vphi, drawn over coin basin's default ranges. Samples are scrambled Sobol points
    (``sampler='sobol'``) or independent draws (``'random'``), reproducible from ``seed``.

    Runs batches of ``batch`` samples on ``threads`` threads (or on Dask: ``workers``,
    ``scheduler``) until the 95 % interval of every probability has half-width <= ``precision``
    (``of='standing'``: of P(standing) only), or ``max_samples`` are spent; ``samples`` fixes
    the count instead (``max_samples`` is spent in whole batches). With ``store`` the samples
    and labels are kept in (and resumed from) that Zarr store. Setting ``stop`` (a
    threading.Event) ends the run early with what it has: the result then says
    ``stopped=StopReason.INTERRUPTED``. Ctrl-C (a notebook's interrupt) raises
    KeyboardInterrupt, as it does in :func:`basin`; a store keeps every batch counted so far
    for a resume. ``rrd``, ``spawn`` and ``connect`` stream the running estimates to Rerun
    (as `coin fractions --rrd FILE`; see :func:`run_fractions`). A run estimated at over
    ``max_seconds`` (12 hours unless given) is refused before any work, as `coin fractions`
    refuses it without --yes (see :func:`run_fractions`). Returns a
    :class:`coincli.montecarlo.Fractions`."""
    from ..throw import with_keywords

    scene = with_keywords(scene, overrides, "fractions")
    plan = plan_fractions(scene, y0=y0, phi0=phi0, vx=vx, vy=vy, vphi=vphi, samples=samples,
                          precision=precision, of=of, max_samples=max_samples, seed=seed,
                          sampler=sampler, batch=batch, force=force)
    return _raise_if_interrupted(
        run_fractions(plan, store=store, overwrite=overwrite, threads=threads,
                      workers=workers, scheduler=scheduler, progress=progress, stop=stop,
                      rrd=rrd, spawn=spawn, connect=connect, notebook=notebook,
                      max_seconds=max_seconds), stop)


# the options of plan_fractions that fractions_over passes on (its other keywords: a scene's)
FRACTIONS_OPTIONS = ("y0", "phi0", "vx", "vy", "vphi", "samples", "precision", "of",
                     "max_samples", "seed", "sampler", "batch", "force")


def _raise_if_interrupted(result, stop):
    """KeyboardInterrupt for a run that Ctrl-C (not ``stop``) cut short; else the result."""
    if not result.interrupted or (stop is not None and stop.is_set()):
        return result
    runs = result.results if isinstance(result, FractionsOver) else [result]
    done = sum(r.samples for r in runs)
    kept = f"; {result.store} keeps them for a resume" if result.store else ""
    raise KeyboardInterrupt(f"fractions interrupted after {done:,} samples{kept}")


def fractions_over(scene: Scene, parameter: str | None = None, values=None, *, over=None,
                   keep=(), **options) -> FractionsOver:
    """The outcome probabilities at each of ``values`` of one physical ``parameter``
    (thickness, diameter, k, c, mass, inertia, g, mu, slip_velocity), or at every point of a
    grid of two
    (``over={"thickness": values, "c": values}``, or a list of (name, values) pairs, the first
    outermost), the same sample points at every value (common random numbers). For thickness
    and diameter the mass and inertia follow a uniform solid disc of the scene's density,
    except those named in ``keep`` (the result's ``note`` says which). Options are those of
    :func:`fractions` (Ctrl-C and ``stop`` as there); each value is resumable on its own in the
    store. Returns a :class:`coincli.FractionsOver` (``to_dataset()``: an xarray
    Dataset, one dimension a parameter). Keywords that are none of these options are the
    scene's values, as :func:`fractions` takes them (``mu=0.3`` over thickness)."""
    from ..throw import with_keywords

    if (over is None) == (parameter is None):
        raise ParameterError("give a parameter and its values, or over={name: values, ...}",
                             parameters=("over",))
    if over is None:  # (scene, "c", values), or (scene, {"thickness": ..., "c": ...})
        over = parameter if values is None else (parameter, values)
    run_options = {k: options.pop(k) for k in ("store", "overwrite", "threads", "workers",
                                               "scheduler", "progress", "stop", "rrd",
                                               "spawn", "connect", "notebook", "max_seconds")
                   if k in options}
    plan_options = {k: options.pop(k) for k in list(options) if k in FRACTIONS_OPTIONS}
    scene = with_keywords(scene, options, "fractions_over")
    plan = plan_fractions(scene, over=over, keep=keep, **plan_options)
    return _raise_if_interrupted(run_fractions(plan, **run_options), run_options.get("stop"))


def run_fractions(plan: FractionsPlan, *, store: str | os.PathLike | None = None,
                  overwrite: bool = False, threads: int | None = None,
                  workers: int | None = None, scheduler: str | None = None,
                  progress: Callable[[FractionsProgress], None] | None = None,
                  stop=None, rrd: str | os.PathLike | None = None, spawn: bool = False,
                  connect: str | None = None, notebook=False,
                  worker_timeout: float | None = None,
                  max_seconds: float | None = MAX_SECONDS,
                  on_start: Callable[[FractionsEstimate | None], None] | None = None,
                  estimate: bool = False) -> Fractions | FractionsOver:
    """Run a Monte Carlo run planned by :func:`plan_fractions` (see :func:`fractions` for the
    options): a Fractions for a plain run, a FractionsOver for a continuation. Unlike
    :func:`fractions`, it does not raise on Ctrl-C: it returns what it has, with
    ``stopped=StopReason.INTERRUPTED`` (as :func:`sweep` returns a report).

    Before any work the run is estimated (the pilot of :func:`estimate_fractions`, a few
    hundred samples) and, over ``max_seconds`` (12 hours unless given; None: no limit),
    refused with :class:`coincli.WorkTooLong` (``estimate``: the FractionsEstimate), nothing
    created or recorded, as `coin fractions` refuses it without --yes and a sweep is refused
    (:func:`sweep`). A run no larger than its pilot is not estimated (the pilot would cost as
    much as the run) unless ``estimate`` asks. ``on_start`` receives the estimate (None if
    there was none) before any work.

    ``rrd`` (an .rrd file), ``spawn`` (a new viewer) and ``connect`` (a running viewer's URL)
    stream the estimates to Rerun as the run goes, as `coin fractions --rrd FILE` does
    (``notebook``, alone: in the notebook's cell, shown once the cell ends): each
    probability with its 95 % band against the samples, or, over a parameter, against the
    parameter as each value finishes. A recording that fails does not fail the run: it is
    said in a RuntimeWarning. ``worker_timeout``: as for :func:`sweep`."""
    from ..engines.fractions import run_fractions as run
    from .recording import fractions_recorder

    check_progress(progress)
    target = None
    if store is not None:
        from ..stores.fractions_store import FractionsStore

        target = FractionsStore.for_run(store)
    where = live_destination(rrd, spawn, connect, notebook)
    recorder = None
    with contextlib.ExitStack() as recording:
        def started(found) -> None:  # the run passed its checks: the recording begins
            nonlocal recorder
            if where is not None:
                recorder = recording.enter_context(fractions_recorder(plan, where))
            if on_start is not None:
                on_start(found)

        def show(update) -> None:
            if progress is not None:
                progress(update)
            if recorder is not None:
                recorder.progress(update)

        result = _with_views(run(plan, target=target, overwrite=overwrite, threads=threads,
                                 workers=workers, scheduler=scheduler,
                                 progress=show if progress or where else None, stop=stop,
                                 worker_timeout=worker_timeout, max_seconds=max_seconds,
                                 on_start=started, estimate=estimate))
        if recorder is not None:
            recorder.result(result)
    warn_if_failed(recorder)
    return result


def _with_views(result):
    """The engine's result as the API hands it out: a continuation with its Dataset view."""
    return FractionsOver.of(result) if isinstance(result, Continuation) else result


def estimate_fractions(plan: FractionsPlan, *, threads: int | None = None,
                       workers: int | None = None, scheduler: str | None = None,
                       store: str | os.PathLike | None = None):
    """How long a planned run should take and how many samples its stop rule likely needs,
    from a pilot of a few hundred samples (timed on this machine): a
    :class:`coincli.montecarlo.estimate.FractionsEstimate` (``budget_suffices`` says whether
    the sample budget covers a precision goal). On ``threads`` threads (default one per core),
    ``workers`` Dask workers, or a cluster (``scheduler``: the estimate is then CPU time);
    samples that ``store`` holds already are not counted. (:func:`run_fractions` makes the
    same estimate before it starts, to refuse a run over its ``max_seconds``.)"""
    from ..engines.fractions import estimate_run

    target = None
    if store is not None and Path(store).is_dir():
        from ..stores.fractions_store import FractionsStore

        target = FractionsStore(store)
    return estimate_run(plan, executor_for(threads, workers, scheduler), target)


def open_fractions(store: str | os.PathLike):
    """A `coin fractions` store as an xarray Dataset: ``initial`` ([value,] sample, ic) and the
    labels ([value,] sample); batches not written hold the fill values (``filled`` says which
    are)."""
    from ..stores.fractions_store import open_fractions as open_store

    return open_store(store)


def render_fractions(result: FractionsOver, out: str | os.PathLike | None = None, *, ax=None,
                     panels=None, title: str | None = None, dpi: int = 150):
    """Plot a continuation and return the matplotlib Figure. Along one parameter: P(outcome)
    against it with 95 % interval bands, the panels "standing" (P(standing) and the uncertain
    fraction) and "outcomes" (P(n) of the most probable n), by default both. Over a grid of
    two: maps of "certain" (P(standing) over the certain labels), "decided" (over all decided
    labels), by default both, and "uncertain" (the uncertain share), each P(standing) with its
    line P = 1/3 and that line's 95 % band. Stacked in a new Figure, or into ``ax`` (one Axes
    a panel). ``out``: also write it to a PNG, SVG or PDF (by the extension)."""
    from ..charts.fractions import PANELS, plot_grid, plot_over

    if not isinstance(result, FractionsOver):
        raise TypeError(f"render_fractions draws a continuation (coincli.fractions_over), got "
                        f"{type(result).__name__}")
    try:
        if len(result.parameters) == 2:
            return plot_grid(result, out, title=title, dpi=dpi, ax=ax,
                             **({} if panels is None else {"panels": panels}))
        return plot_over(result, out, title=title, dpi=dpi, ax=ax,
                         panels=PANELS if panels is None else panels)
    except ValueError as exc:
        raise ParameterError(str(exc)) from None
