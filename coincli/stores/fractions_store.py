"""The Zarr v3 store of `coin fractions`, owned by one object (:class:`FractionsStore`): the
samples drawn and their labels, batch by batch, resumable after Ctrl-C or ``kill -9``. Written and
read through :mod:`coincli.stores.zarr_v3`, as basin stores are.

Layout (a plain run; a continuation adds a leading axis per parameter, named after it)::

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
      .coin/runs.jsonl            the store's records (as a basin store's: :func:`~coincli.
                                  stores.basin_layout.records_dir`): one line per invocation
                                  (wall time, CPU time, samples computed, threads or Dask)
      .coin/claims/               the batches being computed (:mod:`coincli.engines.claims`)
    .out.zarr.lock                beside the store: the creation lock (a store of 0.10.0 keeps
                                  its records beside it too, in out.zarr.cost/)

Every per-sample array is chunked by batch (``sampling.batch`` samples; one value at a time),
so one batch is one chunk of each array, and ``filled`` has one chunk a batch too: writers of
different batches (threads, Dask, other processes sharing the store through batch claims)
never touch the same file, and each chunk is written by an atomic rename. A batch counts only
once its ``filled`` entry, written after its data, says so; a batch cut off by ``kill -9`` is
recomputed on resume, to the same bytes. Every batch computed is written at once, so an
interrupted run keeps all its work; when a run's goal is met, the batches beyond the point where
its stop rule stopped are removed (:meth:`FractionsStore.trim`), so the same command makes the
same store, file for file, whether it ran once, was interrupted and resumed, or ran on more
threads or processes. The sample axis is as long as the largest budget asked for (whole
batches); asking for more later lengthens it. The store is created, checked and lengthened under
the creation lock, so that processes started together all open one store.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..montecarlo.plan import STORE_FORMAT
from ..params import ParameterError
from .basin_layout import (
    RECORDS,
    StoreRecords,
    check_is_store,
    check_store_writable,
    legacy_records_dir,
)
from .basin_metadata import FrictionWords, flatten_attrs, show_value, with_friction
from .basin_schema import VARIABLES, resumable_as
from .zarr_v3 import (
    ArraySpec,
    create_store,
    creation_lock,
    dig,
    encode_chunk,
    group_files,
    group_metadata,
    is_store,
    json_bytes,
    load_json,
    remove_partials,
    write_atomically,
)

FORMAT = STORE_FORMAT  # 2: ``filled`` in one chunk a batch (1: 1024 batches a chunk)
MARK = "coin_fractions"
COMPARED = ("version", "parameters", "sampling", "method", "over")
COLUMNS = ("y0", "phi0", "vx", "vy", "vphi")
LABELS = ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung")
FILLED_ATTRS = {"long_name": "samples of the batch written (written after them); the batch "
                             "counts only when this equals the samples it needs",
                "units": "1"}
INITIAL_ATTRS = {"long_name": "initial state of each sample", "columns": list(COLUMNS),
                 "units": ["m", "rad", "m/s", "m/s", "rad/s"]}


@dataclass(frozen=True)
class Layout:
    """The shape of a store: whole batches of samples, for each value of the parameters of a
    continuation (``values``: how many of each parameter, in ``parameters``; none for a plain
    run). A value is counted flat, the first parameter outermost."""

    batch: int
    batches: int  # capacity, in batches
    values: tuple[int, ...] = ()
    parameters: tuple[str, ...] = ()

    @property
    def samples(self) -> int:
        return self.batch * self.batches

    @property
    def n_values(self) -> int:
        return math.prod(self.values)

    def at(self, value: int) -> tuple[int, ...]:
        """The chunk index of ``value`` along the leading axes."""
        return tuple(int(i) for i in np.unravel_index(value, self.values)) if self.values \
            else ()

    def specs(self, values: list[np.ndarray] | None = None) -> dict[str, ArraySpec]:
        """Every array of a store of this layout."""
        lead, dims, ones = self.values, self.parameters, (1,) * len(self.values)
        specs = {name: ArraySpec(name, (n,), (n,), "float64", 0.0, (name,),
                                 {"long_name": f"the value of {name}"})
                 for name, n in zip(dims, lead, strict=True)}
        specs["initial"] = ArraySpec("initial", (*lead, self.samples, len(COLUMNS)),
                                     (*ones, self.batch, len(COLUMNS)), "float64", math.nan,
                                     (*dims, "sample", "ic"), INITIAL_ATTRS)
        for name in LABELS:
            dtype, fill, attrs = VARIABLES[name]
            specs[name] = ArraySpec(name, (*lead, self.samples), (*ones, self.batch), dtype,
                                    fill, (*dims, "sample"), attrs)
        specs["filled"] = ArraySpec("filled", (*lead, self.batches), (*ones, 1), "uint32", 0,
                                    (*dims, "batch"), FILLED_ATTRS)
        return specs


def _layout(plan) -> Layout:
    """The layout of a run of ``plan`` (a FractionsPlan)."""
    return Layout(plan.sampling.batch, plan.goal.batches(plan.sampling.batch), plan.shape,
                  plan.parameters)


ASKED = ("parameters.", "sampling.")  # what a run's options set, said first


def differences(stored: dict, wanted: dict) -> list[str]:
    """'parameters.foundation.k = 10000 in the store, 5000 here', one per difference."""
    a = flatten_attrs({k: stored.get(k) for k in COMPARED})
    b = flatten_attrs({k: wanted.get(k) for k in COMPARED})
    for flat in (a, b):  # explanations, not what was computed
        for key in [k for k in flat if k.endswith((".note", ".sample_i"))]:
            del flat[key]
    a, b = with_friction(a), with_friction(b)  # no mu recorded: mu = 0 (basin_metadata)
    said = FrictionWords(a, b, ("in the store", "here"))
    # what was asked first (the parameters, the sampling), then what follows from it; the
    # horizon is the scene's, said by the parameters when one of them differs
    keys = sorted(set(a) | set(b), key=lambda k: (not k.startswith(ASKED), k))
    parameters_differ = any(a.get(k, "absent") != b.get(k, "absent") for k in keys
                            if k.startswith("parameters."))
    out = []
    for key in keys:
        if said.skips(key) or (parameters_differ and key == "method.horizon"):
            continue
        if a.get(key, "absent") != b.get(key, "absent"):
            name = key.split(".", 1)[1] if key.startswith(ASKED) else key
            out.append(f"{name} = {show_value(a.get(key, 'absent'))} in the store, "
                       f"{show_value(b.get(key, 'absent'))} here{said.after(key)}")
    return out


class FractionsStore(StoreRecords):
    """The store of a Monte Carlo run at ``path``; :meth:`prepare` creates or opens it for a
    run of a layout, after which it reads and writes that run's batches."""

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        self.name = str(path)  # as the caller named it
        self.layout: Layout | None = None
        self.specs: dict[str, ArraySpec] = {}

    def __repr__(self) -> str:
        return f"FractionsStore({str(self.path)!r})"

    @classmethod
    def for_run(cls, path: str | os.PathLike) -> FractionsStore:
        """The store a run will write at ``path``, checked first: NotWritable (one line) unless
        it (or the folder it will be created in) and its records folder accept new files."""
        check_store_writable(path)
        store = cls(path)
        return store

    def prepare_run(self, plan, overwrite: bool = False) -> np.ndarray:
        """:meth:`prepare` for a run of ``plan`` (a FractionsPlan): its layout, attributes and
        parameter values."""
        return self.prepare(plan.attrs, _layout(plan), [np.asarray(a) for a in plan.axes] or None,
                            overwrite=overwrite)

    def check_run(self, plan) -> None:
        """Refuse now, in one line, what :meth:`prepare_run` would refuse without
        ``overwrite`` (a store of other samples, of another format, damaged, or a path that is
        no store), before a run's work (its pilot) begins; nothing is created or changed."""
        self._check_path()
        if is_store(self.path):
            with creation_lock(self.path):  # as prepare reads it: not while another grows it
                self._check_stored(plan.attrs, _layout(plan))

    def exists(self) -> bool:
        return is_store(self.path)

    # -- opening --------------------------------------------------------------------------------
    def attrs(self) -> dict:
        """The store's attributes, read now; ParameterError (one line) if there are none."""
        check_is_store(self.path)
        attrs = dig(load_json(self.path / "zarr.json"), "attributes")
        if not isinstance(attrs, dict):
            raise ParameterError(f"{self.path}: its metadata cannot be read: the store is "
                                 "damaged; overwrite starts it again",
                                 parameters=("overwrite",))
        return attrs

    @classmethod
    def open(cls, path: str | os.PathLike) -> FractionsStore:
        """An existing store, its layout read from its arrays (to read its batches, or trim
        them); ParameterError (one line) if it is none, or not one of coin fractions."""
        store = cls(path)
        if MARK not in store.attrs():
            raise ParameterError(f"{path} is not a coin fractions store")
        try:
            specs = store._read_specs()
            filled, initial = specs["filled"], specs["initial"]
        except (ValueError, KeyError) as exc:
            raise ParameterError(f"{path}: an array's metadata cannot be read ({exc}): the "
                                 "store is damaged; overwrite starts it again",
                                 parameters=("overwrite",)) from None
        store.layout = Layout(initial.chunks[-2], filled.shape[-1], filled.shape[:-1],
                              filled.dims[:-1])
        store.specs = specs
        return store

    def _read_specs(self) -> dict[str, ArraySpec]:
        """The arrays as the store's metadata describe them."""
        root = load_json(self.path / "zarr.json")
        listed = dig(root, "consolidated_metadata", "metadata") or {}
        specs = {}
        for name in listed:
            metadata = load_json(self.path / name / "zarr.json")
            if metadata is None:
                raise ValueError(f"array {name}: its metadata cannot be read")
            specs[name] = ArraySpec.of(name, metadata)
        return specs

    def prepare(self, attrs: dict, layout: Layout, values: list[np.ndarray] | None = None,
                overwrite: bool = False) -> np.ndarray:
        """Create the store, or open one holding the same sampling and parameters (lengthening
        its sample axis if this run may need more), and return its ``filled`` counts
        ([value,] batch). A store of anything else is refused in one line unless
        ``overwrite``. Several processes may call this at once on one path: one creates the
        store (under the creation lock), the others open it."""
        path = self.path
        self._check_path()
        path.parent.mkdir(parents=True, exist_ok=True)
        specs = layout.specs()
        if overwrite or not is_store(path):
            create_store(path, lambda: self._template(attrs, layout, values),
                         replace=overwrite, folders=(RECORDS,), side=legacy_records_dir(path))
        with creation_lock(path):
            self._check_stored(attrs, layout)
            if layout.batches > self._read_specs()["filled"].shape[-1]:
                self._grow(layout, specs)
        self.layout, self.specs = layout, specs
        self.records_dir.mkdir(exist_ok=True)
        return self.read_filled()

    def _check_path(self) -> None:
        """Refuse a path that is a file, or a folder with files that is no Zarr store."""
        path = self.path
        if path.exists() and not path.is_dir():
            raise ParameterError(f"{path} exists and is not a directory")
        if path.is_dir() and not is_store(path) and any(path.iterdir()):
            raise ParameterError(f"{path} exists and is not a Zarr store: refusing to touch it")

    @staticmethod
    def _template(attrs: dict, layout: Layout, values) -> dict[str, bytes]:
        specs = layout.specs()
        files = group_files(attrs, list(specs.values()))
        for name, column in zip(layout.parameters, values or (), strict=False):
            spec = specs[name]
            files[spec.key((0,))] = encode_chunk(np.asarray(column, dtype=np.float64),
                                                 spec.dtype, spec.fill, spec.chunks)
        return files

    def _check_stored(self, attrs: dict, layout: Layout) -> None:
        """Refuse, in one line, a store of anything but these samples, or one whose arrays do
        not have the layout its attributes describe."""
        path = self.path
        stored = dig(load_json(path / "zarr.json"), "attributes")
        if not isinstance(stored, dict):
            raise ParameterError(f"{path}: its metadata cannot be read: the store is damaged; "
                                 "overwrite starts it again", parameters=("overwrite",))
        if MARK not in stored:
            raise ParameterError(f"{path} is a Zarr store but not of coin fractions; "
                                 "overwrite replaces it", parameters=("overwrite",))
        fmt = stored[MARK].get("format") if isinstance(stored[MARK], dict) else None
        if isinstance(fmt, int) and fmt > FORMAT:  # its data are good: never advised away
            raise ParameterError(f"{path} was written by a newer coin: a fractions store of "
                                 f"format {fmt}, where this version writes format {FORMAT}; "
                                 "upgrade coincli to use it (pip install --upgrade coincli)")
        if fmt != FORMAT:
            raise ParameterError(f"{path} is a coin fractions store of format {fmt}, this "
                                 f"version writes format {FORMAT}: overwrite starts it again",
                                 parameters=("overwrite",))
        earlier = resumable_as(stored, attrs)  # a store of an earlier version: resumed as is
        diff = differences(stored, attrs if earlier is None else earlier)
        if diff:
            raise ParameterError(f"{path} holds other samples: {'; '.join(diff[:4])}"
                                 f"{' ...' if len(diff) > 4 else ''}. Run again with the "
                                 "store's settings to resume it, or overwrite to "
                                 "replace it", parameters=("overwrite",))
        try:
            found = self._read_specs()
        except ValueError as exc:  # an array's metadata that does not parse
            raise ParameterError(f"{path}: an array's metadata cannot be read ({exc}): the "
                                 "store is damaged; overwrite starts it again",
                                 parameters=("overwrite",)) from None
        missing = [n for n in ("initial", "filled", *LABELS) if n not in found]
        if missing:
            raise ParameterError(f"{path} is damaged: array '{missing[0]}' is missing; "
                                 "overwrite starts it again", parameters=("overwrite",))
        want = layout.specs()
        if (found["filled"].shape[:-1] != layout.values or found["filled"].chunks[-1] != 1
                or found["initial"].chunks[-2:] != want["initial"].chunks[-2:]):
            raise ParameterError(f"{path} is damaged: its arrays do not have the shape "
                                 "of its attributes; overwrite starts it again",
                                 parameters=("overwrite",))

    def _grow(self, layout: Layout, specs: dict[str, ArraySpec]) -> None:
        """Lengthen the sample axis to ``layout.batches`` batches (call with the creation lock
        held): each array's metadata, then the group's."""
        root = load_json(self.path / "zarr.json")
        metadata = dict(dig(root, "consolidated_metadata", "metadata") or {})
        for name in ("initial", *LABELS, "filled"):
            document = load_json(self.path / name / "zarr.json")
            document["shape"] = list(specs[name].shape)
            write_atomically(self.path / name / "zarr.json", json_bytes(document))
            metadata[name] = document
        write_atomically(self.path / "zarr.json",
                         json_bytes(group_metadata(root["attributes"], metadata)))

    # -- reading and writing batches -----------------------------------------------------------
    def _files(self, value: int, batch: int) -> list[Path]:
        """The files of one batch, ``filled`` first."""
        at = self.layout.at(value)
        return [self.specs["filled"].file(self.path, (*at, batch)),
                self.specs["initial"].file(self.path, (*at, batch, 0)),
                *(self.specs[name].file(self.path, (*at, batch)) for name in LABELS)]

    def read_filled(self) -> np.ndarray:
        """The ``filled`` count of every batch ([value,] batch), read now; 0 for a batch whose
        ``filled`` chunk does not read back (damaged: the batch is computed again)."""
        spec = self._read_specs()["filled"]
        out = np.zeros(spec.shape, dtype=np.uint32)
        for index in np.ndindex(*spec.shape):
            with contextlib.suppress(FileNotFoundError, OSError, ValueError):
                out[index] = spec.read(self.path, index).reshape(-1)[0]
        return out

    def batch_written(self, value: int, batch: int) -> bool:
        """Whether a batch's ``filled`` chunk exists (one stat): written last, after all its
        data, so one that appears while a run waits for it means another process finished
        the batch."""
        return self._files(value, batch)[0].is_file()

    def filled_count(self, value: int, batch: int) -> int:
        """One batch's ``filled`` count, read now (0 if its chunk does not read back)."""
        try:
            block = self.specs["filled"].read(self.path, (*self.layout.at(value), batch))
            return int(block.reshape(-1)[0])
        except (OSError, ValueError):  # damaged: the batch counts as not written
            return 0

    def _remove_partials(self, value: int, batch: int) -> None:
        """Temporary files of this batch's chunks left by a writer that died (only the owner
        of a batch's claim writes it, so any such file is an orphan)."""
        for f in self._files(value, batch):
            remove_partials(f)

    def write_batch(self, value: int, batch: int, states: np.ndarray, labels: dict) -> None:
        """One batch's samples (``states``: N x 6) and labels, then its ``filled`` count."""
        self._remove_partials(value, batch)
        at = self.layout.at(value)
        lead = (1,) * len(at)
        self.specs["initial"].write(self.path, (*at, batch, 0),
                                    states[:, 1:].reshape(*lead, *states[:, 1:].shape))
        for name in LABELS:
            block = np.asarray(labels[name])
            self.specs[name].write(self.path, (*at, batch), block.reshape(*lead, block.size))
        self.specs["filled"].write(self.path, (*at, batch),
                                   np.full((*lead, 1), states.shape[0], dtype=np.uint32))

    def read_batches(self, value: int, batches: list[int],
                     counts: list[int]) -> tuple[dict[int, dict], list[int]]:
        """The labels of the given batches of one value, ``counts[i]`` samples of each, and the
        batches that do not read back (a chunk of any of their arrays missing or damaged)."""
        at = self.layout.at(value)
        out: dict[int, dict] = {}
        damaged = []
        for batch, count in zip(batches, counts, strict=True):
            try:  # every chunk of the batch: one damaged is the batch's damage
                block = {name: self.specs[name].read(self.path, (*at, batch)).reshape(-1)[:count]
                         for name in LABELS}
                initial = self.specs["initial"].read(self.path, (*at, batch, 0))
            except (OSError, ValueError):  # missing (FileNotFoundError), or damaged
                damaged.append(batch)
                continue
            rows = initial.reshape(-1, len(COLUMNS))[:count]
            if np.isnan(rows).all(axis=-1).any() or \
                    (block["status"] == VARIABLES["status"][1]).any():
                damaged.append(batch)  # samples never written
                continue
            out[batch] = {name: block[name] for name in ("quarter_turns", "status", "certainty")}
        return out, damaged

    def read_initial(self, value: int, batch: int, count: int) -> np.ndarray:
        """The stored initial states (y0, phi0, vx, vy, vphi) of one batch."""
        block = self.specs["initial"].read(self.path, (*self.layout.at(value), batch, 0))
        return block.reshape(-1, len(COLUMNS))[:count]

    def trim(self, value: int, keep: int,
             held: Callable[[int, int], bool] | None = None) -> int:
        """Remove the batches from ``keep`` on of one value (its ``filled`` chunk first, so that
        a batch cut off midway counts as not written): those a run computed beyond the point
        where its stop rule stopped; not those ``held(value, batch)`` says another process is
        writing. The number removed."""
        removed = 0
        for batch in range(keep, self.layout.batches):
            if held is not None and held(value, batch):
                continue
            self._remove_partials(value, batch)
            files = self._files(value, batch)
            if not any(f.exists() for f in files):
                continue
            for f in files:
                with contextlib.suppress(FileNotFoundError):
                    f.unlink()
            removed += 1
        return removed

    def held_samples(self, plan) -> list[int] | None:
        """The samples of the run of ``plan`` this store holds, per value (None if it holds
        another run): those of the batches the run can use that are whole in the store (a
        batch missing or cut short is to compute, whatever the store holds beyond the run)."""
        try:
            filled = self.read_filled()
            stored = self.attrs()
        except Exception:  # noqa: BLE001 - an unreadable store is the run's to report
            return None
        earlier = resumable_as(stored, plan.attrs)
        if differences(stored, plan.attrs if earlier is None else earlier):
            return None
        rows = filled.reshape(len(plan.scenes), -1)
        goal, batch = plan.goal, plan.sampling.batch
        uses = [goal.count(b, batch) for b in range(goal.batches(batch))]
        return [sum(n for n, held in zip(uses, row, strict=False) if held >= n)
                for row in rows]

    def dataset(self):
        """The store as an xarray Dataset, in memory: ``initial`` ([value,] sample, ic) and the
        labels ([value,] sample); batches not written hold the fill values (``filled`` says
        which are)."""
        import xarray as xr

        attrs = self.attrs()
        if MARK not in attrs:
            raise ParameterError(f"{self.path} is not a coin fractions store")
        specs = self._read_specs()
        variables, coords = {}, {}
        for name, spec in specs.items():
            values = np.full(spec.shape, spec.fill, dtype=spec.dtype)
            grid = [math.ceil(n / c) for n, c in zip(spec.shape, spec.chunks, strict=True)]
            for index in np.ndindex(*grid):
                with contextlib.suppress(FileNotFoundError):
                    block = spec.read(self.path, index)
                    where = tuple(slice(i * c, i * c + b) for i, c, b
                                  in zip(index, spec.chunks, block.shape, strict=True))
                    values[where] = block
            variable = xr.Variable(spec.dims, values, attrs=spec.attributes)
            if spec.dims == (name,):
                coords[name] = variable
            else:
                variables[name] = variable
        # decoded as xarray.open_zarr decodes them: labels with a missing_value as NaN
        return xr.decode_cf(xr.Dataset(variables, coords=coords,
                                       attrs=json.loads(json.dumps(attrs))))


def open_fractions(path) -> object:
    """A `coin fractions` store as an xarray Dataset (:meth:`FractionsStore.dataset`)."""
    check_is_store(path)
    return FractionsStore(path).dataset()


__all__ = ["COLUMNS", "FORMAT", "FractionsStore", "LABELS", "Layout", "MARK", "differences",
           "open_fractions"]
