"""A basin in memory (:class:`Basin`: numpy arrays and the attributes of the schema) and its
xarray form, the Dataset the public API returns. Rendering and statistics work on a Basin;
:func:`from_dataset` takes a Dataset back (ours, or ``xarray.open_zarr`` of a store)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..params import ParameterError
from .schema import FILLS, VARIABLES

DONE_VAR_ATTRS = {"long_name": "1 = tile complete (its data checked against its digest)"}


@dataclass
class Basin:
    """Arrays indexed [first swept axis, second swept axis]; cells of tiles not done hold the
    fill values (status NOT_COMPUTED)."""

    attrs: dict  # the schema's attributes: parameters, sweep, method, version
    arrays: dict[str, np.ndarray]  # the schema's variables (coincli.io.schema.VARIABLES)
    done: np.ndarray  # per tile, 1 = complete (and, read from a store, verified)
    tile_seconds: np.ndarray  # CPU seconds of each tile, NaN where unknown
    runs: list = field(default_factory=list)  # one record per invocation (wall time, mode)
    path: str | None = None  # the store it was read from
    damaged: list = field(default_factory=list)  # tiles whose data failed their check

    @property
    def dims(self) -> tuple[str, str]:
        return tuple(self.attrs["sweep"]["dims"])

    @property
    def axes(self) -> list[dict]:
        return self.attrs["sweep"]["axes"]

    @property
    def chunk(self) -> tuple[int, int]:
        return tuple(self.attrs["sweep"]["chunk"])

    @property
    def coords(self) -> tuple[np.ndarray, np.ndarray]:
        return tuple(np.linspace(a["lo"], a["hi"], a["n"]) for a in self.axes)

    @property
    def verified(self) -> bool:
        return len(self.attrs["method"]["verification"]["rungs"]) > 1

    @property
    def computed(self) -> np.ndarray:
        """Cell mask of complete tiles."""
        c0, c1 = self.chunk
        n0, n1 = self.arrays["status"].shape
        return np.repeat(np.repeat(self.done.astype(bool), c0, axis=0), c1, axis=1)[:n0, :n1]

    def mask_not_done(self) -> None:
        """Give the cells of tiles not done the fill values (whatever a chunk holds)."""
        missing = ~self.computed
        for name, arr in self.arrays.items():
            arr[missing] = FILLS[name]


def to_dataset(basin: Basin):
    """The Basin as an xarray Dataset: the variables of the schema on the two swept axes (cell
    centres as coordinates), ``done`` and ``tile_cpu_seconds`` per tile, every attribute."""
    import xarray as xr

    d0, d1 = basin.dims
    data_vars = {name: ((d0, d1), arr, dict(VARIABLES[name][2]))
                 for name, arr in basin.arrays.items()}
    tdims = (f"tile_{d0}", f"tile_{d1}")
    data_vars["done"] = (tdims, basin.done.astype(np.uint8), dict(DONE_VAR_ATTRS))
    data_vars["tile_cpu_seconds"] = (tdims, basin.tile_seconds,
                                     {"long_name": "CPU time of each tile", "units": "s"})
    coords = {}
    for axis, values in zip(basin.axes, basin.coords, strict=True):
        coords[axis["name"]] = (axis["name"], values, {"units": axis["units"],
                                                       "long_name": axis["long_name"]})
    attrs = {**basin.attrs, "runs": list(basin.runs),
             "damaged_tiles": [list(map(int, t)) for t in basin.damaged]}
    if basin.path is not None:
        attrs["store"] = basin.path
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def from_dataset(ds) -> Basin:
    """A Basin from a Dataset of :func:`to_dataset`, or from ``xarray.open_zarr`` of a store
    (whose masked float ``quarter_turns`` is turned back into int16 with its fill)."""
    if not hasattr(ds, "attrs") or not hasattr(ds, "data_vars"):
        raise TypeError(f"a basin must be an xarray Dataset (coincli.basin, coincli.open_basin) "
                        f"or a store's path, got {type(ds).__name__}")
    if "coin_basin" not in ds.attrs:
        raise ParameterError("not a coin basin dataset (no coin_basin attribute)")
    arrays = {}
    for name in VARIABLES:
        if name in ds.data_vars:
            values = np.asarray(ds[name].values)
            dtype = VARIABLES[name][0]
            if values.dtype != dtype:
                values = np.where(np.isnan(values), FILLS[name], values).astype(dtype)
            arrays[name] = values
    done = (np.asarray(ds["done"].values) != 0).astype(np.uint8)  # a store's: digests
    if "tile_cpu_seconds" in ds.data_vars:
        seconds = np.asarray(ds["tile_cpu_seconds"].values, dtype=float)
    else:
        seconds = np.full(done.shape, np.nan)
    attrs = {k: v for k, v in ds.attrs.items() if k not in ("runs", "store", "damaged_tiles")}
    basin = Basin(attrs=attrs, arrays=arrays, done=done, tile_seconds=seconds,
                  runs=list(ds.attrs.get("runs", [])), path=ds.attrs.get("store"),
                  damaged=[tuple(t) for t in ds.attrs.get("damaged_tiles", [])])
    basin.mask_not_done()
    return basin


__all__ = ["Basin", "from_dataset", "to_dataset"]
