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
``to_dict()``, Datasets). One throw, the statics and the compilation are here; basin maps in
:mod:`.basins`, their boundaries in :mod:`.boundaries`, outcome probabilities in
:mod:`.probabilities`.
"""

from __future__ import annotations

from ..charts.fractions_over import FractionsOver
from ..engines.basin import SweepProgress, SweepReport, SweepStart
from ..engines.basin_plan import SweepEstimate, SweepPlan, SweepTooLong, estimate_sweep, plan_sweep
from ..enums import Certainty, Engine, Method, Status, StopReason
from ..montecarlo import Fractions
from ..montecarlo.plan import FractionsPlan, FractionsProgress, plan_fractions
from ..params import ParameterError, Scene, validate
from ..presets import load
from ..recordings.rrd import record
from ..recordings.trajectory import Trajectory
from ..shock import MinimalShock, minimal_shock
from ..statics import StabilityReport, analyse
from ..stats import BasinStats
from ..throw import Outcome, classify
from ..throw import simulate as simulate_throw
from .basins import (
    basin,
    basin_attrs,
    basin_stats,
    cell_scene,
    export_basin,
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


def load_preset(name_or_path: str = "paper") -> Scene:
    """The scene of a shipped preset (``coin presets`` lists them) or of a TOML file."""
    return load(name_or_path).scene


def simulate(scene: Scene, *, sample_dt: float | None = None, record_events: bool = False,
             force: bool = False, engine: Engine = Engine.AUTO, control=None,
             **overrides) -> Trajectory:
    """Integrate one throw (a :class:`Trajectory`), verified on the ladder of settings unless
    ``verify=False``.

    ``overrides`` change the scene for this throw, by the flat names of
    :meth:`Scene.with_overrides`: initial conditions (``vy=1.197, vphi=3.508``, ``phi0="pi/2"``,
    ``y0="2r"``), physical parameters (``k=5000``) and integration settings (``rtol=1e-8``).
    With ``sample_dt`` the state is kept every ``sample_dt`` seconds of simulated time (exact
    times for the adaptive methods); with ``record_events`` every contact onset and lift-off is
    kept with its state. ``force`` allows a fixed step beyond the method's stable step.
    ``engine`` chooses what runs the kernel (the same result to rounding: compiled code fuses
    multiplies and adds, :mod:`coincli.jit`); ``control`` (from
    :func:`coincli.integrators.new_control`) lets another thread stop it."""
    return Trajectory.of(simulate_throw(scene, sample_dt=sample_dt, record_events=record_events,
                                        force=force, engine=engine, control=control,
                                        **overrides))


def stability(scene: Scene) -> StabilityReport:
    """The static energy table and critical stiffnesses of the paper's section 3, and E_crit."""
    return analyse(validate(scene))


def compile_kernels() -> bool:
    """Compile every kernel for this machine now, unless this version is compiled here already
    (:func:`coincli.jit.kernels_cached`): what the first run of any of them would do, in about
    ``coincli.jit.FIRST_COMPILE_SECONDS``. Whatever the scene, the kernels take the same
    argument types, so the default scene's compile serves every later one. True if it
    compiled. Silent: a caller that wants to show the wait does (``coin compile``)."""
    from .. import jit
    from ..labeller import Labeller

    if jit.kernels_cached():
        return False
    Labeller.of(Scene()).compile_all()
    return True


def viewer(*, width: int | None = None, height: int | None = None):
    """A Rerun viewer shown in the notebook's cell now (``width`` and ``height`` in pixels),
    for the work of later cells: ``coincli.basin(..., store=..., notebook=v)``,
    ``fractions(..., notebook=v)``, ``analyze(..., notebook=v)``, ``show_basin(ds,
    notebook=v)`` show in it as they run (a viewer made in the cell that runs the work is
    ready only once the cell has run: Jupyter hands the kernel its "ready" between cells)."""
    from ..recordings.stream import notebook_viewer

    return notebook_viewer(width=width, height=height)


__all__ = ["BasinStats", "Certainty", "Engine", "Fractions", "FractionsOver", "FractionsPlan",
           "FractionsProgress", "Method", "MinimalShock", "Outcome", "ParameterError", "Scene",
           "Status", "StopReason", "SweepEstimate", "SweepPlan", "SweepProgress", "SweepReport",
           "SweepStart", "SweepTooLong", "Trajectory", "analyze", "basin", "basin_attrs",
           "basin_stats", "cell_scene", "classify", "compile_kernels", "estimate_fractions",
           "estimate_sweep", "export_basin", "fractions", "fractions_over", "load_preset",
           "minimal_shock", "open_basin", "open_fractions", "plan_fractions", "plan_sweep",
           "record", "render_analysis", "render_basin", "render_fractions", "run_fractions",
           "show_basin", "simulate", "stability", "sweep", "verify_basin", "viewer"]
