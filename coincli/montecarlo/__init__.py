"""Outcome probabilities by Monte Carlo: P(n), P(standing), P(lying) for throws whose five
initial conditions (y0, phi0, vx, vy, vphi) are drawn from distributions, with 95 % intervals.

The public entry point is :func:`coincli.fractions` (:func:`coincli.api.fractions`)::

    import coincli
    result = coincli.fractions(coincli.load_preset("paper"), phi0="-pi:pi", precision=0.001)
    result.standing        # {"probability": ..., "low": ..., "high": ..., "count": ..., "of": ...}

This package holds the pure computation (no files, no threads, no terminal): the distributions
and their parsing and draws (:mod:`.sampling`: scrambled Sobol points or a seeded generator),
one batch's labels (:mod:`.batch`), the counts, intervals and stop rule (:mod:`.tally`), the
scenes of a continuation (:mod:`.continuation`) and the results (:mod:`.results`; a
continuation's, with their Dataset: :mod:`coincli.charts.fractions_over`).
:mod:`coincli.engines.fractions` runs batches on threads or Dask and
:mod:`coincli.stores.fractions_store` keeps them in a Zarr store.

Reproducibility
---------------
Sample i depends only on (seed, i, the distributions): Sobol points are generated batch by
batch from one scrambled sequence (``fast_forward`` to the batch's first index), random ones
from ``numpy.random.default_rng([seed, batch])``. The same points serve every value of a
continuation (common random numbers). Batches finish out of order on threads, so the stop rule
is evaluated on the prefix of completed batches *in order*: the same command stops after the
same number of samples however many threads ran it and however often it was resumed.

Probabilities and intervals
---------------------------
Probabilities are taken over the *certain* labels (verified: two successive rungs of the ladder
of settings agree, :mod:`coincli.integrators.ladder`); the *uncertain* fraction (no two rungs
agreed, or no label at all) is reported beside them, over all samples, and so are the
probabilities over *all labelled* samples. Each interval is Wilson's score interval at 95 %
(:func:`coincli.stats.proportion`, scipy's). For independent draws (``sampler="random"``) the
binomial interval is exact in its model. Scrambled Sobol points were measured to do no better
here (the variance of P(standing) across 48 scrambles is 1.04 times the binomial one, 95 % 0.72
to 1.63; ``benchmarks/fractions_variance.py``): the outcome is a chaotic function of the initial
conditions, which leaves quasi-random points nothing to exploit, so the same interval fits them.

``precision`` is the half-width, (high - low) / 2, of a 95 % interval: a run stops at the first
batch at which that half-width is at most ``precision`` for every probability it is asked about
(``of="all"``: every outcome n, standing, lying and the uncertain fraction; ``of="standing"``:
P(standing) only), or when the sample budget is spent.
"""

from .batch import (
    LABEL_NAMES,
    BatchResult,
    BatchTask,
    FractionSpec,
    compute_batch,
    make_fraction_spec,
)
from .continuation import (
    PARAMETER_UNITS,
    PARAMETERS,
    continuation_note,
    corner_restitution,
    disc_density,
    disc_inertia,
    lamina_inertia,
    parse_over,
    pender_uhrin,
    point_scene,
    scene_at,
)
from .results import (
    Fractions,
    level_crossing,
    make_result,
)
from .sampling import (
    DEFAULT_BATCH,
    DEFAULT_DISTRIBUTIONS,
    IC5,
    SAMPLERS,
    SOBOL_MAX,
    UNITS,
    Dist,
    Draws,
    Sampling,
    check_box,
    initial_states,
    make_sampling,
    max_reach,
    parse_dist,
)
from .tally import (
    CONFIDENCE,
    DEFAULT_MAX_SAMPLES,
    DEFAULT_PRECISION,
    GOALS,
    INTERVAL_NOTE,
    Goal,
    Progression,
    Tally,
    half_widths,
    make_goal,
    parse_count,
    parse_precision,
    precise,
    samples_needed,
    summary,
    widest,
    wilson_arrays,
)

__all__ = [
    "CONFIDENCE", "DEFAULT_BATCH", "DEFAULT_DISTRIBUTIONS", "DEFAULT_MAX_SAMPLES",
    "DEFAULT_PRECISION", "GOALS", "IC5", "INTERVAL_NOTE", "LABEL_NAMES", "PARAMETER_UNITS",
    "PARAMETERS", "SAMPLERS", "SOBOL_MAX", "UNITS", "BatchResult", "BatchTask", "check_box",
    "compute_batch", "continuation_note", "corner_restitution", "disc_density", "disc_inertia",
    "Dist", "Draws", "Fractions", "FractionSpec", "Goal", "half_widths", "initial_states",
    "lamina_inertia", "level_crossing", "make_fraction_spec", "make_goal", "make_result",
    "make_sampling",
    "max_reach", "parse_count", "parse_dist", "parse_over", "parse_precision", "pender_uhrin",
    "point_scene", "precise", "Progression", "samples_needed", "Sampling", "scene_at",
    "summary", "Tally", "widest", "wilson_arrays"
]
