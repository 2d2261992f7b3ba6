"""The schema of a basin: its variables (dtype, fill value, attributes) and its attributes (every
parameter, the sweep, the method, the version). Shared by the Zarr store (:mod:`.store`) and the
in-memory xarray Dataset (:mod:`.dataset`), so that both hold the same thing."""

from __future__ import annotations

import math

from ..enums import Certainty, Status
from ..grid import Grid, SweepSpec, method_attrs
from ..integrators import NO_LABEL
from ..integrators.registry import MethodInfo
from ..params import Scene
from ..version import __version__

FORMAT = 3  # 3: checksummed chunks, done = a digest of each tile
COMPARED_ATTRS = ("version", "parameters", "sweep", "method")

# name -> (dtype, fill value, attributes)
VARIABLES = {
    "quarter_turns": ("int16", int(NO_LABEL), {
        "long_name": "final number n of quarter turns (phi / (pi/2)); odd = standing",
        "units": "1", "missing_value": int(NO_LABEL),
        "description": "the well that holds the settled coin; round(2 phi / pi) at t_end when "
                       "unsettled; -32768 where not computed or non-finite"}),
    "status": ("uint8", int(Status.NOT_COMPUTED), {
        "long_name": "run status (of the last rung run)",
        "flag_values": [int(s) for s in Status],
        "flag_meanings": " ".join(s.label.replace(" ", "_").replace("-", "_") for s in Status)}),
    "settle_time": ("float32", math.nan, {
        "long_name": "time at which the energy fell below E_crit (n final)", "units": "s"}),
    "steps": ("int64", -1, {"long_name": "integrator steps, summed over the rungs run",
                            "units": "1"}),
    "certainty": ("uint8", int(Certainty.NOT_COMPUTED), {
        "long_name": "whether the label converged on the ladder of settings (attribute "
                     "method.verification)",
        "flag_values": [int(c) for c in Certainty],
        "flag_meanings": " ".join(c.label.replace(" ", "_") for c in Certainty)}),
    "rung": ("int8", -1, {
        "long_name": "index of the last rung of the ladder run: the rung at which a certain "
                     "label converged", "units": "1"}),
}
DTYPES = {name: spec[0] for name, spec in VARIABLES.items()}
FILLS = {name: spec[1] for name, spec in VARIABLES.items()}
DONE_ATTRS = {"long_name": "digest of the tile, 0 = not done (written after its data)",
              "description": "32-bit BLAKE2b (person 'coin-tile') of the tile index (two int64) "
                             "and, for each of " + ", ".join(VARIABLES) + ", its shape (two "
                             "int64) and its values, all little-endian; never 0"}
COORD_NOTE = "linspace(lo, hi, n), ends included"


def basin_attrs(scene: Scene, method: MethodInfo, spec: SweepSpec) -> dict:
    """Everything needed to reproduce a basin: every parameter (the swept ones null, see
    ``sweep``), the grid, the method with its settings and verification ladder, the version."""
    grid = spec.grid
    parameters = scene.to_dict()
    for name in grid.dims:
        parameters["initial"][name] = None  # swept: see sweep.axes
    return {"coin_basin": {"format": FORMAT, "command": "coin basin"}, "version": __version__,
            "parameters": parameters, "sweep": grid.to_dict(),
            "method": method_attrs(scene, method)}


def tile_dims(grid: Grid) -> tuple[str, str]:
    return tuple(f"tile_{d}" for d in grid.dims)


__all__ = ["COMPARED_ATTRS", "COORD_NOTE", "DONE_ATTRS", "DTYPES", "FILLS", "FORMAT",
           "VARIABLES", "basin_attrs", "tile_dims"]
