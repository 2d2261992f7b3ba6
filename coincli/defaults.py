"""Defaults and names a user sees in option help (free of heavy imports, so that the command line
can declare its options without loading numpy or the kernels)."""

from __future__ import annotations

DEFAULT_PRESET = "paper"

# The initial-condition options, in the order of the state vector (x, y, phi, vx, vy, vphi).
IC_NAMES = ("x0", "y0", "phi0", "vx", "vy", "vphi")

# name -> (label for plots, unit, long name)
AXIS_INFO = {
    "x0": ("$x_0$", "m", "initial horizontal position"),
    "y0": ("$y_0$", "m", "initial height of the centroid"),
    "phi0": (r"$\varphi_0$", "rad", "initial angle"),
    "vx": ("$v_{x0}$", "m/s", "initial horizontal velocity"),
    "vy": ("$v_{y0}$", "m/s", "initial vertical velocity"),
    "vphi": (r"$v_{\varphi 0}$", "rad/s", "initial angular velocity"),
}

# The paper sweeps (vy0, vphi0) with x0 = 0, y0 = r, phi0 = 0, vx0 = 0; its ranges were on the
# figures, not in the text. These are the ranges on which the paper's method was measured
# (docs/model.md): they contain the fig.-2 throw and outcomes from robust to chaotic.
DEFAULT_RANGES = {"vy": (0.05, 2.0), "vphi": (-20.0, 20.0)}
DEFAULT_RES = 512
DEFAULT_CHUNK = 64

DEFAULT_LOG_EVERY = 1e-3  # s of simulated time between frames of a recording

# an animation of a throw (coin simulate --gif): its frame rate, and how long it lasts on screen
# (a throw lasts a fraction of a second: it is slowed down to last this long; a longer run,
# sped up)
DEFAULT_FPS = 25
DEFAULT_SECONDS = 4.0

# Work (a sweep, a Monte Carlo run) estimated to take longer is refused before it starts, unless
# the caller goes ahead (max_seconds=None in the API, --yes on the command line).
MAX_SECONDS = 12 * 3600.0

# coin fractions
DEFAULT_BATCH = 8192  # 2^13: Sobol points keep their balance in powers of two
DEFAULT_PRECISION = 0.002  # +- 0.2 percentage points
DEFAULT_MAX_SAMPLES = 1 << 24
# The physical parameters a continuation (--over) can follow, and their units.
PARAMETER_UNITS = {"thickness": "m", "diameter": "m", "k": "N/m", "c": "N s/m", "mass": "kg",
                   "inertia": "kg m^2", "g": "m/s^2", "mu": "1", "slip_velocity": "m/s"}


def display_unit(name: str) -> str:
    """The unit a reader sees beside a parameter's values: its PARAMETER_UNITS entry, but none
    for a dimensionless one (the "1" that stores and JSON keep, as CF conventions write it)."""
    unit = PARAMETER_UNITS[name]
    return "" if unit == "1" else unit


def parameter_label(name: str) -> str:
    """A parameter as an axis or a table column names it: ``thickness (m)``, or ``mu``."""
    unit = display_unit(name)
    return f"{name} ({unit})" if unit else name


__all__ = ["AXIS_INFO", "DEFAULT_BATCH", "DEFAULT_CHUNK", "DEFAULT_FPS", "DEFAULT_LOG_EVERY",
           "DEFAULT_MAX_SAMPLES", "DEFAULT_PRECISION", "DEFAULT_PRESET", "DEFAULT_RANGES",
           "DEFAULT_RES", "DEFAULT_SECONDS", "IC_NAMES", "MAX_SECONDS", "PARAMETER_UNITS",
           "display_unit", "parameter_label"]
