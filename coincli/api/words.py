"""How the package says its settings and results to a user, for a front end to print them the
same way everywhere: a method with its verification ladder (``event, rtol = 1e-06, verified up
to rtol = 1e-12``), a run's horizon (``t_end = 2 s``, or the cap's rule), a duration (``3.5
h``), an OSError in one line (``cannot write out.zarr: read-only file system``), the tables of
the statics, and any result as plain JSON values.

Light: imported by every command module at start-up, it loads nothing heavier than
:mod:`coincli.values`; the rest loads on first use (:mod:`.lazy`)."""

from __future__ import annotations

from ..values import (  # noqa: F401 - '3.5 h'; '0.047 s' measured; a value quoted short
    format_duration,
    format_seconds,
    shown,
)
from ..version import documentation  # noqa: F401 - a page of the documentation site
from .lazy import lazy_names


def _ladder():
    from ..integrators import ladder

    return ladder


def _registry():
    from ..integrators import registry

    return registry


def _models():
    from .. import models

    return models


def _files():
    from .. import files

    return files


def _statics():
    from .. import statics

    return statics


def _boundary():
    from .. import boundary

    return boundary


def _basin_schema():
    from ..stores import basin_schema

    return basin_schema


def _jsonable():
    from .. import jsonable

    return jsonable


# name: (its module, its name there)
_LAZY = {
    # a scene's integration as a user reads it, with its verification ('event, rtol = 1e-06,
    # verified up to rtol = 1e-12'); a setting alone ('rtol = 1e-06', 'dt = 1e-06 s'); the
    # ladder of settings that verifies a label (its rungs' text: rung_text(i))
    "describe_method": (_ladder, "describe_scene"),
    "setting_text": (_registry, "setting_text"),
    "ladder_of": (_ladder, "scene_ladder"),
    # how long a run may last (s: t_end, or the throw's cap) and that rule in words
    "scene_horizon": (_models, "scene_horizon"),
    "horizon_text": (_models, "horizon_text"),
    # a scene's friction in words ('mu = 0.3 at the corners, slip velocity 0.001 m/s'; None
    # without)
    "friction_text": (_models, "friction_text"),
    # a basin store's method attributes in words, with the pair its ladder ran on where that
    # is another ('event (run as event_rodas)')
    "store_method_text": (_basin_schema, "method_text"),
    # an OSError in one line ('cannot write out.zarr: read-only file system'); any error in
    # one line; the errnos of a disk that refuses a write; the OSError of an output found
    # unwritable before any work (its str() is the whole line)
    "describe_error": (_files, "describe"),
    "explain": (_files, "explain"),
    "DISK_ERRORS": (_files, "DISK_ERRORS"),
    "NotWritable": (_files, "NotWritable"),
    # the statics' tables (rows of label, rigid, elastic; of name, value, meaning) and their
    # unit: energies in mJ (J x MJ)
    "energy_rows": (_statics, "energy_rows"),
    "critical_rows": (_statics, "critical_rows"),
    "MJ": (_statics, "MJ"),
    # ln 2: the log-2 criterion of a fractal boundary (boundary basin entropy above it)
    "LOG2": (_boundary, "LOG2"),
    # any result as plain JSON values (numpy numbers, enums by name, NaN as None)
    "jsonable": (_jsonable, "jsonable"),
}
__getattr__ = lazy_names(globals(), _LAZY)


__all__ = ["format_duration", "shown", *_LAZY]
