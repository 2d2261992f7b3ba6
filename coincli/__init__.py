"""coin: the plane model of a rigid coin impacting an elastic foundation.

The public API (see :mod:`coincli.api` and docs/api.md):

    import coincli
    base = coincli.load_preset("paper")
    run = coincli.simulate(base.with_overrides(vy=1.197, vphi=3.508))   # one throw
    ds = coincli.basin(base, vy=(0.05, 2.0), vphi=(-20.0, 20.0), res=64)
    r = coincli.fractions(base, phi0="-pi:pi", precision=0.001)   # Monte Carlo
    r.standing["probability"], r.standing["low"], r.standing["high"]

Names load on first use, so ``import coincli`` (and ``coin --help``) stays cheap.
"""

from .version import __version__

_API = ("BasinStats", "Certainty", "Engine", "Fractions", "FractionsOver", "FractionsPlan",
        "FractionsProgress", "Method", "MinimalShock", "Outcome", "ParameterError", "Scene",
        "Status", "StopReason", "SweepEstimate", "SweepPlan", "SweepProgress", "SweepReport",
        "SweepStart", "SweepTooLong", "Trajectory", "WorkTooLong", "analyze", "basin",
        "basin_attrs", "basin_stats", "cell_scene", "classify", "compile_kernels",
        "estimate_fractions", "estimate_sweep", "export_basin", "fractions", "fractions_over",
        "inspect_cell", "load_preset", "method_table", "minimal_shock", "open_basin",
        "open_fractions", "plan_fractions", "plan_sweep", "record", "render_analysis",
        "render_basin", "render_fractions", "run_fractions", "show_basin", "simulate",
        "stability", "sweep", "verify_basin", "viewer")
# = coincli.api.__all__ (tested)

__all__ = ["__version__", *_API]


# names that need no more than a light module, loaded without even coincli.api (whose other names
# load numpy and the kernels' modules on first use)
_LIGHT = {"Scene": "params", "ParameterError": "params", "Certainty": "enums", "Engine": "enums",
          "Method": "enums", "Status": "enums", "StopReason": "enums"}


def __getattr__(name: str):
    if name in _LIGHT:
        import importlib

        return getattr(importlib.import_module(f".{_LIGHT[name]}", __name__), name)
    if name in _API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'coincli' has no attribute {name!r}")


def __dir__():
    return sorted(__all__)
