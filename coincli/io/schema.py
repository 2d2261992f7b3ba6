"""The schema of a basin: its variables (dtype, fill value, attributes) and its attributes (every
parameter, the sweep, the method, the version). Shared by the Zarr store (:mod:`.store`) and the
in-memory xarray Dataset (:mod:`.dataset`), so that both hold the same thing."""

from __future__ import annotations

import math

from ..enums import Status
from ..grid import UNCERTAIN_NOT_COMPUTED, Grid, SweepSpec, certify_attrs, method_attrs
from ..integrators import NO_LABEL
from ..integrators.registry import MethodInfo
from ..params import Scene
from ..version import __version__

FORMAT = 1
COMPARED_ATTRS = ("version", "parameters", "sweep", "method", "certify")

# name -> (dtype, fill value, attributes)
VARIABLES = {
    "quarter_turns": ("int16", int(NO_LABEL), {
        "long_name": "final number n of quarter turns (phi / (pi/2)); odd = standing",
        "units": "1", "missing_value": int(NO_LABEL),
        "description": "the well that holds the settled coin; round(2 phi / pi) at t_end when "
                       "unsettled; -32768 where not computed or non-finite"}),
    "status": ("uint8", int(Status.NOT_COMPUTED), {
        "long_name": "run status",
        "flag_values": [int(s) for s in (Status.SETTLED, Status.UNSETTLED, Status.NONFINITE,
                                         Status.NOT_COMPUTED)],
        "flag_meanings": "settled unsettled_at_t_end non_finite not_computed"}),
    "settle_time": ("float32", math.nan, {
        "long_name": "time at which the energy fell below E_crit (n final)", "units": "s"}),
    "steps": ("int64", -1, {"long_name": "integrator steps", "units": "1"}),
    "uncertain": ("uint8", UNCERTAIN_NOT_COMPUTED, {
        "long_name": "n changes under the certifying run (see the certify attribute)",
        "flag_values": [0, 1, UNCERTAIN_NOT_COMPUTED],
        "flag_meanings": "certain uncertain not_computed"}),
}
DTYPES = {name: spec[0] for name, spec in VARIABLES.items()}
FILLS = {name: spec[1] for name, spec in VARIABLES.items()}
DONE_ATTRS = {"long_name": "1 = tile complete (written after its data)"}
COORD_NOTE = "linspace(lo, hi, n), ends included"


def basin_attrs(scene: Scene, method: MethodInfo, spec: SweepSpec) -> dict:
    """Everything needed to reproduce a basin: every parameter (the swept ones null, see
    ``sweep``), the grid, the method and its settings, the certifying run, the version."""
    grid = spec.grid
    parameters = scene.to_dict()
    for name in grid.dims:
        parameters["initial"][name] = None  # swept: see sweep.axes
    return {"coin_basin": {"format": FORMAT, "command": "coin basin"}, "version": __version__,
            "parameters": parameters, "sweep": grid.to_dict(),
            "method": method_attrs(scene, method), "certify": certify_attrs(spec)}


def tile_dims(grid: Grid) -> tuple[str, str]:
    return tuple(f"tile_{d}" for d in grid.dims)


__all__ = ["COMPARED_ATTRS", "COORD_NOTE", "DONE_ATTRS", "DTYPES", "FILLS", "FORMAT",
           "VARIABLES", "basin_attrs", "tile_dims"]
