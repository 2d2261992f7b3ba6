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
                                  (one chunk a batch, so writers never share a file)
    out.zarr.cost/runs.jsonl      beside the store: one line per invocation (wall time, CPU
                                  time, samples computed, threads or Dask)
    out.zarr.cost/claims/         the batches being computed (:mod:`coincli.io.claims`)

Every per-sample array is chunked by batch (``sampling.batch`` samples; one value at a time),
so one batch is one chunk of each array, and ``filled`` has one chunk a batch too: writers of
different batches (threads, Dask, other processes sharing the store through batch claims)
never touch the same file, and Zarr writes each chunk by an atomic rename. A batch counts only
once its ``filled`` entry, written after its data, says so; a batch cut off by ``kill -9`` is
recomputed on resume, to the same bytes. Every batch computed is written at once, so an
interrupted run keeps all its work; when a run's goal is met, the batches beyond the point where
its stop rule stopped are removed (:func:`trim`), so the same command makes the same store,
file for file, whether it ran once, was interrupted and resumed, or ran on more threads or
processes. The sample axis is as long as the largest budget asked for (whole batches); asking
for more later lengthens it. The store is created, checked and lengthened under the creation
lock that basin stores use, so that processes started together all open one store.
"""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..montecarlo.plan import STORE_FORMAT
from ..params import ParameterError
from .schema import VARIABLES
from .store import (
    ZSTD_LEVEL,
    check_is_store,
    claims_dir,
    cost_dir,
    creating_name,
    creation_lock,
    flatten_attrs,
    is_store,
    read_runs,
    record_run,
    remove_orphans,
    show_value,
)

FORMAT = STORE_FORMAT  # 2: ``filled`` in one chunk a batch (1: 1024 batches a chunk)
MARK = "coin_fractions"
COMPARED = ("version", "parameters", "sampling", "method", "over")
COLUMNS = ("y0", "phi0", "vx", "vy", "vphi")
READ_RUN = 64  # batches read in one slice (every array: about 30 MB at the default batch)
LABELS = ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung")
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


def _compressors() -> list:
    """Every array's codecs after ``bytes``: zstd, then a CRC-32C of the compressed chunk (as
    basin stores), so that a chunk damaged on disk fails to read instead of decoding to other
    labels."""
    from zarr.codecs import Crc32cCodec, ZstdCodec

    return [ZstdCodec(level=ZSTD_LEVEL, checksum=False), Crc32cCodec()]


def _create(path: Path, attrs: dict, layout: Layout, values: np.ndarray | None) -> None:
    """Create the store in a temporary directory beside it and rename it into place (call with
    the creation lock held)."""
    zarr = _zarr()
    remove_orphans(path)  # creations that died
    tmp = path.with_name(creating_name(path))
    group = zarr.open_group(str(tmp), mode="w-", zarr_format=3, attributes=attrs)
    lead, dims, chunk = layout.lead(), layout.lead_dims(), layout.lead_chunk()
    if values is not None:
        arr = group.create_array(layout.parameter, shape=(len(values),),
                                 chunks=(len(values),), dtype="float64", fill_value=0.0,
                                 dimension_names=(layout.parameter,),
                                 attributes={"long_name": f"the value of {layout.parameter}"},
                                 compressors=_compressors())
        arr[:] = values
    group.create_array("initial", shape=(*lead, layout.samples, len(COLUMNS)),
                       chunks=(*chunk, layout.batch, len(COLUMNS)), dtype="float64",
                       fill_value=math.nan, dimension_names=(*dims, "sample", "ic"),
                       attributes=INITIAL_ATTRS, config={"write_empty_chunks": True},
                       compressors=_compressors())
    for name in LABELS:
        dtype, fill, array_attrs = VARIABLES[name]
        group.create_array(name, shape=(*lead, layout.samples), chunks=(*chunk, layout.batch),
                           dtype=dtype, fill_value=fill, dimension_names=(*dims, "sample"),
                           attributes=array_attrs, config={"write_empty_chunks": True},
                           compressors=_compressors())
    group.create_array("filled", shape=(*lead, layout.batches), chunks=(*chunk, 1),
                       dtype="uint32", fill_value=0, dimension_names=(*dims, "batch"),
                       attributes=FILLED_ATTRS, compressors=_compressors())
    _consolidate(tmp)
    shutil.rmtree(cost_dir(path), ignore_errors=True)  # the records of an older store
    os.rename(tmp, path)
    cost_dir(path).mkdir(exist_ok=True)


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
    ([value,] batch). A store of anything else is refused in one line unless ``overwrite``.
    Several processes may call this at once on one path: one creates the store (under the
    creation lock), the others open it."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{path} exists and is not a directory")
    if path.is_dir() and not is_store(path) and any(path.iterdir()):
        raise ParameterError(f"{path} exists and is not a Zarr store: refusing to touch it")
    path.parent.mkdir(parents=True, exist_ok=True)
    with creation_lock(path):
        if is_store(path) and overwrite:
            shutil.rmtree(path)
            shutil.rmtree(cost_dir(path), ignore_errors=True)
        if not is_store(path):
            if path.is_dir():  # empty
                path.rmdir()
            _create(path, attrs, layout, values)
            return np.zeros((*layout.lead(), layout.batches), dtype=np.uint32)
        _check_stored(path, attrs, layout)
        if layout.batches > int(_zarr().open_group(str(path), mode="r")["filled"].shape[-1]):
            _grow(path, layout)
    cost_dir(path).mkdir(exist_ok=True)
    return read_filled(path)


def _check_stored(path: Path, attrs: dict, layout: Layout) -> None:
    """Refuse, in one line, a store of anything but these samples, or one whose arrays do not
    have the layout its attributes describe."""
    try:
        group = _zarr().open_group(str(path), mode="r")
        stored = dict(group.attrs)
    except Exception as exc:  # noqa: BLE001 - any failure to parse is damage
        raise ParameterError(f"{path}: its metadata cannot be read ({type(exc).__name__}): the "
                             "store is damaged; overwrite starts it again",
                             parameters=("overwrite",)) from None
    if MARK not in stored:
        raise ParameterError(f"{path} is a Zarr store but not of coin fractions; "
                             "overwrite replaces it", parameters=("overwrite",))
    fmt = stored[MARK].get("format") if isinstance(stored[MARK], dict) else None
    if fmt != FORMAT:
        raise ParameterError(f"{path} is a coin fractions store of format {fmt}, this version "
                             f"writes format {FORMAT}: overwrite starts it again",
                             parameters=("overwrite",))
    diff = differences(stored, attrs)
    if diff:
        raise ParameterError(f"{path} holds other samples: {'; '.join(diff[:4])}"
                             f"{' ...' if len(diff) > 4 else ''}. Run again with the "
                             "store's settings to resume it, or overwrite to "
                             "replace it", parameters=("overwrite",))
    try:
        names = set(group.array_keys())
        missing = [n for n in ("initial", "filled", *LABELS) if n not in names]
        shapes_fit = not missing and (
            tuple(group["filled"].shape[:-1]) == layout.lead()
            and group["filled"].chunks[-1] == 1
            and tuple(group["initial"].chunks[-2:]) == (layout.batch, len(COLUMNS)))
    except Exception as exc:  # noqa: BLE001 - an array's metadata that does not parse
        raise ParameterError(f"{path}: an array's metadata cannot be read "
                             f"({type(exc).__name__}): the store is damaged; overwrite "
                             "starts it again", parameters=("overwrite",)) from None
    if missing:
        raise ParameterError(f"{path} is damaged: array '{missing[0]}' is missing; "
                             "overwrite starts it again", parameters=("overwrite",))
    if not shapes_fit:
        raise ParameterError(f"{path} is damaged: its arrays do not have the shape "
                             "of its attributes; overwrite starts it again",
                             parameters=("overwrite",))


def open_attrs(path) -> dict:
    """The store's attributes."""
    return dict(_zarr().open_group(str(path), mode="r").attrs)


def read_filled(path) -> np.ndarray:
    """The ``filled`` counts of every batch ([value,] batch), read now; 0 for a batch whose
    ``filled`` chunk does not read back (damaged: the batch is computed again)."""
    filled = _zarr().open_group(str(path), mode="r")["filled"]
    try:
        return np.asarray(filled[:])
    except Exception:  # noqa: BLE001 - a damaged chunk: read them one by one
        out = np.zeros(filled.shape, dtype=np.uint32)
        for index in np.ndindex(*filled.shape):
            with contextlib.suppress(Exception):
                out[index] = filled[index]
        return out


def _chunk_files(path: Path, layout: Layout, value: int, batch: int) -> list[Path]:
    """The files of one batch, ``filled`` first (chunk keys as Zarr v3 names them by default:
    ``NAME/c/I/J``)."""
    at = [str(i) for i in layout.at(value)]
    return [path.joinpath("filled", "c", *at, str(batch)),
            path.joinpath("initial", "c", *at, str(batch), "0"),
            *(path.joinpath(name, "c", *at, str(batch)) for name in LABELS)]


def batch_written(path, layout: Layout, value: int, batch: int) -> bool:
    """Whether a batch's ``filled`` chunk exists (one stat): written last, after all its data,
    so one that appears while a run waits for it means another process finished the batch."""
    return _chunk_files(Path(path), layout, value, batch)[0].is_file()


def filled_count(path, layout: Layout, value: int, batch: int) -> int:
    """One batch's ``filled`` count, read now (0 if its chunk does not read back)."""
    try:
        filled = _zarr().open_group(str(path), mode="r")["filled"]
        return int(filled[(*layout.at(value), batch)])
    except Exception:  # noqa: BLE001 - damaged: the batch counts as not written
        return 0


def trim(path, layout: Layout, value: int, keep: int,
         held: Callable[[int, int], bool] | None = None) -> int:
    """Remove the batches from ``keep`` on of one value (its ``filled`` chunk first, so that a
    batch cut off midway counts as not written): those a run computed beyond the point where
    its stop rule stopped; not those ``held(value, batch)`` says another process is writing.
    The number removed."""
    path = Path(path)
    removed = 0
    for batch in range(keep, layout.batches):
        if held is not None and held(value, batch):
            continue
        files = _chunk_files(path, layout, value, batch)
        if not any(f.exists() for f in files):
            continue
        for f in files:
            with contextlib.suppress(FileNotFoundError):
                f.unlink()
        removed += 1
    return removed


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
                 counts: list[int]) -> tuple[dict[int, dict], list[int]]:
    """The labels of the given batches of one value, ``counts[i]`` samples of each, and the
    batches that do not read back (a chunk of any of their arrays damaged: their checksum
    fails, or a chunk is missing). Read in one slice per run of consecutive batches, batch by
    batch where a run fails."""
    if not batches:
        return {}, []
    group = _zarr().open_group(str(path), mode="r")
    at = layout.at(value)
    out: dict[int, dict] = {}

    def read(first: int, last: int) -> dict:
        lo = batches[first] * layout.batch
        hi = batches[last] * layout.batch + counts[last]
        block = {name: np.asarray(group[name][(*at, slice(lo, hi))])
                 for name in ("initial", *LABELS)}
        written = batches[last] - batches[first] + 1  # whole batches: none reads as the fill
        if np.isnan(block["initial"]).all(axis=-1).sum() > 0 or \
                (block["status"] == VARIABLES["status"][1]).sum() > 0:
            raise ValueError(f"{written} batch(es) hold samples never written")
        return block

    whole = [all(f.is_file() for f in _chunk_files(Path(path), layout, value, index))
             for index in batches]  # a missing chunk would read back as fill values
    damaged = [index for index, ok in zip(batches, whole, strict=True) if not ok]
    counts = [c for c, ok in zip(counts, whole, strict=True) if ok]
    batches = [index for index, ok in zip(batches, whole, strict=True) if ok]
    start = 0
    while start < len(batches):
        end = start
        while end + 1 < len(batches) and batches[end + 1] == batches[end] + 1 and \
                end - start + 1 < READ_RUN:
            end += 1
        try:
            runs = [(start, end, read(start, end))]
        except Exception:  # noqa: BLE001 - some chunk of the run is damaged: batch by batch
            runs = []
            for i in range(start, end + 1):
                try:
                    runs.append((i, i, read(i, i)))
                except Exception:  # noqa: BLE001
                    damaged.append(batches[i])
        for first, last, block in runs:
            for i in range(first, last + 1):
                a = (batches[i] - batches[first]) * layout.batch
                out[batches[i]] = {name: block[name][a:a + counts[i]]
                                   for name in ("quarter_turns", "status", "certainty")}
        start = end + 1
    return out, damaged


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


__all__ = ["COLUMNS", "LABELS", "Layout", "Writer", "batch_written", "claims_dir", "cost_dir",
           "differences", "filled_count", "open_attrs", "open_fractions", "prepare",
           "read_batches", "read_filled", "read_initial", "read_runs", "record_run", "run_record",
           "trim"]
