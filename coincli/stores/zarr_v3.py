"""Zarr v3 groups written and read by coin's stores (basin and fractions) without zarr-python:
the one way the package writes and reads Zarr.

Why not zarr-python: a tile is one chunk in each of seven arrays, and zarr-python's
``array[...] = block`` spends about 4 ms a chunk in its asyncio machinery against 0.5 ms here
(benchmarks/zarr_route.py measures both on the default 512 x 512 map), and importing it costs a
quarter of a second. What is written is what zarr-python writes and reads (tests/test_store.py
compares chunk bytes and metadata with it): a group whose metadata are consolidated into its
``zarr.json``, arrays of the codecs :data:`CODECS` (little-endian bytes, zstd level 0, then a
CRC-32C of the compressed chunk, with numcodecs and google-crc32c, the libraries Zarr's own
codecs call), chunk keys ``NAME/c/I/J``, every chunk written (also one equal to the fill
value). So ``xarray.open_zarr`` and ``zarr.open_group`` open a store directly.

What this module owns: encoding and decoding a chunk (:func:`encode_chunk`, which a damaged
chunk fails: a checksum, a length), an array's metadata (:class:`ArraySpec`), a group's
(:func:`group_metadata`), writing a file whole through a temporary beside it
(:func:`write_atomically`), and creating a store whole: built in ``.NAME.creating-HOST-PID``
beside it and renamed into place under a lock (``.NAME.lock``, ``flock``), so that processes
racing to create one store all end up in the winner's (:func:`create_store`).
"""

from __future__ import annotations

import contextlib
import functools
import glob
import json
import math
import os
import shutil
import socket
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..files import atomic_output

ZSTD_LEVEL = 0  # a tile compresses 3-10x at level 0 already
# Every array's codecs, as Zarr v3 names them: bytes little-endian, zstd, then a CRC-32C
CODECS = ({"name": "bytes", "configuration": {"endian": "little"}},
          {"name": "zstd", "configuration": {"level": ZSTD_LEVEL, "checksum": False}},
          {"name": "crc32c"})
PARTIAL = ".partial"  # the suffix of a file being written (a killed writer's is an orphan)


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
    ``fill`` to the chunk's shape (a chunk at an array's far edge is smaller), its values
    little-endian in C order, zstd-compressed, then the CRC-32C of the compressed bytes
    (little-endian uint32)."""
    full = np.full(chunk, fill, dtype=np.dtype(dtype).newbyteorder("<"))
    full[tuple(slice(0, n) for n in np.shape(block))] = block
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
    size = wanted.itemsize * math.prod(chunk)
    if len(raw) != size:
        raise ChunkError(f"{len(raw)} bytes where {size} belong")
    return np.frombuffer(raw, dtype=wanted).reshape(chunk).astype(np.dtype(dtype))


def fill_json(fill):
    """A fill value as Zarr v3 writes it in JSON (NaN and infinities as strings)."""
    if isinstance(fill, float) and not math.isfinite(fill):
        return "NaN" if math.isnan(fill) else ("Infinity" if fill > 0 else "-Infinity")
    return fill


def fill_value(text, dtype: str):
    """A fill value as read from JSON, as the array's dtype holds it."""
    if isinstance(text, str):
        return {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}[text]
    return np.dtype(dtype).type(text).item()


def codecs_of(dtype: str) -> list[dict]:
    """:data:`CODECS` as Zarr writes them for ``dtype``: single bytes have no byte order."""
    if np.dtype(dtype).itemsize == 1:
        return [{"name": "bytes"}, *CODECS[1:]]
    return list(CODECS)


@dataclass(frozen=True)
class ArraySpec:
    """One array of a group: what its zarr.json says, and where its chunks are."""

    name: str
    shape: tuple[int, ...]
    chunks: tuple[int, ...]
    dtype: str
    fill: object
    dims: tuple[str, ...]
    attributes: dict = field(default_factory=dict, compare=False)

    def metadata(self) -> dict:
        """The array's zarr.json, key for key as Zarr v3 writes it."""
        return {"shape": list(self.shape), "data_type": self.dtype,
                "chunk_grid": {"name": "regular",
                               "configuration": {"chunk_shape": list(self.chunks)}},
                "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
                "fill_value": fill_json(self.fill), "codecs": codecs_of(self.dtype),
                "attributes": self.attributes, "dimension_names": list(self.dims),
                "zarr_format": 3, "node_type": "array", "storage_transformers": []}

    @classmethod
    def of(cls, name: str, metadata: dict) -> ArraySpec:
        """The spec of an array from its zarr.json (ours or zarr-python's); ValueError unless
        it is one this module can read (regular chunks, '/' keys, :data:`CODECS`)."""
        try:
            dtype = metadata["data_type"]
            chunks = tuple(metadata["chunk_grid"]["configuration"]["chunk_shape"])
            codecs = [c["name"] for c in metadata["codecs"]]
            separator = metadata["chunk_key_encoding"].get("configuration", {}).get(
                "separator", "/")
            spec = cls(name, tuple(metadata["shape"]), chunks, dtype,
                       fill_value(metadata["fill_value"], dtype),
                       tuple(metadata.get("dimension_names") or ()),
                       metadata.get("attributes") or {})
        except (KeyError, TypeError, AttributeError) as exc:
            raise ValueError(f"array {name}: its metadata lack {exc}") from None
        if codecs != [c["name"] for c in CODECS] or separator != "/":
            raise ValueError(f"array {name}: codecs {codecs} and keys '{separator}' are not "
                             "those of a coin store")
        return spec

    def key(self, index: tuple[int, ...]) -> str:
        """The chunk's key: ``NAME/c/I/J``."""
        return "/".join((self.name, "c", *(str(int(i)) for i in index)))

    def file(self, root: Path, index: tuple[int, ...]) -> Path:
        return root.joinpath(self.name, "c", *(str(int(i)) for i in index))

    def read(self, root: Path, index: tuple[int, ...]) -> np.ndarray:
        """The chunk at ``index``, cut to the array's edge (FileNotFoundError if it was never
        written, ChunkError or OSError if it cannot be read)."""
        values = decode_chunk(self.file(root, index).read_bytes(), self.dtype, self.chunks)
        edge = tuple(slice(0, min(c, n - i * c))
                     for i, c, n in zip(index, self.chunks, self.shape, strict=True))
        return values[edge]

    def write(self, root: Path, index: tuple[int, ...], block: np.ndarray) -> None:
        """Write the chunk at ``index`` whole (the block padded with the fill value)."""
        write_atomically(self.file(root, index),
                         encode_chunk(block, self.dtype, self.fill, self.chunks))

    def resized(self, shape: tuple[int, ...]) -> ArraySpec:
        return ArraySpec(self.name, tuple(shape), self.chunks, self.dtype, self.fill,
                         self.dims, self.attributes)


def json_bytes(document: dict) -> bytes:
    return json.dumps(document, indent=2, allow_nan=True).encode()  # as Zarr writes metadata


def group_metadata(attributes: dict, arrays: dict[str, dict]) -> dict:
    """A group's zarr.json: its attributes and the metadata of its arrays, consolidated."""
    return {"attributes": attributes, "zarr_format": 3,
            "consolidated_metadata": {"kind": "inline", "must_understand": False,
                                      "metadata": {k: arrays[k] for k in sorted(arrays)}},
            "node_type": "group"}


def group_files(attributes: dict, arrays: list[ArraySpec]) -> dict[str, bytes]:
    """The metadata files of a group (its zarr.json and each array's), by key."""
    metadata = {a.name: a.metadata() for a in arrays}
    files = {"zarr.json": json_bytes(group_metadata(attributes, metadata))}
    files.update({f"{name}/zarr.json": json_bytes(doc) for name, doc in metadata.items()})
    return files


def load_json(file: Path):
    """A metadata file parsed, or None if it cannot be read or parsed."""
    try:
        return json.loads(file.read_bytes())
    except (OSError, ValueError):
        return None


def dig(document, *keys):
    """``document[k0][k1]...``, or None where a level is missing or no mapping."""
    for key in keys:
        if not isinstance(document, dict):
            return None
        document = document.get(key)
    return document


def is_store(path: str | os.PathLike) -> bool:
    return (Path(path) / "zarr.json").is_file()


def write_atomically(target: Path, data: bytes) -> None:
    """Write a file whole, through a temporary file beside it (``NAME.HOST-PID-THREAD``
    :data:`PARTIAL`), renamed into place."""
    tmp = target.with_name(f"{target.name}.{socket.gethostname()}-{os.getpid()}-"
                           f"{threading.get_ident()}{PARTIAL}")
    with atomic_output(target, tmp) as out:
        out.write_bytes(data)


def remove_partials(target: Path) -> None:
    """Remove the temporary files of writes of ``target`` (:func:`write_atomically`'s): call
    only where no other live writer can be writing it (a chunk of a tile or batch whose claim
    the caller holds), so that they are the orphans of a writer that died."""
    for leftover in target.parent.glob(f"{glob.escape(target.name)}.*{PARTIAL}"):
        with contextlib.suppress(OSError):
            leftover.unlink()


def write_files(root: Path, files: dict[str, bytes]) -> None:
    for key, data in files.items():
        target = root / key
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)


@contextlib.contextmanager
def creation_lock(path: Path, blocking: bool = True) -> Iterator[bool]:
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


def tidy(path: Path) -> None:
    """Remove what a creation killed midway left beside an existing store (its temporary
    directory, its lock file), unless a creation is running now."""
    if not path.parent.is_dir():
        return
    if not any(path.parent.glob(f".{path.name}.creating-*")) and \
            not path.with_name(f".{path.name}.lock").exists():
        return
    with contextlib.suppress(OSError), creation_lock(path, blocking=False) as held:
        if held:
            remove_orphans(path)


def create_store(path: Path, files: Callable[[], dict[str, bytes]], *,
                 replace: bool = False, folders: tuple[str, ...] = (),
                 side: Path | None = None) -> bool:
    """Create the store at ``path`` from ``files()`` (key -> bytes) and the empty ``folders``
    in it (its records folder), under the creation lock, whole or not at all; unless one exists
    (another process won the race), or ``replace``. The ``side`` folder beside it (where an
    older version kept a store's records) is removed: it holds an older store's. True if this
    call created it."""
    with creation_lock(path):
        if is_store(path) and not replace:
            return False
        remove_orphans(path)
        if is_store(path):
            shutil.rmtree(path)
        elif path.is_dir() and not any(path.iterdir()):
            path.rmdir()
        tmp = path.with_name(creating_name(path))
        try:
            write_files(tmp, files())
            for folder in folders:
                (tmp / folder).mkdir(parents=True, exist_ok=True)
            if side is not None:
                shutil.rmtree(side, ignore_errors=True)  # the records of an older store
            os.rename(tmp, path)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    return True


__all__ = ["CODECS", "PARTIAL", "ArraySpec", "ChunkError", "codecs_of", "create_store",
           "creating_name", "creation_lock", "decode_chunk", "dig", "encode_chunk",
           "fill_json", "fill_value", "group_files", "group_metadata", "is_store",
           "json_bytes", "load_json", "remove_orphans", "remove_partials", "tidy",
           "write_atomically", "write_files"]
