"""The public API: what the CLI, the benchmarks, the tests and a notebook call.

    import coincli
    base = coincli.load_preset("paper")
    run = coincli.simulate(base, vy=1.197, vphi=3.508)     # a Trajectory
    outcome = coincli.classify(base, vy=1.197, vphi=3.508) # an Outcome: quarter_turns, status...
    ds = coincli.basin(base, vy=(0.05, 2.0), vphi=(-20.0, 20.0), res=64)   # xarray.Dataset
    coincli.basin_stats(ds).standing
    coincli.render_basin(ds, "basin.png")

A facade: each function checks its options, builds a plan and calls the one engine of its job (a
sweep's :func:`coincli.engines.basin.run_sweep`, a Monte Carlo run's
:func:`coincli.engines.fractions.run_fractions`, the analysis's
:func:`coincli.analysis.analyze_basin`). Options are keywords; results are named (objects with
``to_dict()``, Datasets). One throw, the statics, the methods and the compilation are in
:mod:`.throws`; basin maps in :mod:`.basins`, their boundaries in :mod:`.boundaries`, outcome
probabilities in :mod:`.probabilities`, the studies of the methods in :mod:`.studies`.

The command line (:mod:`coincli.cli`) imports nothing of the package but this API. What a front
end needs beyond the public names is in submodules: :mod:`.options` (parsers, checks of paths
and options, defaults, units: how to read user input), :mod:`.words` (how settings and results
are said: method ladders, horizons, durations, disk errors), :mod:`.recording` (live recordings
to Rerun) and :mod:`.errors` (every exception the API raises on purpose).

Names load on first use (the module's ``__getattr__``): importing this package, or its light
submodules :mod:`.options` and :mod:`.words`, loads no numpy, numba or kernels, so that the
command line declares its options (``coin --help``) without them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from ..version import __version__  # noqa: F401 - for a front end (coincli.__version__ too)

# where each public name is defined (a module of the package, relative to coincli)
_WHERE = {
    "enums": ("Certainty", "Engine", "Method", "Status", "StopReason"),
    "params": ("ParameterError", "Scene"),
    "stats": ("BasinStats",),
    "throw": ("Outcome", "classify"),
    "shock": ("MinimalShock", "minimal_shock"),
    "montecarlo": ("Fractions",),
    "montecarlo.plan": ("FractionsPlan", "FractionsProgress", "plan_fractions"),
    "engines.work": ("WorkTooLong",),
    "engines.basin": ("SweepProgress", "SweepReport", "SweepStart"),
    "engines.basin_plan": ("SweepEstimate", "SweepPlan", "SweepTooLong", "estimate_sweep",
                           "plan_sweep"),
    "charts.fractions_over": ("FractionsOver",),
    "recordings.rrd": ("record",),
    "recordings.trajectory": ("Trajectory",),
    "api.throws": ("compile_kernels", "load_preset", "method_table", "simulate", "stability",
                   "viewer"),
    "api.basins": ("basin", "basin_attrs", "basin_stats", "cell_scene", "export_basin",
                   "inspect_cell", "open_basin", "render_basin", "show_basin", "sweep",
                   "verify_basin"),
    "api.boundaries": ("analyze", "render_analysis"),
    "api.probabilities": ("estimate_fractions", "fractions", "fractions_over", "open_fractions",
                          "render_fractions", "run_fractions"),
}
_MODULE = {name: module for module, names in _WHERE.items() for name in names}

if TYPE_CHECKING:  # the same names, for the reference's generator and for type checkers
    from ..charts.fractions_over import FractionsOver
    from ..engines.basin import SweepProgress, SweepReport, SweepStart
    from ..engines.basin_plan import (
        SweepEstimate,
        SweepPlan,
        SweepTooLong,
        estimate_sweep,
        plan_sweep,
    )
    from ..engines.work import WorkTooLong
    from ..enums import Certainty, Engine, Method, Status, StopReason
    from ..montecarlo import Fractions
    from ..montecarlo.plan import FractionsPlan, FractionsProgress, plan_fractions
    from ..params import ParameterError, Scene
    from ..recordings.rrd import record
    from ..recordings.trajectory import Trajectory
    from ..shock import MinimalShock, minimal_shock
    from ..stats import BasinStats
    from ..throw import Outcome, classify
    from .basins import (
        basin,
        basin_attrs,
        basin_stats,
        cell_scene,
        export_basin,
        inspect_cell,
        open_basin,
        render_basin,
        show_basin,
        sweep,
        verify_basin,
    )
    from .boundaries import analyze, render_analysis
    from .probabilities import (
        estimate_fractions,
        fractions,
        fractions_over,
        open_fractions,
        render_fractions,
        run_fractions,
    )
    from .throws import (
        compile_kernels,
        load_preset,
        method_table,
        simulate,
        stability,
        viewer,
    )


def __getattr__(name: str):
    module = _MODULE.get(name)
    if module is None:
        raise AttributeError(f"module 'coincli.api' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"coincli.{module}"), name)
    globals()[name] = value  # loaded once
    return value


def __dir__():
    return sorted({*globals(), *__all__})


__all__ = ["BasinStats", "Certainty", "Engine", "Fractions", "FractionsOver", "FractionsPlan",
           "FractionsProgress", "Method", "MinimalShock", "Outcome", "ParameterError", "Scene",
           "Status", "StopReason", "SweepEstimate", "SweepPlan", "SweepProgress", "SweepReport",
           "SweepStart", "SweepTooLong", "Trajectory", "WorkTooLong", "analyze", "basin",
           "basin_attrs", "basin_stats", "cell_scene", "classify", "compile_kernels",
           "estimate_fractions", "estimate_sweep", "export_basin", "fractions",
           "fractions_over", "inspect_cell", "load_preset", "method_table", "minimal_shock",
           "open_basin", "open_fractions", "plan_fractions", "plan_sweep", "record",
           "render_analysis", "render_basin", "render_fractions", "run_fractions",
           "show_basin", "simulate", "stability", "sweep", "verify_basin", "viewer"]
