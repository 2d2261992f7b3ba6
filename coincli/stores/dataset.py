"""A basin in memory (:class:`Basin`: numpy arrays and the attributes of the schema) and its
xarray form, the Dataset the public API returns. Rendering and statistics work on a Basin;
:func:`from_dataset` takes a Dataset back (ours, a NetCDF export of it opened by xarray, or
``xarray.open_zarr`` of a store).

Two conventions make a Dataset the same on every route (``coincli.basin``,
``coincli.open_basin``, ``xarray.open_zarr`` of a store, ``xarray.open_dataset`` of an export):

- Missing labels: ``quarter_turns`` is float32 with NaN where a cell has no label (not
  computed, or non-finite), as xarray decodes the store's int16 with its ``missing_value``
  -32768; written out (``to_netcdf``) it is int16 with that ``missing_value`` again, and any
  route opened with ``mask_and_scale=False`` gives the raw int16.
- Attributes: NetCDF holds no nested attributes, so every Dataset attribute that is not a
  string or a number is JSON text, and the attribute ``json_attributes`` names them;
  :func:`decoded_attrs` gives them back (a store opened by ``xarray.open_zarr`` has them
  nested already, and is taken as it is).
"""

from __future__ import annotations

import json
import numbers
from dataclasses import dataclass, field

import numpy as np

from ..params import ParameterError
from ..stats import BasinCounts, BasinStats
from .basin_schema import FILLS, MARK, VARIABLES

JSON_ATTRS = "json_attributes"  # the Dataset attribute naming those held as JSON text
MASKED = "quarter_turns"  # the variable whose missing labels are NaN in a Dataset
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

    def stats(self) -> BasinStats:
        """Its statistics (:func:`coincli.basin_stats`); damaged tiles count as not
        computed."""
        counts = BasinCounts()
        a = self.arrays
        counts.add(a["quarter_turns"], a["status"], a.get("certainty"))
        return BasinStats(counts, self.done, self.damaged, self.tile_seconds, self.runs)


def to_dataset(basin: Basin):
    """The Basin as an xarray Dataset: the variables of the schema on the two swept axes (cell
    centres as coordinates), ``done`` and ``tile_cpu_seconds`` per tile, every attribute."""
    import xarray as xr

    d0, d1 = basin.dims
    data_vars = {name: ((d0, d1), arr, dict(VARIABLES[name][2]))
                 for name, arr in basin.arrays.items()}
    if MASKED in data_vars:
        data_vars[MASKED] = ((d0, d1), *_masked(basin.arrays[MASKED], data_vars[MASKED][2]))
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
    ds = xr.Dataset(data_vars, coords=coords, attrs=encode_attrs(attrs))
    if MASKED in ds:  # written out as the store holds it: int16, -32768 where no label
        ds[MASKED].encoding = {"dtype": VARIABLES[MASKED][0],
                               "missing_value": np.int16(FILLS[MASKED])}
    return ds


def _masked(values: np.ndarray, attrs: dict) -> tuple[np.ndarray, dict]:
    """``quarter_turns`` as xarray decodes it from a store: float32, NaN where no label (its
    ``missing_value`` moves to the encoding, as xarray's decoding moves it)."""
    attrs = {k: v for k, v in attrs.items() if k != "missing_value"}
    attrs["description"] = attrs["description"].replace("-32768", "NaN (-32768 when written)")
    floats = np.where(values == FILLS[MASKED], np.nan, values).astype(np.float32)
    return floats, attrs


def encode_attrs(attrs: dict) -> dict:
    """Attributes NetCDF can hold: every value that is not a string or a number as JSON text,
    named in the attribute ``json_attributes``."""
    out, encoded = {}, []
    for key, value in attrs.items():
        if key == JSON_ATTRS:
            continue
        if isinstance(value, str) or (isinstance(value, numbers.Number)
                                      and not isinstance(value, bool)):
            out[key] = value
        else:
            out[key] = json.dumps(value, allow_nan=True)
            encoded.append(key)
    if encoded:
        out[JSON_ATTRS] = " ".join(encoded)
    return out


def decoded_attrs(ds) -> dict:
    """A basin Dataset's attributes with the values :func:`encode_attrs` wrote as JSON text
    decoded (nested attributes, as a store's ``xarray.open_zarr`` has them, are taken as they
    are): the one way every reader of a Dataset's attributes gets them."""
    if not hasattr(ds, "attrs") or not hasattr(ds, "data_vars"):
        raise TypeError(f"a basin must be an xarray Dataset (coincli.basin, coincli.open_basin) "
                        f"or a store's path, got {type(ds).__name__}")
    if MARK not in ds.attrs:
        raise ParameterError(f"not a coin basin dataset (no {MARK} attribute)")
    attrs = dict(ds.attrs)
    for key in str(attrs.pop(JSON_ATTRS, "")).split():
        if isinstance(attrs.get(key), str):
            try:
                attrs[key] = json.loads(attrs[key])
            except ValueError:
                raise ParameterError(f"attribute {key!r} of the basin Dataset is not the JSON "
                                     "text its json_attributes says") from None
    return attrs


def from_dataset(ds) -> Basin:
    """A Basin from a Dataset of :func:`to_dataset`, or from ``xarray.open_zarr`` of a store
    (whose masked float ``quarter_turns`` is turned back into int16 with its fill)."""
    ds_attrs = decoded_attrs(ds)
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
    attrs = {k: v for k, v in ds_attrs.items() if k not in ("runs", "store", "damaged_tiles")}
    basin = Basin(attrs=attrs, arrays=arrays, done=done, tile_seconds=seconds,
                  runs=list(ds_attrs.get("runs", [])), path=ds_attrs.get("store"),
                  damaged=[tuple(t) for t in ds_attrs.get("damaged_tiles", [])])
    basin.mask_not_done()
    return basin


__all__ = ["JSON_ATTRS", "Basin", "decoded_attrs", "encode_attrs", "from_dataset",
           "to_dataset"]
