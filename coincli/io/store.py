"""The Zarr v3 store of a basin sweep: create or resume it, write one tile, check it, read it back.

Layout (dims named after the two swept initial conditions, e.g. ``vy`` and ``vphi``)::

    out.zarr/                       group; attributes: coin_basin (format 5, the parameters
                                    digest), version, parameters, sweep, method (with its
                                    verification ladder)
      vy, vphi                      float64 cell centres, linspace(LO, HI, n)
      quarter_turns  (vy, vphi)     int16, fill -32768 = no label (not computed or non-finite)
      status         (vy, vphi)     uint8, 0 settled, 1 unsettled at t_end, 2 non-finite,
                                    3 over budget, 255 not computed
      settle_time    (vy, vphi)     float32 [s], NaN fill (also NaN when never settled)
      steps          (vy, vphi)     int64 integrator steps (cost), fill -1
      certainty      (vy, vphi)     uint8, 0 uncertain (decided, rungs disagree: chaotic), 1
                                    certain, 2 unverified, 3 undecided (a rung not settled
                                    within its horizon or budget), 255 not computed
      rung           (vy, vphi)     int8, last rung of the ladder run, fill -1
      done           (tile_vy, tile_vphi)  uint32 digest of the tile, 0 = not done; chunks (1, 1);
                                    attributes: a copy of the sweep's, with their digest
    out.zarr.cost/                  beside the store, so that the store itself is bit-identical
      tile_I_J.json                 however it was computed: each tile's CPU seconds and who
      runs.jsonl                    computed it, one line per invocation (wall time, tiles,
      claims/tile_I_J               mode), and the claims of the tiles being computed
                                    (:mod:`coincli.io.claims`)

Every data array is chunked exactly like the tiles, so one tile is one chunk in every array and
concurrent writers (threads, Dask workers, other processes) never touch the same file. Every
chunk ends with a CRC-32C of its compressed bytes (Zarr v3's ``crc32c`` codec, after ``zstd``),
so a chunk damaged on disk (random bytes, truncated, a bit flipped, emptied) fails to read
instead of decoding to garbage. A tile's ``done`` entry, written after all its data, is
:func:`tile_digest`: a 32-bit BLAKE2b of its data, *its tile index and the digest of the
parameters it was computed with*, so that a chunk copied from another tile (a valid chunk, at
the wrong place) or a missing chunk (read back as fill values) is caught too, and so is a
parameter changed in the metadata after the tile was computed. A tile is done only if its
``done`` digest equals the digest of the data its chunks read back as (:func:`scan`); otherwise
it is recomputed on resume (recomputing gives the same bytes), counted as not computed by
``stats`` and ``render``, and listed by ``coin basin verify``.

The store is Zarr v3, but this module writes and reads it without importing Zarr, whose import
alone takes a quarter of a second of every `coin basin` (the layout is fixed: one chunk per tile,
the codecs of :data:`CODECS`). A tile's chunks are encoded here (:func:`encode_chunk`: bytes
little-endian, zstd level 0, crc32c, with numcodecs and google-crc32c, the libraries Zarr's own
codecs call), and written to ``CHUNK.HOST-PID-THREAD.partial``, then renamed: Zarr's ``arr[...] =``
takes 4 ms a chunk, nearly all of it in its asyncio machinery, against 0.5 ms. Every chunk of a
tile is written, also one equal to the fill value. A ``.partial`` file left by a killed writer is
removed by the next writer of that tile. Reading decodes the same chunks (:func:`decode_chunk`,
which checks their CRC and length). The store is created from a template built in memory
(:func:`template`: every metadata file and the coordinate chunks), in
``.NAME.creating-HOST-PID`` beside it, renamed into place under a lock (``.NAME.lock``,
``flock``), so that processes racing to create one store all end up in the winner's. Chunks,
metadata and what is read back are the same, byte for byte and value for value, as Zarr's
(tests/test_store.py). Metadata is consolidated once at creation, so ``xarray.open_zarr(path)``
and ``zarr.open_group(path)`` open it directly.

The sweep's attributes (what determines the labels: :data:`coincli.io.schema.COMPARED_ATTRS`)
are kept in three copies, each with its digest: the group's attributes, and the ``done`` array's
attributes in the consolidated metadata and in done/zarr.json. On opening, copies that differ
are judged by the tiles (:func:`open_view`): the parameters a computed tile verifies under are
those it was computed with, and the copies that differ from them are damage, rebuilt on resume.
Metadata files are compared parsed, on what the sweep wrote (shape, chunks, dtype, fill value,
codecs, dimension names, its attributes): what a user adds (an attribute, an array listed in the
consolidated metadata) is theirs, kept on resume and never called damage; a metadata file or
coordinate chunk that differs is rewritten on resume from the proven parameters, with what the
user added. ``quarter_turns``
carries ``missing_value`` so xarray masks cells without a label to NaN (``mask_and_scale=False``
keeps the int16 values).
"""

from __future__ import annotations

import contextlib
import enum
import functools
import hashlib
import json
import math
import os
import shutil
import socket
import threading
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..defaults import IC_NAMES
from ..grid import Axis, Grid, SweepSpec, TileResult
from ..params import ParameterError
from .dataset import Basin
from .paths import atomic_output
from .schema import (
    COMPARED_ATTRS,
    COORD_NOTE,
    COPY,
    DTYPES,
    FILLS,
    FORMAT,
    MARK,
    VARIABLES,
    done_attrs,
    owned,
    parameters_digest,
    root_attrs,
    tile_dims,
)

ARRAY_NAMES = SweepSpec.array_names  # the data arrays, in the order of the digest
DONE_DTYPE = "uint32"  # the digests; fill 0 = not done


ZSTD_LEVEL = 0  # the store's compression: a tile compresses 3-10x at level 0 already
# Every array's codecs, as Zarr v3 names them: bytes little-endian, zstd, then a CRC-32C
CODECS = ({"name": "bytes", "configuration": {"endian": "little"}},
          {"name": "zstd", "configuration": {"level": ZSTD_LEVEL, "checksum": False}},
          {"name": "crc32c"})


class ChunkError(ValueError):
    """A chunk file that does not decode (checksum, length)."""


@functools.cache
def _zstd():
    from numcodecs.zstd import Zstd

    return Zstd(level=ZSTD_LEVEL, checksum=False)


def _crc32c(data: bytes) -> bytes:
    import google_crc32c

    return np.array([google_crc32c.value(data)], dtype="<u4").tobytes()


def encode_chunk(block: np.ndarray, dtype: str, fill, chunk: tuple[int, ...]) -> bytes:
    """The bytes of one chunk as Zarr writes it under :data:`CODECS`: the block padded with
    ``fill`` to the chunk's shape (a tile at the grid's far edge is smaller), its values
    little-endian in C order, zstd-compressed, then the CRC-32C of the compressed bytes
    (little-endian uint32)."""
    full = np.full(chunk, fill, dtype=np.dtype(dtype).newbyteorder("<"))
    full[tuple(slice(0, n) for n in block.shape)] = block
    compressed = bytes(_zstd().encode(full.tobytes()))
    return compressed + _crc32c(compressed)


def decode_chunk(data: bytes, dtype: str, chunk: tuple[int, ...]) -> np.ndarray:
    """The values of a chunk written by :func:`encode_chunk` (the whole chunk, padding
    included); ChunkError if its checksum or its length is wrong."""
    if len(data) < 4 or _crc32c(data[:-4]) != data[-4:]:
        raise ChunkError("checksum mismatch")
    try:
        raw = _zstd().decode(data[:-4])
    except Exception as exc:  # noqa: BLE001 - undecodable bytes are damage
        raise ChunkError(f"zstd: {exc}") from None
    wanted = np.dtype(dtype).newbyteorder("<")
    if len(raw) != wanted.itemsize * math.prod(chunk):
        raise ChunkError(f"{len(raw)} bytes where {wanted.itemsize * math.prod(chunk)} belong")
    return np.frombuffer(raw, dtype=wanted).reshape(chunk).astype(np.dtype(dtype))


def is_store(path: str | os.PathLike) -> bool:
    return (Path(path) / "zarr.json").is_file()


def check_is_store(path: str | os.PathLike) -> None:
    """ParameterError (one line) unless ``path`` is a Zarr store, saying what it is instead."""
    p = Path(path)
    if not p.exists():
        raise ParameterError(f"{path} does not exist")
    if not is_store(p):
        raise ParameterError(f"{path} is not a Zarr store (it has no zarr.json)")


# -- comparing parameters ------------------------------------------------------------------------
def flatten_attrs(value, prefix: str = "") -> dict:
    """Nested attribute dicts -> {'parameters.foundation.k': 1e4, 'sweep.axes.vy.lo': 0.05}."""
    if isinstance(value, dict):
        out = {}
        for key, sub in value.items():
            out.update(flatten_attrs(sub, f"{prefix}.{key}" if prefix else str(key)))
        return out
    if isinstance(value, list) and value and all(isinstance(v, dict) and "name" in v
                                                for v in value):
        out = {}
        for sub in value:
            out.update(flatten_attrs({k: v for k, v in sub.items() if k != "name"},
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
        return {"n": f"--res ({parts[2]} cells)", "lo": f"--{parts[2]} LO",
                "hi": f"--{parts[2]} HI"}.get(parts[3], f"{parts[2]} {parts[3]}")
    if parts[0] == "sweep":
        return {"dims": "swept axes", "chunk": "--chunk", "fixed": "fixed initial value",
                "mirror": "mirrored axes (none: --no-mirror)"}.get(
            parts[1], parts[1]) + (f" {parts[2]}" if len(parts) > 2 else "")
    if parts[0] == "method":
        return "method" if parts[1] == "name" else parts[1]
    if parts[0] == "version":
        return "coincli version"
    return key


def show_value(value) -> str:
    if value is None:
        return "none"
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


def differences(stored: dict, wanted: dict,
                where: tuple[str, str] = ("in the store", "here")) -> list[str]:
    """One phrase per differing parameter: 'k = 10000 in the store, 5000 here' (``where``
    names the two sides)."""
    a = flatten_attrs({k: stored.get(k) for k in COMPARED_ATTRS})
    b = flatten_attrs({k: wanted.get(k) for k in COMPARED_ATTRS})
    out = []
    # the sweep first, then in the attributes' own order (the axes as swept: vy, then vphi)
    for key in sorted(dict.fromkeys([*a, *b]), key=lambda k: k.split(".")[0] != "sweep"):
        if key.startswith("sweep.axes.") and key.endswith((".units", ".long_name")):
            continue  # they follow from the axis's name, which differs too
        if a.get(key, "absent") != b.get(key, "absent"):
            out.append(f"{_display_name(key)} = {show_value(a.get(key))} {where[0]}, "
                       f"{show_value(b.get(key))} {where[1]}")
    return out


# -- the digest of a tile ------------------------------------------------------------------------
def tile_digest(tile: tuple[int, int], arrays: dict[str, np.ndarray], parameters: bytes) -> int:
    """32-bit BLAKE2b of the parameters the tile was computed with (their digest,
    :func:`coincli.io.schema.parameters_digest`), its index and its data (every array of the
    schema, in a fixed order, as little-endian bytes of its stored dtype): never 0, which means
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


# -- creating ------------------------------------------------------------------------------------
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


def _fill_json(fill):
    """A fill value as Zarr v3 writes it in JSON (NaN and infinities as strings)."""
    if isinstance(fill, float) and not math.isfinite(fill):
        return "NaN" if math.isnan(fill) else ("Infinity" if fill > 0 else "-Infinity")
    return fill


def _codecs(dtype: str) -> list[dict]:
    """CODECS as Zarr writes them for ``dtype``: single bytes have no byte order."""
    if np.dtype(dtype).itemsize == 1:
        return [{"name": "bytes"}, *CODECS[1:]]
    return list(CODECS)


def _array_metadata(shape, chunks, dtype: str, fill, dims, attributes: dict) -> dict:
    """The zarr.json of one array, key for key as Zarr v3 writes it."""
    return {"shape": list(shape), "data_type": dtype,
            "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": list(chunks)}},
            "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
            "fill_value": _fill_json(fill), "codecs": _codecs(dtype),
            "attributes": attributes, "dimension_names": list(dims), "zarr_format": 3,
            "node_type": "array", "storage_transformers": []}


def _json_bytes(document: dict) -> bytes:
    return json.dumps(document, indent=2, allow_nan=True).encode()  # as Zarr writes metadata


def template(attrs: dict, grid: Grid) -> dict[str, bytes]:
    """Every file of an empty store, by key ('zarr.json', 'vy/c/0', ...): the metadata of the
    group and its arrays (consolidated into the group's) and the coordinate chunks, byte for
    byte what Zarr writes for them (tests/test_store.py), without importing Zarr (a quarter of
    a second). Creating a store is writing these files; checking one, comparing with them.
    Only the attributes the sweep owns are taken from ``attrs`` (with their digest, in the
    group's attributes and in a copy in the ``done`` array's)."""
    d0, d1 = grid.dims
    arrays = {}
    files = {}
    for axis in grid.axes:
        arrays[axis.name] = _array_metadata(
            (axis.n,), (axis.n,), "float64", 0.0, (axis.name,),
            {"units": axis.units, "long_name": axis.long_name, "cell_centres": COORD_NOTE})
        files[f"{axis.name}/c/0"] = encode_chunk(np.asarray(axis.coords, dtype=np.float64),
                                                 "float64", 0.0, (axis.n,))
    for name in ARRAY_NAMES:
        dtype, fill, array_attrs = VARIABLES[name]
        arrays[name] = _array_metadata(grid.shape, grid.chunk, dtype, fill, (d0, d1),
                                       array_attrs)
    arrays["done"] = _array_metadata(grid.tile_grid, (1, 1), DONE_DTYPE, 0, tile_dims(grid),
                                     done_attrs(attrs))
    group = {"attributes": root_attrs(attrs), "zarr_format": 3,
             "consolidated_metadata": {"kind": "inline", "must_understand": False,
                                       "metadata": {k: arrays[k] for k in sorted(arrays)}},
             "node_type": "group"}
    files["zarr.json"] = _json_bytes(group)
    for name, metadata in arrays.items():
        files[f"{name}/zarr.json"] = _json_bytes(metadata)
    return files


def _write_files(root: Path, files: dict[str, bytes]) -> None:
    for key, data in files.items():
        target = root / key
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)


@contextlib.contextmanager
def creation_lock(path: Path, blocking: bool = True):
    """Hold ``.NAME.lock`` beside the store (flock; the kernel drops it when its holder dies).
    Yields False if not ``blocking`` and someone else holds it."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        yield True
        return
    lock = path.with_name(f".{path.name}.lock")
    while True:
        fd = os.open(lock, os.O_CREAT | os.O_RDWR, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
        except BlockingIOError:
            os.close(fd)
            yield False
            return
        except BaseException:
            os.close(fd)
            raise
        try:  # the file we locked must still be the lock (its holder may have removed it)
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        yield True
    finally:
        with contextlib.suppress(OSError):
            os.unlink(lock)
        os.close(fd)


def creating_name(path: Path) -> str:
    return f".{path.name}.creating-{socket.gethostname()}-{os.getpid()}"


def remove_orphans(path: Path) -> None:
    """Temporary stores of creations that died (call with the creation lock held)."""
    for leftover in path.parent.glob(f".{path.name}.creating-*"):
        shutil.rmtree(leftover, ignore_errors=True)


def tidy(path: str | os.PathLike) -> None:
    """Remove what a creation killed midway left beside an existing store (its temporary
    directory, its lock file), unless a creation is running now, and the writability probes
    (``.coin-probe-HOST-PID``) of dead processes of this host inside it."""
    from .claims import HOST, pid_alive

    path = Path(path)
    if not path.parent.is_dir():
        return
    for probe in path.glob(".coin-probe-*"):
        host, _, pid = probe.name.removeprefix(".coin-probe-").rpartition("-")
        if host == HOST and pid.isdigit() and not pid_alive(int(pid)):
            with contextlib.suppress(OSError):
                probe.unlink()
    if not any(path.parent.glob(f".{path.name}.creating-*")) and \
            not path.with_name(f".{path.name}.lock").exists():
        return
    with contextlib.suppress(OSError), creation_lock(path, blocking=False) as held:
        if held:
            remove_orphans(path)


def _create(path: Path, attrs: dict, spec: SweepSpec, overwrite: bool) -> None:
    """Create the store (under the creation lock), unless another process did meanwhile."""
    with creation_lock(path):
        if is_store(path) and not overwrite:
            return  # another process won the race: open its store
        remove_orphans(path)
        if is_store(path):  # overwrite
            shutil.rmtree(path)
        elif path.is_dir() and not any(path.iterdir()):
            path.rmdir()
        tmp = path.with_name(creating_name(path))
        try:
            _write_files(tmp, template(attrs, spec.grid))
            shutil.rmtree(cost_dir(path), ignore_errors=True)  # the records of an older store
            os.rename(tmp, path)
            cost_dir(path).mkdir(exist_ok=True)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise


# -- opening and checking ------------------------------------------------------------------------
class StoreDamaged(ParameterError):
    """A store whose metadata cannot be read, or whose parameters cannot be recovered."""


class Tile(enum.Enum):
    DONE = "done"  # digest matches the data
    MISSING = "missing"  # not done (never computed, or cut off before its digest)
    DAMAGED = "damaged"  # a digest, but data that do not read back or do not match it


@dataclass
class StoreCheck:
    """What checking a store found."""

    path: str
    attrs: dict
    grid: Grid
    done: np.ndarray  # bool per tile: complete and verified
    damaged: dict[tuple[int, int], str] = field(default_factory=dict)  # tile -> why
    metadata: list[str] = field(default_factory=list)  # metadata/coordinate files that differ
    repaired: list[str] = field(default_factory=list)  # ... and were rewritten
    leftovers: int = 0  # temporary files (*.partial) of writers that died
    seconds: float = 0.0  # time the check took
    problems: list[str] = field(default_factory=list)  # copies of the parameters found changed

    @property
    def intact(self) -> bool:
        return not self.damaged and not (set(self.metadata) - set(self.repaired))

    @property
    def tiles_done(self) -> int:
        return int(self.done.sum())

    def __repr__(self) -> str:
        return (f"StoreCheck({self.path!r}, intact={self.intact}, {self.tiles_done} of "
                f"{self.done.size} tiles done, {len(self.damaged)} damaged, "
                f"{len(self.metadata)} metadata files differing)")


@dataclass
class StoreView:
    """An opened store: its attributes (those of the sweep its tiles were computed with, and
    any a user added), its grid, and the parameters digest its tiles are checked against."""

    path: Path
    attrs: dict
    grid: Grid
    parameters: bytes = b""  # schema.parameters_digest of the sweep attributes
    problems: list[str] = field(default_factory=list)  # copies of them that differ, and how
    proof: str = "agree"  # how the sweep attributes are known: agree, tiles, digest


@dataclass
class _Copy:
    """One copy of the sweep attributes in a store's metadata."""

    where: str
    value: dict | None  # None: unreadable
    digest: str | None = None  # the parameters digest stored beside them

    @property
    def consistent(self) -> bool:
        return self.value is not None and self.digest == parameters_digest(self.value).hex()


_PROOF = {"tiles": "proven by its computed tiles", "digest": "confirmed by its digest",
          "agree": "in the other copies"}


def _load_json(file: Path):
    """A metadata file parsed, or None if it cannot be read or parsed."""
    try:
        return json.loads(file.read_bytes())
    except (OSError, ValueError):
        return None


def _dig(document, *keys):
    for key in keys:
        if not isinstance(document, dict):
            return None
        document = document.get(key)
    return document


def _copy_in(where: str, attributes) -> _Copy:
    """The copy of the sweep attributes in the ``done`` array's attributes."""
    value = _dig(attributes, COPY)
    if not isinstance(value, dict):
        return _Copy(where, None)
    return _Copy(where, owned(value), _dig(attributes, "digest"))


def _copies(path: Path) -> tuple[dict | None, list[_Copy]]:
    """The group's attributes (None if unreadable) and the three copies of the sweep
    attributes: the group's own, and the ``done`` array's in the consolidated metadata and in
    its zarr.json."""
    root = _load_json(path / "zarr.json")
    attrs = _dig(root, "attributes")
    if isinstance(attrs, dict):
        group = _Copy("the group's attributes (zarr.json)", owned(attrs),
                      _dig(attrs, MARK, "digest"))
    else:
        attrs, group = None, _Copy("zarr.json", None)
    return attrs, [group,
                   _copy_in("the consolidated metadata of done (zarr.json)",
                            _dig(root, "consolidated_metadata", "metadata", "done",
                                 "attributes")),
                   _copy_in("done/zarr.json", _dig(_load_json(path / "done" / "zarr.json"),
                                                   "attributes"))]


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
    except Exception:  # noqa: BLE001 - attributes that describe no grid prove nothing
        return False
    view = StoreView(path, value, grid, parameters_digest(value))
    t0, t1 = grid.tile_grid
    tried = 0
    for tile in tiles:
        if tile[0] >= t0 or tile[1] >= t1:
            continue
        try:
            flag = int(_read_chunk(view, "done", tile)[0, 0])
        except Exception:  # noqa: BLE001 - damage: no proof
            continue
        data, _ = _read_tile(view, tile)
        if data is None:
            continue
        if tile_digest(tile, data, view.parameters) == flag:
            return True
        tried += 1
        if tried >= most:
            break
    return False


def _unique(values: Iterable[dict]) -> list[dict]:
    out = []
    for value in values:
        if value not in out:
            out.append(value)
    return out


def _prove(path: Path, copies: list[_Copy], wanted: dict | None) -> tuple[dict | None, str]:
    """The sweep attributes the store's tiles were computed with, and how that is known:
    'agree' (every copy whole and the same), 'tiles' (a computed tile verifies under them),
    'digest' (the one copy that matches its own digest); (None, why) if nothing proves any."""
    values = _unique(c.value for c in copies if c.value is not None)
    if len(values) == 1 and all(c.consistent for c in copies):
        return values[0], "agree"
    tiles = _digest_tiles(path)
    candidates = _unique([*values, *([owned(wanted)] if wanted is not None else [])])
    for value in candidates:
        if tiles and _tiles_verify(path, value, tiles):
            return value, "tiles"
    consistent = _unique(c.value for c in copies if c.consistent)
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
                      + (f": {_disagreement(copies)}" if len(values) > 1 else "") + "). "
                      + "Run the sweep with the parameters of its tiles to resume it, or "
                      "overwrite to start again")
    return None, (f"its parameters cannot be recovered: {_disagreement(copies)}, and no "
                  "computed tile proves either; overwrite starts the sweep again")


def _disagreement(copies: list[_Copy]) -> str:
    """'the group's attributes (zarr.json) and done/zarr.json disagree: c = 0.4 in the one,
    0.5 in the other'."""
    readable = [c for c in copies if c.value is not None]
    for a in readable:
        for b in readable:
            if a.value != b.value:
                diff = differences(a.value, b.value, ("in the one", "in the other"))
                return f"{a.where} and {b.where} disagree ({'; '.join(diff[:2])})"
    return "every copy of them fails its digest"


def open_view(path: str | os.PathLike, grid: Grid | None = None,
              wanted: dict | None = None) -> StoreView:
    """Open a basin store for reading; ParameterError (one line) if it is none, or if its
    metadata cannot be read, StoreDamaged if the parameters its tiles were computed with
    cannot be recovered. ``grid``: the sweep's grid when known (else from the attributes);
    ``wanted``: the attributes of a sweep about to resume it (they are tried too).

    The sweep attributes are in three copies (the group's attributes; the ``done`` array's, in
    the consolidated metadata and in its zarr.json), each with its digest. When they differ
    (one was damaged or edited), the one a computed tile verifies under is the one the tiles
    were computed with; without any tile, the one that matches its digest. The copies that
    differ from it are listed in ``problems`` (a resume rewrites them)."""
    p = Path(path)
    check_is_store(p)
    attrs, copies = _copies(p)
    if attrs is not None and MARK not in attrs and copies[2].value is None:
        raise ParameterError(f"{path} is not a coin basin store")
    mark = attrs.get(MARK) if attrs is not None else None
    fmt = mark.get("format") if isinstance(mark, dict) else None
    if fmt is not None and fmt != FORMAT:
        raise ParameterError(f"{path} is a coin basin store of format {fmt}, this version "
                             f"reads format {FORMAT}: recompute it (overwrite)",
                             parameters=("overwrite",))
    if all(c.value is None for c in copies):
        raise StoreDamaged(f"{path}: its metadata cannot be read: the store is damaged; "
                           "overwrite starts the sweep again", parameters=("overwrite",))
    proven, proof = _prove(p, copies, wanted)
    if proven is None:
        raise StoreDamaged(f"{path}: {proof}", parameters=("overwrite",))
    problems = []
    for c in copies:
        if c.value is None:
            problems.append(f"{c.where} cannot be read")
        elif c.value != proven:
            problems.append(f"{c.where}: " + "; ".join(
                differences(c.value, proven, ("there", _PROOF[proof]))))
        elif not c.consistent:
            problems.append(f"{c.where}: the digest stored with them is not theirs")
    extra = {k: v for k, v in (attrs or {}).items() if k != MARK and k not in COMPARED_ATTRS}
    full = {**root_attrs(proven), **extra}
    if grid is None or (wanted is not None and owned(wanted) != proven):
        try:
            grid = grid_of(full)
        except Exception as exc:  # noqa: BLE001
            raise StoreDamaged(f"{path}: its metadata cannot be read ({_short(exc)}): the "
                               "store is damaged; overwrite starts the sweep again",
                               parameters=("overwrite",)) from None
    return StoreView(p, full, grid, parameters_digest(proven), problems, proof)


def _short(exc: BaseException) -> str:
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if "checksum" in text.lower():
        return "checksum mismatch"
    return text if len(text) <= 100 else text[:97] + "..."


# -- comparing metadata --------------------------------------------------------------------------
# Where a user may add entries to the metadata the sweep wrote (a group or array attribute, an
# array in the consolidated listing): those are theirs, kept, and never damage.
_OPEN_KEYS = ("attributes", "metadata")


def _same(found, want) -> bool:
    if isinstance(want, float) and isinstance(found, float) and math.isnan(want):
        return math.isnan(found)
    return type(found) is type(want) and found == want


def _agrees(found, want, extensible: bool = False) -> bool:
    """Whether parsed metadata ``found`` holds what the sweep wrote, ``want``: equal, except
    for entries added where a user may add them."""
    if isinstance(want, dict):
        if not isinstance(found, dict) or not (extensible or set(found) == set(want)):
            return False
        return all(k in found and _agrees(found[k], v, k in _OPEN_KEYS)
                   for k, v in want.items())
    if isinstance(want, list):
        return (isinstance(found, list) and len(found) == len(want)
                and all(_agrees(f, w) for f, w in zip(found, want, strict=True)))
    return _same(found, want)


def _merged(found, want, extensible: bool = False):
    """``want`` with the entries a user added to ``found`` (where they may add them)."""
    if not (isinstance(want, dict) and isinstance(found, dict)):
        return want
    out = {k: _merged(found.get(k), v, k in _OPEN_KEYS) for k, v in want.items()}
    if extensible:
        out.update({k: v for k, v in found.items() if k not in want})
    return out


def _differs(file: Path, data: bytes) -> bool:
    """Whether a file of the store does not hold what the template has for it: a metadata file
    compared parsed, on what the sweep wrote; a coordinate chunk byte for byte."""
    if file.name == "zarr.json":
        found = _load_json(file)
        return found is None or not _agrees(found, json.loads(data))
    try:
        return file.read_bytes() != data
    except OSError:
        return True


def _repaired(file: Path, data: bytes) -> bytes:
    """What a differing file is rewritten with: the template's, with what a user added."""
    if file.name != "zarr.json":
        return data
    found = _load_json(file)
    merged = _merged(found, json.loads(data))
    return data if merged == json.loads(data) else _json_bytes(merged)


def damaged_metadata(view: StoreView) -> list[str]:
    """Keys of the metadata files and coordinate chunks that do not hold what the store's
    (proven) parameters give."""
    return [key for key, data in template(view.attrs, view.grid).items()
            if _differs(view.path / key, data)]


def _write_atomically(target: Path, data: bytes) -> None:
    """Write a file of the store (or of its cost records) whole, through a temporary file
    beside it, renamed into place."""
    # "*.partial": the suffix by which the next writer of a tile finds a dead writer's file
    tmp = target.with_name(f"{target.name}.{socket.gethostname()}-{os.getpid()}-"
                           f"{threading.get_ident()}.partial")
    with atomic_output(target, tmp) as out:
        out.write_bytes(data)


def _chunk_file(root: Path, name: str, tile: tuple[int, int]) -> Path:
    return root / name / "c" / str(tile[0]) / str(tile[1])


def _read_chunk(view: StoreView, name: str, tile: tuple[int, int]) -> np.ndarray:
    """One tile's chunk of array ``name``, cut to the tile (ChunkError, OSError if it cannot
    be read; a missing chunk file is FileNotFoundError)."""
    dtype = DONE_DTYPE if name == "done" else DTYPES[name]
    chunk = (1, 1) if name == "done" else view.grid.chunk
    values = decode_chunk(_chunk_file(view.path, name, tile).read_bytes(), dtype, chunk)
    if name == "done":
        return values
    s0, s1 = view.grid.tile_slices(tile)
    return values[:s0.stop - s0.start, :s1.stop - s1.start]


def _done_flags(view: StoreView, tiles=None) -> tuple[np.ndarray, set]:
    """The ``done`` digests (of ``tiles`` only, if given; 0 where a tile has none), and the
    tiles whose digest cannot be read."""
    t0, t1 = view.grid.tile_grid
    flags = np.zeros((t0, t1), dtype=np.uint32)
    unreadable = set()
    for tile in ([(i, j) for i in range(t0) for j in range(t1)] if tiles is None else tiles):
        try:
            flags[tile] = _read_chunk(view, "done", tile)[0, 0]
        except FileNotFoundError:
            pass  # not done
        except Exception:  # noqa: BLE001 - any failure to read is damage
            unreadable.add(tuple(tile))
    return flags, unreadable


def _read_tile(view: StoreView, tile: tuple[int, int]) -> tuple[dict | None, str | None]:
    """One tile's arrays, or why they cannot be read."""
    out = {}
    for name in ARRAY_NAMES:
        key = f"chunk {name}/c/{tile[0]}/{tile[1]}"
        try:
            out[name] = _read_chunk(view, name, tile)
        except FileNotFoundError:
            return None, f"{key} is missing"
        except Exception as exc:  # noqa: BLE001 - any failure to read is damage
            return None, f"{key} cannot be read ({_short(exc)})"
    return out, None


def _judge(view: StoreView, tile, flag: int, data: dict | None, why: str | None):
    if data is None:
        return Tile.DAMAGED, None, why
    if tile_digest(tile, data, view.parameters) != flag:
        return Tile.DAMAGED, None, ("its data do not match its digest (a chunk from another "
                                    "tile, or changed on disk)")
    return Tile.DONE, data, None


def scan(view: StoreView, *, with_data: bool = False,
         tiles: Iterable[tuple[int, int]] | None = None) -> Iterator[tuple]:
    """Check every tile (or ``tiles``): yield (tile, Tile state, arrays or None, why damaged).
    Arrays are given for DONE tiles when ``with_data``. Tiles are read one at a time (one
    chunk file per array), so memory stays flat."""
    t0, t1 = view.grid.tile_grid
    wanted = None if tiles is None else [tuple(t) for t in tiles]
    flags, unreadable = _done_flags(view, wanted)
    for tile in ([(i, j) for i in range(t0) for j in range(t1)] if wanted is None else wanted):
        if tile in unreadable:
            yield tile, Tile.DAMAGED, None, "its done digest cannot be read"
            continue
        if not flags[tile]:
            yield tile, Tile.MISSING, None, None
            continue
        data, why = _read_tile(view, tile)
        state, data, why = _judge(view, tile, int(flags[tile]), data, why)
        yield tile, state, (data if with_data else None), why


def _leftovers(path: Path) -> int:
    return sum(1 for _ in path.glob("*/c/**/*.partial"))


def check(path: str | os.PathLike, *, repair_with: dict | None = None,
          view: StoreView | None = None) -> StoreCheck:
    """Check every tile and every metadata file of a store (read only, unless
    ``repair_with`` gives the attributes to rewrite differing metadata from: what the sweep
    wrote is rewritten, what a user added to it is kept)."""
    t0 = time.perf_counter()
    view = view or open_view(path)
    attrs = repair_with if repair_with is not None else view.attrs
    files = template(attrs, view.grid)
    metadata = [key for key, data in files.items() if _differs(view.path / key, data)]
    repaired = []
    if repair_with is not None:
        for key in metadata:
            target = view.path / key
            target.parent.mkdir(parents=True, exist_ok=True)
            _write_atomically(target, _repaired(target, files[key]))
            repaired.append(key)
    done = np.zeros(view.grid.tile_grid, dtype=bool)
    damaged = {}
    for tile, state, _, why in scan(view):
        if state is Tile.DONE:
            done[tile] = True
        elif state is Tile.DAMAGED:
            damaged[tile] = why
    return StoreCheck(str(path), view.attrs, view.grid, done, damaged, metadata, repaired,
                      _leftovers(view.path), time.perf_counter() - t0, list(view.problems))


def prepare(path: str | os.PathLike, attrs: dict, spec: SweepSpec,
            overwrite: bool = False) -> StoreCheck:
    """Create the store, or open an existing one with the same parameters, and check it: which
    tiles are done (verified), which damaged. A store with other parameters (those its tiles
    were computed with, whatever its metadata say now) is refused with a message naming them
    unless ``overwrite``. Metadata that differ from those of the parameters are rewritten
    (keeping what a user added). Several processes may call this at once on one path: one
    creates the store, the others open it."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{path} exists and is not a directory")
    if path.is_dir() and not is_store(path) and any(path.iterdir()):
        raise ParameterError(f"{path} exists and is not a Zarr store: refusing to touch it")
    if overwrite or not is_store(path):
        path.parent.mkdir(parents=True, exist_ok=True)
        _create(path, attrs, spec, overwrite)
    else:
        tidy(path)
    view = open_view(path, spec.grid, wanted=attrs)
    diff = differences(view.attrs, attrs)
    if diff:
        changed = ""
        if view.problems:
            when = "its tiles were computed" if view.proof == "tiles" else "it was created"
            changed = f" (its metadata were changed after {when}: {view.problems[0]})"
        raise ParameterError(f"{path} holds a different sweep: {'; '.join(diff[:4])}"
                             f"{' ...' if len(diff) > 4 else ''}{changed}. Run again with the "
                             "store's parameters to resume it, or overwrite to "
                             "replace it", parameters=("overwrite",))
    cost_dir(path).mkdir(exist_ok=True)
    return check(path, repair_with=attrs, view=view)


def has_digest(path: str | os.PathLike, tile: tuple[int, int]) -> bool:
    """Whether a tile's ``done`` chunk exists (one stat). Written last, after all its data, so a
    digest that appears while a sweep runs means another process finished the tile."""
    return _chunk_file(Path(path), "done", tile).is_file()


def tile_done(path: str | os.PathLike, tile: tuple[int, int],
              grid: Grid | None = None) -> bool:
    """Whether one tile is done and verified (read now, from disk; without a ``done`` chunk
    file it is not, which takes one stat to know)."""
    if not _chunk_file(Path(path), "done", tile).is_file():
        return False
    view = open_view(path, grid)
    return any(state is Tile.DONE for _, state, _, _ in scan(view, tiles=[tuple(tile)]))


# -- writing -------------------------------------------------------------------------------------
def _remove_partials(path: Path, tile: tuple[int, int]) -> None:
    """Temporary chunk files of this tile's chunks left by a writer that died (only the owner
    of a tile's claim writes it, so any such file is an orphan)."""
    for name in (*ARRAY_NAMES, "done"):
        folder = path / name / "c" / str(tile[0])
        if folder.is_dir():
            for leftover in folder.glob(f"{tile[1]}.*.partial"):
                with contextlib.suppress(OSError):
                    leftover.unlink()


def _store_parameters(path: Path) -> bytes:
    """The parameters digest a tile written to the store now binds: the one in the ``done``
    array's zarr.json (:func:`prepare` made it the sweep's before any tile was computed)."""
    digest = _dig(_load_json(path / "done" / "zarr.json"), "attributes", "digest")
    try:
        return bytes.fromhex(digest)
    except (TypeError, ValueError):
        raise StoreDamaged(f"{path}: the parameters digest in done/zarr.json cannot be read: "
                           "the store was damaged while the sweep ran; rerun it to repair "
                           "the store") from None


def write_tile(path: str | os.PathLike, spec: SweepSpec, result: TileResult,
               parameters: bytes | None = None) -> None:
    """Write one tile's arrays, its cost, and last its ``done`` digest, which binds the
    parameters digest ``parameters`` (by default, the store's)."""
    path = Path(path)
    parameters = _store_parameters(path) if parameters is None else parameters
    tile = result.tile
    i, j = tile
    _remove_partials(path, tile)
    for name in ARRAY_NAMES:
        _write_atomically(_chunk_file(path, name, tile),
                          encode_chunk(result.arrays[name], DTYPES[name], FILLS[name],
                                       spec.grid.chunk))
    cost = {"cpu_seconds": result.cpu_seconds, "host": socket.gethostname(), "pid": os.getpid()}
    if result.mirror_of is not None:
        cost["mirror_of"] = list(result.mirror_of)
    _write_atomically(cost_dir(path) / f"tile_{i}_{j}.json", json.dumps(cost).encode())
    digest = np.array([[tile_digest(tile, result.arrays, parameters)]])
    _write_atomically(_chunk_file(path, "done", tile),
                      encode_chunk(digest, DONE_DTYPE, 0, (1, 1)))


def read_done(path: str | os.PathLike) -> np.ndarray:
    """Per tile, 1 if done and verified."""
    return check(path).done.astype(np.uint8)


def cost_dir(path: str | os.PathLike) -> Path:
    """Where a store's cost records and claims live: beside it, ``out.zarr.cost/``."""
    return Path(f"{os.fspath(path).rstrip(os.sep)}.cost")


def claims_dir(path: str | os.PathLike) -> Path:
    return cost_dir(path) / "claims"


def record_run(path: str | os.PathLike, run: dict) -> None:
    """Append one invocation's record (wall time, tiles, mode) to ``out.zarr.cost/runs.jsonl``
    (only the coordinating process writes it; one write of one line, so that the records of
    processes sharing a store do not interleave)."""
    target = cost_dir(path) / "runs.jsonl"
    target.parent.mkdir(parents=True, exist_ok=True)
    with open(target, "a") as fh:
        fh.write(json.dumps(run) + "\n")


def read_costs(path: str | os.PathLike, tile_grid: tuple[int, int]) -> tuple[np.ndarray, list]:
    """Per-tile CPU seconds (NaN where unknown) and the run records of a store."""
    seconds = np.full(tile_grid, math.nan)
    folder = cost_dir(path)
    if folder.is_dir():
        for f in folder.glob("tile_*.json"):
            try:
                i, j = (int(x) for x in f.stem.split("_")[1:3])
                if i < tile_grid[0] and j < tile_grid[1]:
                    seconds[i, j] = json.loads(f.read_text())["cpu_seconds"]
            except (ValueError, KeyError, TypeError, OSError):
                pass  # a damaged cost record loses the cost, never the results
    return seconds, read_runs(path)


def read_runs(path: str | os.PathLike) -> list[dict]:
    """The run records of ``out.zarr.cost/runs.jsonl`` (a damaged line is skipped)."""
    runs = []
    log = cost_dir(path) / "runs.jsonl"
    if log.is_file():
        for line in log.read_text().splitlines():
            try:
                runs.append(json.loads(line))
            except ValueError:
                continue
    return runs


# -- reading -------------------------------------------------------------------------------------
def read_basin(path: str | os.PathLike) -> Basin:
    """Read a store back, every tile checked: cells of tiles not done, or damaged, read as not
    computed (their tiles are listed in ``Basin.damaged``)."""
    view = open_view(path)
    grid = view.grid
    arrays = {name: np.full(grid.shape, FILLS[name], dtype=VARIABLES[name][0])
              for name in ARRAY_NAMES}
    done = np.zeros(grid.tile_grid, dtype=np.uint8)
    damaged = []
    for tile, state, data, _ in scan(view, with_data=True):
        if state is Tile.DONE:
            s0, s1 = grid.tile_slices(tile)
            for name in ARRAY_NAMES:
                arrays[name][s0, s1] = data[name]
            done[tile] = 1
        elif state is Tile.DAMAGED:
            damaged.append(tile)
    tile_seconds, runs = read_costs(view.path, grid.tile_grid)
    return Basin(attrs=view.attrs, arrays=arrays, done=done, tile_seconds=tile_seconds,
                 runs=runs, path=str(path), damaged=damaged)


def run_record(started: float, wall: float, tiles: int, cells: int, mode: str, workers: int,
               interrupted: bool, kernel_seconds: float = 0.0,
               store_seconds: float = 0.0) -> dict:
    """One invocation's record: when, how long, what it computed, and where the time went (the
    tiles' wall time in the kernels and in writing, summed over threads)."""
    return {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(started)),
            "wall_seconds": round(wall, 3), "tiles": tiles, "cells": cells, "mode": mode,
            "workers": workers, "interrupted": interrupted, "host": socket.gethostname(),
            "pid": os.getpid(), "kernel_seconds": round(kernel_seconds, 3),
            "store_seconds": round(store_seconds, 3)}


def check_store_writable(path: str | os.PathLike) -> None:
    """Raise NotWritable (one line) unless the store (or the folder it will be created in) and
    its side folder accept new files: a read-only mount or a full disk is found before any
    work."""
    import errno

    from .paths import REASONS, NotWritable, check_writable

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


__all__ = ["ARRAY_NAMES", "StoreCheck", "StoreDamaged", "StoreView", "Tile", "check",
           "check_is_store", "check_store_writable", "claims_dir", "cost_dir", "creation_lock",
           "damaged_metadata", "differences", "flatten_attrs", "grid_of", "has_digest",
           "is_store", "open_view", "prepare", "read_basin", "read_costs", "read_done",
           "read_runs", "record_run", "run_record", "scan", "show_value", "template", "tidy",
           "tile_digest", "tile_done", "write_tile"]
