"""The Zarr v3 store of `coin fractions`: the samples drawn and their labels, batch by batch,
resumable after Ctrl-C or ``kill -9``.

Layout (a plain run; a continuation adds a leading axis named after the parameter)::

    out.zarr/                     group; attributes: coin_fractions, version, parameters (the
                                  base scene; drawn initial conditions null), sampling (sampler,
                                  seed, batch, distributions), method (with its verification
                                  ladder), over (null, or parameter, values, keep, note)
      thickness   (thickness)     float64 the values of a continuation (only then)
      initial     ([value,] sample, ic)  float64 the initial state of every sample, columns
                                  y0, phi0, vx, vy, vphi (attribute ``columns``); x0 is the
                                  scene's
      quarter_turns ([value,] sample)  int16 n, fill -32768 = no label
      status      ([value,] sample)  uint8 (coincli.enums.Status), 255 not computed
      settle_time ([value,] sample)  float32 s
      steps       ([value,] sample)  int64, summed over the rungs run
      certainty   ([value,] sample)  uint8 (coincli.enums.Certainty), 255 not computed
      rung        ([value,] sample)  int8, the last rung of the ladder run
      filled      ([value,] batch)   uint32 samples of the batch written; written last
                                  (chunks of 1024 batches: only the coordinating process
                                  writes it, each chunk by an atomic rename)
    out.zarr.cost/runs.jsonl      beside the store: one line per invocation (wall time, CPU
                                  time, samples computed, threads or Dask)

Every per-sample array is chunked by batch (``sampling.batch`` samples; one value at a time),
so one batch is one chunk of each array. A batch counts only once its ``filled`` entry, written
after its data, says so; a batch cut off by ``kill -9`` is recomputed on resume, to the same
bytes. The coordinating process writes the batches in order (batches beyond the point where a
run stops are not kept), so the same command makes the same store, file for file, whether it
ran once, was interrupted and resumed, or ran on more threads. The sample axis is as long as
the largest budget asked for (whole batches); asking for more later lengthens it.
"""

from __future__ import annotations

import math
import os
import shutil
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..params import ParameterError
from .schema import VARIABLES
from .store import (
    check_is_store,
    cost_dir,
    flatten_attrs,
    is_store,
    read_runs,
    record_run,
    show_value,
)

FORMAT = 1
MARK = "coin_fractions"
COMPARED = ("version", "parameters", "sampling", "method", "over")
COLUMNS = ("y0", "phi0", "vx", "vy", "vphi")
LABELS = ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung")
FILLED_CHUNK = 1024  # batches a chunk of ``filled`` (only the coordinating process writes it)
FILLED_ATTRS = {"long_name": "samples of the batch written (written after them); the batch "
                             "counts only when this equals the samples it needs",
                "units": "1"}
INITIAL_ATTRS = {"long_name": "initial state of each sample", "columns": list(COLUMNS),
                 "units": ["m", "rad", "m/s", "m/s", "rad/s"]}


def _zarr():
    import zarr

    return zarr


@dataclass(frozen=True)
class Layout:
    """The shape of a store: ``values`` (None for a plain run) and whole batches of samples."""

    batch: int
    batches: int  # capacity, in batches
    values: int | None = None  # number of values of a continuation
    parameter: str | None = None

    @property
    def samples(self) -> int:
        return self.batch * self.batches

    def lead(self) -> tuple:
        return () if self.values is None else (self.values,)

    def lead_dims(self) -> tuple:
        return () if self.values is None else (self.parameter,)

    def lead_chunk(self) -> tuple:
        return () if self.values is None else (1,)

    def at(self, value: int) -> tuple:
        return () if self.values is None else (value,)


def differences(stored: dict, wanted: dict) -> list[str]:
    """'parameters.foundation.k = 10000 in the store, 5000 here', one per difference."""
    a = flatten_attrs({k: stored.get(k) for k in COMPARED})
    b = flatten_attrs({k: wanted.get(k) for k in COMPARED})
    for flat in (a, b):  # explanations, not what was computed
        for key in [k for k in flat if k.endswith((".note", ".sample_i"))]:
            del flat[key]
    out = []
    for key in sorted(set(a) | set(b)):
        if a.get(key, "absent") != b.get(key, "absent"):
            name = key.split(".", 1)[1] if key.startswith(("parameters.", "sampling.")) else key
            out.append(f"{name} = {show_value(a.get(key, 'absent'))} in the store, "
                       f"{show_value(b.get(key, 'absent'))} here")
    return out


def _consolidate(path: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "consolidated metadata is not part of the v3 spec"
        _zarr().consolidate_metadata(str(path))


def _create(path: Path, attrs: dict, layout: Layout, values: np.ndarray | None) -> None:
    zarr = _zarr()
    tmp = path.with_name(f".{path.name}.creating-{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp)
    group = zarr.open_group(str(tmp), mode="w-", zarr_format=3, attributes=attrs)
    lead, dims, chunk = layout.lead(), layout.lead_dims(), layout.lead_chunk()
    if values is not None:
        arr = group.create_array(layout.parameter, shape=(len(values),),
                                 chunks=(len(values),), dtype="float64", fill_value=0.0,
                                 dimension_names=(layout.parameter,),
                                 attributes={"long_name": f"the value of {layout.parameter}"})
        arr[:] = values
    group.create_array("initial", shape=(*lead, layout.samples, len(COLUMNS)),
                       chunks=(*chunk, layout.batch, len(COLUMNS)), dtype="float64",
                       fill_value=math.nan, dimension_names=(*dims, "sample", "ic"),
                       attributes=INITIAL_ATTRS, config={"write_empty_chunks": True})
    for name in LABELS:
        dtype, fill, array_attrs = VARIABLES[name]
        group.create_array(name, shape=(*lead, layout.samples), chunks=(*chunk, layout.batch),
                           dtype=dtype, fill_value=fill, dimension_names=(*dims, "sample"),
                           attributes=array_attrs, config={"write_empty_chunks": True})
    group.create_array("filled", shape=(*lead, layout.batches), chunks=(*chunk, FILLED_CHUNK),
                       dtype="uint32", fill_value=0, dimension_names=(*dims, "batch"),
                       attributes=FILLED_ATTRS)
    _consolidate(tmp)
    os.rename(tmp, path)
    shutil.rmtree(cost_dir(path), ignore_errors=True)
    cost_dir(path).mkdir()


def _grow(path: Path, layout: Layout) -> None:
    """Lengthen the sample axis to ``layout.batches`` batches (before any batch is written)."""
    group = _zarr().open_group(str(path), mode="r+")
    lead = layout.lead()
    group["initial"].resize((*lead, layout.samples, len(COLUMNS)))
    for name in LABELS:
        group[name].resize((*lead, layout.samples))
    group["filled"].resize((*lead, layout.batches))
    _consolidate(path)


def prepare(path, attrs: dict, layout: Layout, values: np.ndarray | None = None,
            overwrite: bool = False) -> np.ndarray:
    """Create the store, or open one holding the same sampling and parameters (lengthening its
    sample axis if this run may need more), and return its ``filled`` counts
    ([value,] batch). A store of anything else is refused in one line unless ``overwrite``."""
    zarr = _zarr()
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{path} exists and is not a directory")
    if path.is_dir() and not is_store(path):
        if any(path.iterdir()):
            raise ParameterError(f"{path} exists and is not a Zarr store: refusing to touch it")
        path.rmdir()
    if is_store(path):
        if overwrite:
            shutil.rmtree(path)
            shutil.rmtree(cost_dir(path), ignore_errors=True)
        else:
            group = zarr.open_group(str(path), mode="r")
            stored = dict(group.attrs)
            if MARK not in stored:
                raise ParameterError(f"{path} is a Zarr store but not of coin fractions; "
                                     "--overwrite replaces it")
            diff = differences(stored, attrs)
            if diff:
                raise ParameterError(f"{path} holds other samples: {'; '.join(diff[:4])}"
                                     f"{' ...' if len(diff) > 4 else ''}. Run again with the "
                                     "store's settings to resume it, or --overwrite to "
                                     "replace it")
            names = set(group.array_keys())
            missing = [n for n in ("initial", "filled", *LABELS) if n not in names]
            if missing:
                raise ParameterError(f"{path} is damaged: array '{missing[0]}' is missing; "
                                     "--overwrite starts it again")
            have = int(group["filled"].shape[-1])
            if tuple(group["filled"].shape[:-1]) != layout.lead() or \
                    tuple(group["initial"].chunks[-2:]) != (layout.batch, len(COLUMNS)):
                raise ParameterError(f"{path} is damaged: its arrays do not have the shape "
                                     "of its attributes; --overwrite starts it again")
            if layout.batches > have:
                _grow(path, layout)
            return np.asarray(zarr.open_group(str(path), mode="r")["filled"][:])
    path.parent.mkdir(parents=True, exist_ok=True)
    _create(path, attrs, layout, values)
    return np.zeros((*layout.lead(), layout.batches), dtype=np.uint32)


class Writer:
    """Writes batches into an open store (one group handle for the whole run)."""

    def __init__(self, path, layout: Layout):
        self.path = Path(path)
        self.layout = layout
        group = _zarr().open_group(str(path), mode="r+")
        self.arrays = {name: group[name].with_config({"write_empty_chunks": True})
                       for name in ("initial", "filled", *LABELS)}

    def write(self, value: int, batch: int, states: np.ndarray, labels: dict) -> None:
        """One batch's samples (``states``: N x 6) and labels, then its ``filled`` count."""
        count = states.shape[0]
        lo = batch * self.layout.batch
        at = self.layout.at(value)
        rows = (*at, slice(lo, lo + count))
        self.arrays["initial"][rows] = states[:, 1:]
        for name in LABELS:
            self.arrays[name][rows] = labels[name]
        self.arrays["filled"][(*at, slice(batch, batch + 1))] = count


def read_batches(path, layout: Layout, value: int, batches: list[int],
                 counts: list[int]) -> dict[int, dict]:
    """The labels of the given batches of one value, ``counts[i]`` samples of each (read in one
    slice per run of consecutive batches)."""
    if not batches:
        return {}
    group = _zarr().open_group(str(path), mode="r")
    at = layout.at(value)
    out: dict[int, dict] = {}
    start = 0
    while start < len(batches):
        end = start
        while end + 1 < len(batches) and batches[end + 1] == batches[end] + 1:
            end += 1
        lo = batches[start] * layout.batch
        hi = batches[end] * layout.batch + counts[end]
        block = {name: np.asarray(group[name][(*at, slice(lo, hi))])
                 for name in ("quarter_turns", "status", "certainty")}
        for i in range(start, end + 1):
            a = (batches[i] - batches[start]) * layout.batch
            out[batches[i]] = {name: arr[a:a + counts[i]] for name, arr in block.items()}
        start = end + 1
    return out


def read_initial(path, layout: Layout, value: int, batch: int, count: int) -> np.ndarray:
    """The stored initial states (y0, phi0, vx, vy, vphi) of one batch."""
    group = _zarr().open_group(str(path), mode="r")
    lo = batch * layout.batch
    return np.asarray(group["initial"][(*layout.at(value), slice(lo, lo + count))])


def run_record(started: float, wall: float, cpu: float, samples: int, mode: str, workers: int,
               interrupted: bool) -> dict:
    return {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(started)),
            "wall_seconds": round(wall, 3), "cpu_seconds": round(cpu, 3), "samples": samples,
            "mode": mode, "workers": workers, "interrupted": interrupted}


def open_fractions(path):
    """The store as an xarray Dataset (lazy; cells of batches not written hold the fills)."""
    import xarray as xr

    check_is_store(path)
    ds = xr.open_zarr(str(path))
    if MARK not in ds.attrs:
        raise ParameterError(f"{path} is not a coin fractions store")
    return ds


__all__ = ["COLUMNS", "LABELS", "Layout", "Writer", "cost_dir", "differences", "open_fractions",
           "prepare", "read_batches", "read_initial", "read_runs", "record_run", "run_record"]
