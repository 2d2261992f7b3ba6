"""What a basin store is made of, and what opening one proves: its arrays and the files of an
empty one (:func:`template`), a tile's digest (:func:`tile_digest`), the side folder of its costs
and claims; and the parameters its tiles were computed with, proven from the three copies of the
sweep's attributes (:mod:`coincli.stores.basin_metadata`) and from the tiles themselves
(:func:`read_view`). :class:`coincli.stores.basin_store.BasinStore` owns a store through these."""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..defaults import IC_NAMES
from ..engines.claims import HOST, Claims, pid_alive
from ..grid import Axis, Grid
from ..params import ParameterError
from ..version import __version__
from . import basin_metadata as meta
from .basin_schema import (
    COMPARED_ATTRS,
    COORD_NOTE,
    FORMAT,
    MARK,
    VARIABLES,
    done_attrs,
    owned,
    parameters_digest,
    root_attrs,
    tile_dims,
)
from .zarr_v3 import (
    ArraySpec,
    ChunkError,
    group_files,
    is_store,
)

ARRAY_NAMES = tuple(VARIABLES)  # the data arrays, in the order of the digest


DONE_DTYPE = "uint32"  # the digests; fill 0 = not done


class StoreDamaged(ParameterError):
    """A store whose metadata cannot be read, or whose parameters cannot be recovered."""


# -- the grid, the digest and the files of a store --------------------------------------------
def grid_of(attrs: dict) -> Grid:
    """The grid a basin's attributes describe: its swept axes, its fixed initial values, its
    tiles and its mirror."""
    sweep = attrs["sweep"]
    axes = tuple(Axis(a["name"], float(a["lo"]), float(a["hi"]), int(a["n"]))
                 for a in sweep["axes"])
    fixed = sweep.get("fixed") or {}
    base = tuple(float(fixed[name]) if name in fixed else 0.0 for name in IC_NAMES)
    return Grid(axes=axes, base_state=base, chunk=tuple(int(c) for c in sweep["chunk"]),
                use_mirror=bool(sweep.get("mirror")))


def tile_digest(tile: tuple[int, int], arrays: dict[str, np.ndarray], parameters: bytes) -> int:
    """32-bit BLAKE2b of the parameters the tile was computed with (their digest,
    :func:`coincli.stores.basin_schema.parameters_digest`), its index and its data (every array of
    the schema, in a fixed order, as little-endian bytes of its stored dtype): never 0, which means
    "not done"."""
    h = hashlib.blake2b(digest_size=4, person=b"coin-tile")
    h.update(parameters)
    h.update(np.asarray(tile, dtype="<i8").tobytes())
    for name in ARRAY_NAMES:
        block = np.ascontiguousarray(arrays[name],
                                     dtype=np.dtype(VARIABLES[name][0]).newbyteorder("<"))
        h.update(np.asarray(block.shape, dtype="<i8").tobytes())
        h.update(block.tobytes())
    return int.from_bytes(h.digest(), "little") or 1


def array_specs(attrs: dict, grid: Grid) -> dict[str, ArraySpec]:
    """Every array of the store of a sweep with attributes ``attrs`` on ``grid``."""
    d0, d1 = grid.dims
    specs = {axis.name: ArraySpec(axis.name, (axis.n,), (axis.n,), "float64", 0.0,
                                  (axis.name,), {"units": axis.units,
                                                 "long_name": axis.long_name,
                                                 "cell_centres": COORD_NOTE})
             for axis in grid.axes}
    for name in ARRAY_NAMES:
        dtype, fill, array_attrs = VARIABLES[name]
        specs[name] = ArraySpec(name, grid.shape, grid.chunk, dtype, fill, (d0, d1),
                                array_attrs)
    specs["done"] = ArraySpec("done", grid.tile_grid, (1, 1), DONE_DTYPE, 0, tile_dims(grid),
                              done_attrs(attrs))
    return specs


def template(attrs: dict, grid: Grid) -> dict[str, bytes]:
    """Every file of an empty store, by key ('zarr.json', 'vy/c/0', ...): the metadata of the
    group and its arrays (consolidated into the group's) and the coordinate chunks. Creating a
    store is writing these files; checking one, comparing with them. Only the attributes the
    sweep owns are taken from ``attrs`` (with their digest, in the group's attributes and in a
    copy in the ``done`` array's)."""
    specs = array_specs(attrs, grid)
    files = {}
    for axis in grid.axes:
        spec = specs[axis.name]
        files[spec.key((0,))] = encode(spec, np.asarray(axis.coords, dtype=np.float64))
    files.update(group_files(root_attrs(attrs), list(specs.values())))
    return files


def encode(spec: ArraySpec, block: np.ndarray) -> bytes:
    from .zarr_v3 import encode_chunk

    return encode_chunk(block, spec.dtype, spec.fill, spec.chunks)


def cost_dir(path: str | os.PathLike) -> Path:
    """Where a store's cost records and claims live: beside it, ``out.zarr.cost/``."""
    return Path(f"{os.fspath(path).rstrip(os.sep)}.cost")


def root_lost(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a basin store whose root ``zarr.json`` is gone (deleted) while the
    copy of its attributes in ``done/zarr.json`` is there: a store all the same, whose
    parameters that copy (and its tiles) prove, and whose root a resume rewrites."""
    p = Path(path)
    return not is_store(p) and (p / "done" / "zarr.json").is_file()


def check_is_store(path: str | os.PathLike) -> None:
    """ParameterError (one line) unless ``path`` is a Zarr store (or a basin store whose root
    ``zarr.json`` is lost: :func:`root_lost`), saying what it is instead."""
    p = Path(path)
    if not p.exists():
        raise ParameterError(f"{path} does not exist")
    if not is_store(p) and not root_lost(p):
        raise ParameterError(f"{path} is not a Zarr store (it has no zarr.json)")


def short_error(exc: BaseException) -> str:
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if "checksum" in text.lower():
        return "checksum mismatch"
    return text if len(text) <= 100 else text[:97] + "..."


def read_runs(path: str | os.PathLike) -> list[dict]:
    """The run records of ``STORE.cost/runs.jsonl`` (a damaged line is skipped)."""
    runs = []
    log = cost_dir(path) / "runs.jsonl"
    if log.is_file():
        for line in log.read_text().splitlines():
            try:
                runs.append(json.loads(line))
            except ValueError:
                continue
    return runs


def record_run(path: str | os.PathLike, run: dict) -> None:
    """Append one invocation's record to ``STORE.cost/runs.jsonl`` (only the coordinating
    process writes it; one write of one line, so that the records of processes sharing a store
    do not interleave)."""
    target = cost_dir(path) / "runs.jsonl"
    target.parent.mkdir(parents=True, exist_ok=True)
    with open(target, "a") as fh:
        fh.write(json.dumps(run) + "\n")


class SideRecords:
    """What a store (basin or fractions) keeps beside it, in ``STORE.cost/``: the records of
    its runs and the claims of the processes that share it. Its owner sets ``path``."""

    path: Path

    @property
    def cost_dir(self) -> Path:
        return cost_dir(self.path)

    @property
    def claims_dir(self) -> Path:
        return self.cost_dir / "claims"

    def claims(self) -> Claims:
        """This process's claims on the store's pieces of work (close them when done)."""
        return Claims(self.claims_dir)

    def record_run(self, run: dict) -> None:
        record_run(self.path, run)

    def runs(self) -> list[dict]:
        return read_runs(self.path)


def check_store_writable(path: str | os.PathLike) -> None:
    """Raise NotWritable (one line) unless the store (or the folder it will be created in) and
    its side folder accept new files: a read-only mount or a full disk is found before any
    work."""
    import errno

    from ..files import REASONS, NotWritable, check_writable

    path = Path(path)
    existed = is_store(path)
    try:
        check_writable(path, what="store", directory=True, create_parents=True)
        side = cost_dir(path)
        if side.is_dir():
            check_writable(side, what="store", directory=True)
    except OSError as exc:
        read_only = (errno.EROFS, errno.EACCES, errno.EPERM)
        if not (isinstance(exc, PermissionError) or exc.errno in read_only):
            raise  # a full disk, ...: said as it is
        reason = REASONS.get(exc.errno, "permission denied")
        raise NotWritable(exc.errno, f"the store {path} is read-only ({reason}): a sweep "
                                     "cannot write to it here" if existed else
                          f"cannot create the store {path}: its folder is read-only "
                          f"({reason})") from None


def remove_dead_probes(path: Path) -> None:
    """The writability probes (``.coin-probe-HOST-PID``) of dead processes of this host."""
    for probe in path.glob(".coin-probe-*"):
        host, _, pid = probe.name.removeprefix(".coin-probe-").rpartition("-")
        if host == HOST and pid.isdigit() and not pid_alive(int(pid)):
            with contextlib.suppress(OSError):
                probe.unlink()


# -- the store --------------------------------------------------------------------------------
@dataclass(frozen=True)
class StoreView:
    """What opening a store read once: its attributes (those of the sweep its tiles were
    computed with, and any a user added), its grid, the parameters digest its tiles are checked
    against, the copies of its parameters found changed (and how the right ones are known:
    agree, tiles, digest), and its arrays."""

    attrs: dict
    grid: Grid
    parameters: bytes
    problems: tuple[str, ...] = ()
    proof: str = "agree"

    @functools.cached_property
    def specs(self) -> dict[str, ArraySpec]:
        """The arrays' specs, made once (every tile read and written goes through them)."""
        return array_specs(self.attrs, self.grid)


# -- which parameters the tiles were computed with ----------------------------------------------
def read_view(path: Path, grid: Grid | None = None, wanted: dict | None = None) -> StoreView:
    """What opening the store at ``path`` reads once
    (:meth:`coincli.stores.basin_store.BasinStore.open` says what): ParameterError if it is none or
    of another format, StoreDamaged if the
    parameters its tiles were computed with cannot be recovered."""
    check_is_store(path)
    attrs, copies = meta.read_copies(path)
    if attrs is not None and MARK not in attrs and copies[2].value is None:
        raise ParameterError(f"{path} is not a coin basin store")
    mark = attrs.get(MARK) if attrs is not None else None
    fmt = mark.get("format") if isinstance(mark, dict) else None
    if isinstance(fmt, int) and fmt > FORMAT:  # its data are good: never advise them away
        raise ParameterError(f"{path} was written by a newer coin: a basin store of format "
                             f"{fmt}, where this version (coincli {__version__}) reads format "
                             f"{FORMAT}; upgrade coincli to read it (pip install --upgrade "
                             "coincli)")
    if fmt is not None and fmt != FORMAT:
        raise ParameterError(f"{path} is a coin basin store of format {fmt}, this version "
                             f"reads format {FORMAT}: recompute it (overwrite)",
                             parameters=("overwrite",))
    if all(c.value is None for c in copies):
        raise StoreDamaged(f"{path}: its metadata cannot be read: the store is damaged; "
                           "overwrite starts the sweep again", parameters=("overwrite",))
    proven, proof = _prove(path, copies, wanted)
    if proven is None:
        raise StoreDamaged(f"{path}: {proof}", parameters=("overwrite",))
    extra = {k: v for k, v in (attrs or {}).items() if k != MARK and k not in COMPARED_ATTRS}
    full = {**root_attrs(proven), **extra}
    if grid is None or (wanted is not None and owned(wanted) != proven):
        try:
            grid = grid_of(full)
        except Exception as exc:  # noqa: BLE001
            raise StoreDamaged(f"{path}: its metadata cannot be read ({short_error(exc)}): the "
                               "store is damaged; overwrite starts the sweep again",
                               parameters=("overwrite",)) from None
    return StoreView(full, grid, parameters_digest(proven),
                     tuple(meta.problems_of(copies, proven, proof)), proof)


def _digest_tiles(path: Path) -> list[tuple[int, int]]:
    """The tiles with a ``done`` chunk file, from the folder (whatever the metadata say)."""
    tiles = []
    for row in (path / "done" / "c").glob("*"):
        for cell in row.glob("*"):
            if row.name.isdigit() and cell.name.isdigit():
                tiles.append((int(row.name), int(cell.name)))
    return sorted(tiles)


def _tiles_verify(path: Path, value: dict, tiles: list, most: int = 16) -> bool:
    """Whether a computed tile verifies under the sweep attributes ``value`` (one does only
    under the parameters it was computed with). Up to ``most`` readable tiles are tried."""
    try:
        grid = grid_of(value)
        specs = array_specs(value, grid)
    except Exception:  # noqa: BLE001 - attributes that describe no grid prove nothing
        return False
    parameters = parameters_digest(value)
    t0, t1 = grid.tile_grid
    tried = 0
    for tile in tiles:
        if tile[0] >= t0 or tile[1] >= t1:
            continue
        try:
            flag = int(specs["done"].read(path, tile)[0, 0])
        except (OSError, ChunkError, ValueError):  # damage: no proof
            continue
        data, _ = read_tile(specs, path, tile)
        if data is None:
            continue
        if tile_digest(tile, data, parameters) == flag:
            return True
        tried += 1
        if tried >= most:
            break
    return False


def read_tile(specs: dict[str, ArraySpec], path: Path,
              tile: tuple[int, int]) -> tuple[dict | None, str | None]:
    """One tile's arrays of the store at ``path`` (its ``specs``), or why they cannot be
    read."""
    out = {}
    for name in ARRAY_NAMES:
        key = f"chunk {name}/c/{tile[0]}/{tile[1]}"
        try:
            out[name] = specs[name].read(path, tile)
        except FileNotFoundError:
            return None, f"{key} is missing"
        except Exception as exc:  # noqa: BLE001 - any failure to read is damage
            return None, f"{key} cannot be read ({short_error(exc)})"
    return out, None


def _prove(path: Path, copies: list[meta.Copy],
           wanted: dict | None) -> tuple[dict | None, str]:
    """The sweep attributes the store's tiles were computed with, and how that is known:
    'agree' (every copy whole and the same), 'tiles' (a computed tile verifies under them),
    'digest' (the one copy that matches its own digest); (None, why) if nothing proves any."""
    values = meta.unique(c.value for c in copies if c.value is not None)
    if len(values) == 1 and all(c.consistent for c in copies):
        return values[0], "agree"
    tiles = _digest_tiles(path)
    candidates = meta.unique([*values, *([owned(wanted)] if wanted is not None else [])])
    for value in candidates:
        if tiles and _tiles_verify(path, value, tiles):
            return value, "tiles"
    consistent = meta.unique(c.value for c in copies if c.consistent)
    if len(consistent) == 1:
        return consistent[0], "digest"
    if len(values) == 1 and not tiles:  # nothing computed, and nothing says otherwise
        return values[0], "agree"
    if tiles:
        n = len(tiles)
        return None, (f"the parameters its {n} tile{'s' if n != 1 else ''} were computed with "
                      "cannot be recovered: no tile verifies under "
                      + ("its metadata's" if wanted is None else "its metadata's or these")
                      + " (the metadata were changed after the tiles were computed"
                      + (f": {meta.disagreement(copies)}" if len(values) > 1 else "") + "). "
                      + "Run the sweep with the parameters of its tiles to resume it, or "
                      "overwrite to start again")
    return None, (f"its parameters cannot be recovered: {meta.disagreement(copies)}, and no "
                  "computed tile proves either; overwrite starts the sweep again")


__all__ = ["ARRAY_NAMES", "DONE_DTYPE", "StoreDamaged", "StoreView", "array_specs",
           "check_is_store", "check_store_writable", "cost_dir", "grid_of", "read_runs",
           "read_tile", "read_view", "record_run", "remove_dead_probes", "root_lost",
           "short_error", "template", "tile_digest"]
