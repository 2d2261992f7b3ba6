"""What a front end (the command line, a GUI, a web form) needs to read and check user input
before it calls the API: the defaults and units it shows in its help, the parsers of numbers,
quantities, ranges, counts and resolutions as users type them, the presets, and the checks made
before any work (is an output path of the right kind and writable, is a choice of where to run
consistent, is a step stable).

Errors are :class:`coincli.ParameterError` in the API's words (``res must be at least 2``,
``parameters`` naming the API's keywords), which a front end words its own way (the command
line: :func:`coincli.cli.common.in_cli_words`); a path that cannot be written is the OSError a
user should read (:mod:`.words` says it in one line).

Light: imported by every command module at start-up, it loads only the parameters, the
presets and the defaults; the rest loads on first use (:mod:`.lazy`)."""

from __future__ import annotations

from ..defaults import (  # noqa: F401 - the defaults a front end shows
    DEFAULT_BATCH,
    DEFAULT_CHUNK,
    DEFAULT_FPS,
    DEFAULT_LOG_EVERY,
    DEFAULT_MAX_SAMPLES,
    DEFAULT_PRECISION,
    DEFAULT_PRESET,
    DEFAULT_RANGES,
    DEFAULT_RES,
    DEFAULT_SECONDS,
    IC_NAMES,
    MAX_SECONDS,
    PARAMETER_UNITS,
    parameter_label,
)
from ..params import ParameterError, parse_number, parse_whole, shown, validate  # noqa: F401
from ..presets import available as available_presets  # noqa: F401 - every shipped Preset
from ..presets import load as read_preset  # noqa: F401 - a Preset (name, description, scene)
from ..presets import presets_dir  # noqa: F401
from ..quantities import parse_quantity  # noqa: F401 - 0.5, pi/2, 5r
from .lazy import lazy_names


def parse_eps(text, count: int) -> tuple[float, ...]:
    """``count`` perturbation sizes log-spaced over the range ``text`` (``'1e-9:1e-4'``, or a
    pair): the ``eps`` of :func:`coincli.analyze`."""
    from ..analysis import eps_values
    from ..grid import parse_range

    span = parse_range("eps", text)
    if not isinstance(span, tuple):
        raise ParameterError(f"eps '{shown(text)}' is not a LO:HI range", parameters=("eps",))
    return eps_values(span[0], span[1], count)


def _files():
    from .. import files

    return files


def _grid():
    from .. import grid

    return grid


def _tally():
    from ..montecarlo import tally

    return tally


def _executors():
    from ..engines import executors

    return executors


def _export():
    from ..charts import export

    return export


def _animation():
    from ..charts import animation

    return animation


def _store_layout():
    from ..stores import basin_layout

    return basin_layout


def _registry():
    from ..integrators import registry

    return registry


def _zarr():
    from ..stores import zarr_v3

    return zarr_v3


# name: (its module, its name there)
_LAZY = {
    # numbers and ranges as typed: 'LO:HI' or a value (a sweep's axes); 'N' or 'NxM'; '16k',
    # '4.6e6'; '0.001' or '0.1%'
    "parse_range": (_grid, "parse_range"),
    "parse_pair": (_grid, "parse_pair"),
    "parse_count": (_tally, "parse_count"),
    "parse_precision": (_tally, "parse_precision"),
    # where work runs: threads, Dask workers or a scheduler, checked; this machine's cores
    "check_where": (_executors, "check_where"),
    "usable_cores": (_executors, "usable_cores"),
    # outputs checked before any work: writable (the OSError a user should read), and of a
    # kind the API writes (ParameterError)
    "check_writable": (_files, "check_writable"),
    "check_figure_path": (_files, "check_figure_path"),
    "check_rrd_path": (_files, "check_rrd_path"),
    "check_export_path": (_export, "check_export_path"),
    "check_animation_path": (_animation, "check_animation_path"),
    "check_store_writable": (_store_layout, "check_store_writable"),
    "atomic_output": (_files, "atomic_output"),
    # whether a (Zarr) store is at a path: what a failed run has written there is kept
    "is_store": (_zarr, "is_store"),
    # a fixed step against the method's stable step (ParameterError unless force)
    "check_step": (_registry, "check_step"),
}
__getattr__ = lazy_names(globals(), _LAZY)


__all__ = ["DEFAULT_BATCH", "DEFAULT_CHUNK", "DEFAULT_FPS", "DEFAULT_LOG_EVERY",
           "DEFAULT_MAX_SAMPLES", "DEFAULT_PRECISION", "DEFAULT_PRESET", "DEFAULT_RANGES",
           "DEFAULT_RES", "DEFAULT_SECONDS", "IC_NAMES", "MAX_SECONDS", "PARAMETER_UNITS",
           "ParameterError", "available_presets", "parameter_label", "parse_eps", "parse_number",
           "parse_quantity", "parse_whole", "presets_dir", "read_preset", "shown", "validate",
           *_LAZY]
