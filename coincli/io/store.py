"""The Zarr v3 store of a basin sweep: create or resume it, write one tile, read it back.

Layout (dims named after the two swept initial conditions, e.g. ``vy`` and ``vphi``)::

    out.zarr/                       group; attributes: coin_basin, version, parameters, sweep,
                                    method, certify
      vy, vphi                      float64 cell centres, linspace(LO, HI, n)
      quarter_turns  (vy, vphi)     int16, fill -32768 = no label (not computed or non-finite)
      status         (vy, vphi)     uint8, 0 settled, 1 unsettled at t_end, 2 non-finite,
                                    255 not computed
      settle_time    (vy, vphi)     float32 [s], NaN fill (also NaN when never settled)
      steps          (vy, vphi)     int64 integrator steps (cost), fill -1
      uncertain      (vy, vphi)     uint8, only with --certify: 0 certain, 1 uncertain,
                                    255 not computed
      done           (tile_vy, tile_vphi)  uint8, 1 = the tile is complete; chunked (1, 1)
    out.zarr.cost/                  what the sweep cost, kept beside the store so that the store
      tile_I_J.json                 itself is bit-identical however it was computed: each tile's
      runs.jsonl                    CPU seconds (written by whoever computed it, before its
                                    ``done`` flag) and one line per invocation (wall time, mode)

Every data array is chunked exactly like the tiles, so one tile is one chunk in every array and
concurrent writers (threads, Dask workers) never touch the same file. A tile's ``done`` flag is
written after all its data, so a tile is either complete and flagged, or recomputed on resume
(recomputing gives the same bytes). Chunks are written through Zarr's LocalStore (plain paths:
write to a temporary file, then rename), with ``write_empty_chunks`` on so that a tile equal to
the fill value is still written. The store is created in a temporary directory and renamed into
place, and its metadata consolidated once at creation: nothing in the store's metadata changes
afterwards, so ``xarray.open_zarr(path)`` opens it directly. ``quarter_turns`` carries
``missing_value`` so xarray masks cells without a label to NaN (``mask_and_scale=False`` keeps
the int16 values).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import threading
import time
import warnings
from pathlib import Path

import numpy as np

from ..grid import SweepSpec, TileResult
from ..params import ParameterError
from .dataset import Basin
from .schema import COMPARED_ATTRS, COORD_NOTE, DONE_ATTRS, VARIABLES, tile_dims


def _zarr():
    import zarr

    return zarr


def _is_store(path: Path) -> bool:
    return (path / "zarr.json").is_file()


def _flatten(value, prefix: str = "") -> dict:
    """Nested attribute dicts -> {'parameters.foundation.k': 1e4, 'sweep.axes.vy.lo': 0.05}."""
    if isinstance(value, dict):
        out = {}
        for key, sub in value.items():
            out.update(_flatten(sub, f"{prefix}.{key}" if prefix else str(key)))
        return out
    if isinstance(value, list) and value and all(isinstance(v, dict) and "name" in v
                                                for v in value):
        out = {}
        for sub in value:
            out.update(_flatten({k: v for k, v in sub.items() if k != "name"},
                                f"{prefix}.{sub['name']}"))
        return out
    if isinstance(value, list):
        return {prefix: json.dumps(value)}
    return {prefix: value}


def _display_name(key: str) -> str:
    parts = key.split(".")
    if parts[0] == "parameters":
        return parts[-1]
    if parts[0] == "sweep" and parts[1] == "axes" and len(parts) == 4:
        return f"--{parts[2]} {'LO' if parts[3] == 'lo' else 'HI' if parts[3] == 'hi' else 'cells'}"
    if parts[0] == "sweep":
        return {"dims": "swept axes", "chunk": "--chunk", "fixed": "fixed initial value"}.get(
            parts[1], parts[1]) + (f" {parts[2]}" if len(parts) > 2 else "")
    if parts[0] == "method":
        return "method" if parts[1] == "name" else parts[1]
    if parts[0] == "version":
        return "coincli version"
    return key


def _show(value) -> str:
    if value is None:
        return "none"
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


def differences(stored: dict, wanted: dict) -> list[str]:
    """One phrase per differing parameter: 'k = 10000 in the store, 5000 here'."""
    a = _flatten({k: stored.get(k) for k in COMPARED_ATTRS})
    b = _flatten({k: wanted.get(k) for k in COMPARED_ATTRS})
    out = []
    for key in sorted(set(a) | set(b), key=lambda k: (k.split(".")[0] != "sweep", k)):
        if a.get(key, "absent") != b.get(key, "absent"):
            out.append(f"{_display_name(key)} = {_show(a.get(key))} in the store, "
                       f"{_show(b.get(key))} here")
    return out


def _create(path: Path, attrs: dict, spec: SweepSpec) -> None:
    """Build the empty store in a temporary directory and rename it into place."""
    zarr = _zarr()
    grid = spec.grid
    tmp = path.with_name(f".{path.name}.creating-{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp)
    group = zarr.open_group(str(tmp), mode="w-", zarr_format=3, attributes=attrs)
    d0, d1 = grid.dims
    for axis in grid.axes:
        arr = group.create_array(axis.name, shape=(axis.n,), chunks=(axis.n,), dtype="float64",
                                 fill_value=0.0, dimension_names=(axis.name,),
                                 attributes={"units": axis.units, "long_name": axis.long_name,
                                             "cell_centres": COORD_NOTE})
        arr[:] = axis.coords
    for name in spec.array_names:
        dtype, fill, array_attrs = VARIABLES[name]
        group.create_array(name, shape=grid.shape, chunks=grid.chunk, dtype=dtype,
                           fill_value=fill, dimension_names=(d0, d1), attributes=array_attrs,
                           config={"write_empty_chunks": True})
    group.create_array("done", shape=grid.tile_grid, chunks=(1, 1), dtype="uint8", fill_value=0,
                       dimension_names=tile_dims(grid), attributes=DONE_ATTRS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "consolidated metadata is not part of the v3 spec"
        zarr.consolidate_metadata(str(tmp))
    os.rename(tmp, path)
    shutil.rmtree(cost_dir(path), ignore_errors=True)
    cost_dir(path).mkdir()


def _check_layout(group, spec: SweepSpec, path: Path) -> None:
    grid = spec.grid
    expected = {**{name: (grid.shape, grid.chunk) for name in spec.array_names},
                "done": (grid.tile_grid, (1, 1))}
    present = set(group.array_keys())
    for name, (shape, chunks) in expected.items():
        if name not in present:
            raise ParameterError(f"{path} is damaged: array '{name}' is missing; "
                                 "--overwrite starts it again")
        arr = group[name]
        if tuple(arr.shape) != tuple(shape) or tuple(arr.chunks) != tuple(chunks):
            raise ParameterError(f"{path} is damaged: array '{name}' has shape {arr.shape} "
                                 f"chunks {arr.chunks}, expected {shape} {chunks}; "
                                 "--overwrite starts it again")


def prepare(path: str | os.PathLike, attrs: dict, spec: SweepSpec,
            overwrite: bool = False) -> np.ndarray:
    """Create the store, or open an existing one with the same parameters, and return its
    ``done`` flags (tile grid, 1 = complete). A store with other parameters is refused with a
    message naming them unless ``overwrite``."""
    zarr = _zarr()
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{path} exists and is not a directory")
    if path.is_dir() and not _is_store(path):
        if any(path.iterdir()):
            raise ParameterError(f"{path} exists and is not a Zarr store: refusing to touch it")
        path.rmdir()
    if _is_store(path):
        if overwrite:
            shutil.rmtree(path)
            shutil.rmtree(cost_dir(path), ignore_errors=True)
        else:
            group = zarr.open_group(str(path), mode="r")
            stored = dict(group.attrs)
            if "coin_basin" not in stored:
                raise ParameterError(f"{path} is a Zarr store but not a coin basin sweep; "
                                     "--overwrite replaces it")
            diff = differences(stored, attrs)
            if diff:
                raise ParameterError(f"{path} holds a different sweep: {'; '.join(diff[:4])}"
                                     f"{' ...' if len(diff) > 4 else ''}. Rerun with the "
                                     "store's parameters to resume it, or --overwrite to "
                                     "replace it")
            _check_layout(group, spec, path)
            return np.asarray(group["done"][:])
    path.parent.mkdir(parents=True, exist_ok=True)
    _create(path, attrs, spec)
    return np.zeros(spec.grid.tile_grid, dtype=np.uint8)


def write_tile(path: str | os.PathLike, spec: SweepSpec, result: TileResult) -> None:
    """Write one tile's arrays, its cost, and last its ``done`` flag."""
    zarr = _zarr()
    group = zarr.open_group(str(path), mode="r+")
    s0, s1 = spec.grid.tile_slices(result.tile)
    i, j = result.tile
    for name in spec.array_names:
        arr = group[name].with_config({"write_empty_chunks": True})
        arr[s0, s1] = result.arrays[name]
    _write_atomically(cost_dir(path) / f"tile_{i}_{j}.json",
                      json.dumps({"cpu_seconds": result.cpu_seconds}))
    group["done"].with_config({"write_empty_chunks": True})[i:i + 1, j:j + 1] = 1


def read_done(path: str | os.PathLike) -> np.ndarray:
    return np.asarray(_zarr().open_group(str(path), mode="r")["done"][:])


def cost_dir(path: str | os.PathLike) -> Path:
    """Where a store's cost records live: beside it, ``out.zarr.cost/``."""
    return Path(f"{os.fspath(path).rstrip(os.sep)}.cost")


def _write_atomically(target: Path, text: str) -> None:
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.{threading.get_ident()}")
    tmp.write_text(text)
    os.replace(tmp, target)


def record_run(path: str | os.PathLike, run: dict) -> None:
    """Append one invocation's record (wall time, tiles, mode) to ``out.zarr.cost/runs.jsonl``
    (only the coordinating process writes it)."""
    target = cost_dir(path) / "runs.jsonl"
    target.parent.mkdir(parents=True, exist_ok=True)
    with open(target, "a") as fh:
        fh.write(json.dumps(run) + "\n")


def read_costs(path: str | os.PathLike, tile_grid: tuple[int, int]) -> tuple[np.ndarray, list]:
    """Per-tile CPU seconds (NaN where unknown) and the run records of a store."""
    seconds = np.full(tile_grid, math.nan)
    folder = cost_dir(path)
    for i in range(tile_grid[0]):
        for j in range(tile_grid[1]):
            f = folder / f"tile_{i}_{j}.json"
            if f.is_file():
                try:
                    seconds[i, j] = json.loads(f.read_text())["cpu_seconds"]
                except (ValueError, KeyError):
                    pass  # a damaged cost record loses the cost, never the results
    runs = []
    log = folder / "runs.jsonl"
    if log.is_file():
        for line in log.read_text().splitlines():
            try:
                runs.append(json.loads(line))
            except ValueError:
                continue
    return seconds, runs


def read_basin(path: str | os.PathLike) -> Basin:
    """Read a store back (cells of tiles not flagged done read as not computed)."""
    zarr = _zarr()
    p = Path(path)
    if not _is_store(p):
        raise ParameterError(f"{path} is not a Zarr store (no zarr.json)")
    group = zarr.open_group(str(p), mode="r")
    attrs = dict(group.attrs)
    if "coin_basin" not in attrs:
        raise ParameterError(f"{path} is not a coin basin store")
    present = set(group.array_keys())
    arrays = {name: np.asarray(group[name][:]) for name in VARIABLES if name in present}
    done = np.asarray(group["done"][:])
    tile_seconds, runs = read_costs(p, done.shape)
    basin = Basin(attrs=attrs, arrays=arrays, done=done, tile_seconds=tile_seconds, runs=runs,
                  path=str(path))
    basin.mask_not_done()
    return basin


def run_record(started: float, wall: float, tiles: int, cells: int, mode: str, workers: int,
               interrupted: bool) -> dict:
    return {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(started)),
            "wall_seconds": round(wall, 3), "tiles": tiles, "cells": cells, "mode": mode,
            "workers": workers, "interrupted": interrupted}


__all__ = ["differences", "prepare", "read_basin", "read_done",
           "read_costs", "record_run", "run_record", "write_tile", "cost_dir"]
