"""A basin written out for other tools: NetCDF-4 (the Dataset of :func:`.dataset.to_dataset`,
every variable and attribute, reopened by ``xarray.open_dataset`` or ``coincli.open_basin``)
or CSV (one row per cell, header names with units, empty fields where a value is missing).
Written through a temporary file: an export is complete or absent. A NetCDF file is made in
memory first and then written by this module: HDF5 (h5py, beneath h5netcdf) does not survive
a write that fails on a full disk (it crashes the interpreter), a plain write raises OSError."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from ..enums import Certainty, Status
from ..files import atomic_output
from ..integrators import NO_LABEL
from ..params import ParameterError
from ..stores.dataset import Basin, from_dataset, to_dataset

FORMATS = (".nc", ".csv")
COMPRESSION = {"zlib": True, "complevel": 4}  # NetCDF-4 chunked and deflated: maps compress well
CSV_BLOCK = 64  # rows of the first axis formatted at a time (memory stays flat)


def check_export_path(path: str | os.PathLike) -> Path:
    """``path`` as a Path, or ParameterError unless it ends in .nc or .csv."""
    path = Path(path)
    if path.suffix.lower() not in FORMATS:
        raise ParameterError(f"{path}: the export's file name must end in .nc (NetCDF-4) or "
                             ".csv")
    return path


def export_basin(basin: Basin, path: str | os.PathLike) -> Path:
    """Write ``basin`` to ``path``, NetCDF-4 or CSV by its suffix (an existing file is
    replaced, as a figure is); returns the path."""
    path = check_export_path(path)
    write = write_netcdf if path.suffix.lower() == ".nc" else write_csv
    with atomic_output(path) as tmp:
        write(basin, tmp)
    return path


def write_netcdf(basin: Basin, path: Path) -> None:
    try:
        import h5py  # noqa: F401 - h5netcdf's backend, which it does not install itself
    except ImportError:
        raise ParameterError("writing NetCDF needs the package h5py (pip install h5py)") from None
    ds = to_dataset(basin)
    encoding = {name: {**ds[name].encoding, **COMPRESSION} for name in ds.data_vars}
    # into memory (no path: a memoryview), then one plain write: h5py writing to a full disk
    # prints tracebacks from its destructors and crashes the interpreter (SIGSEGV), where a
    # write of ours raises OSError (ENOSPC) and leaves nothing behind (atomic_output)
    data = ds.to_netcdf(engine="h5netcdf", encoding=encoding)
    with open(path, "wb") as fh:
        fh.write(data)


def open_export(path: str | os.PathLike):
    """The Dataset of a NetCDF file (in memory, the file closed); ParameterError for a file
    xarray cannot read."""
    import xarray as xr

    try:
        with xr.open_dataset(path, engine="h5netcdf") as ds:
            return ds.load()
    except (OSError, ValueError) as exc:
        raise ParameterError(f"{path}: not a basin store or a NetCDF export of one "
                             f"({str(exc).splitlines()[0][:120]})") from None


def read_export(path: str | os.PathLike) -> Basin:
    """The Basin of a NetCDF file written by :func:`export_basin`."""
    basin = from_dataset(open_export(path))
    basin.path = None  # the export is no store: nothing to resume
    return basin


def csv_header(basin: Basin) -> list[str]:
    """The column names, units in brackets."""
    axes = [f"{a['name']} [{a['units']}]" for a in basin.axes]
    return [*axes, "n [quarter turns]", "pose", "status", "certainty", "settle_time [s]",
            "steps", "rung"]


def write_csv(basin: Basin, path: Path) -> None:
    """One row per cell, the first swept axis outermost; a cell without a label has empty n
    and pose, a value not computed an empty field."""
    a = basin.arrays
    x, y = basin.coords
    status_words = _words(Status, a["status"])
    certainty_words = _words(Certainty, a["certainty"])
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(csv_header(basin))
        y_text = np.array([repr(float(v)) for v in y])
        for start in range(0, x.size, CSV_BLOCK):
            rows = slice(start, min(start + CSV_BLOCK, x.size))
            q = a["quarter_turns"][rows]
            n = np.where(q == NO_LABEL, "", q.astype(str))
            pose = np.where(q == NO_LABEL, "", np.where(q % 2 == 1, "standing", "lying"))
            t = a["settle_time"][rows]
            settle = np.where(np.isnan(t), "", t.astype(str))
            steps = _ints(a["steps"][rows])
            rung = _ints(a["rung"][rows])
            xs = np.repeat(np.array([repr(float(v)) for v in x[rows]]), y.size)
            ys = np.tile(y_text, rows.stop - rows.start)
            columns = (xs, ys, n, pose, status_words[rows], certainty_words[rows], settle,
                       steps, rung)
            # plain str lists: the csv module writes them several times faster than numpy's
            writer.writerows(zip(*(c.ravel().tolist() for c in columns), strict=True))


def _ints(values: np.ndarray) -> np.ndarray:
    return np.where(values < 0, "", values.astype(str))


def _words(enum, codes: np.ndarray) -> np.ndarray:
    """The label of each code (a code no member has: its number)."""
    out = codes.astype(str).astype(object)
    for member in enum:
        out[codes == member] = member.label
    return out


__all__ = ["FORMATS", "check_export_path", "csv_header", "export_basin", "open_export",
           "read_export"]
