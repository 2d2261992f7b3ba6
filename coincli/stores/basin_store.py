"""The Zarr store of a basin sweep, owned by one object (:class:`BasinStore`): its path, its
metadata (read once, when it is opened), the parameters digest its tiles bind, its claims and
cost records, reading and writing tiles, verifying and repairing it.

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
      .coin/                        the store's records (:func:`~coincli.stores.basin_layout.
        tile_I_J.json               records_dir`), which no array is named after and which
        runs.jsonl                  Zarr does not read: each tile's CPU seconds and who
        claims/tile_I_J             computed it, one line per invocation (wall time, tiles,
                                    mode), and the claims of the tiles being computed
                                    (:mod:`coincli.engines.claims`). They differ from run to
                                    run; everything else is bit-identical however the store
                                    was computed. A store of 0.10.0 keeps them beside it, in
                                    out.zarr.cost/, read and written while it is there
    .out.zarr.lock, .out.zarr.creating-HOST-PID  beside the store while it is created (the
                                    creation lock and the store being built, renamed into
                                    place): they exist before the store's folder does

Every data array is chunked exactly like the tiles, so one tile is one chunk in every array and
concurrent writers (threads, Dask workers, other processes) never touch the same file. Every
chunk ends with a CRC-32C of its compressed bytes (:mod:`coincli.stores.zarr_v3`), so a chunk
damaged on disk fails to read instead of decoding to garbage. A tile's ``done`` entry, written
after all its data, is its digest (:func:`~coincli.stores.basin_layout.tile_digest`): a 32-bit
BLAKE2b of its data, *its tile index and the digest of the parameters it was computed with*, so
that a chunk copied from another tile (a valid chunk, at the wrong place) or a missing chunk
(read back as fill values) is caught too, and so is a parameter changed in the metadata after
the tile was computed. A tile is done only if its ``done`` digest equals the digest of the data
its chunks read back as (:meth:`BasinStore.scan`); otherwise it is recomputed on resume
(recomputing gives the same bytes), counted as not computed by ``stats`` and ``render``, and
listed by ``coin basin verify``. A ``.partial`` file left by a killed writer is removed by the
next writer of that tile.

The sweep's attributes are kept in three copies (:mod:`coincli.stores.basin_metadata`); on opening,
copies that differ are judged by the tiles: the parameters a computed tile verifies under are
those it was computed with, and the copies that differ from them are damage, rebuilt on resume.
``quarter_turns`` carries ``missing_value`` so xarray masks cells without a label to NaN
(``mask_and_scale=False`` keeps the int16 values).
"""

from __future__ import annotations

import enum
import json
import math
import os
import shutil
import socket
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..engines.basin import Prepared
from ..grid import Grid, TileResult
from ..params import ParameterError
from ..stats import BasinCounts, BasinStats
from . import basin_metadata as meta
from .basin_layout import (
    ARRAY_NAMES,
    RECORDS,
    StoreRecords,
    StoreView,
    check_store_writable,
    legacy_records_dir,
    read_tile,
    read_view,
    remove_dead_probes,
    root_lost,
    template,
    tile_digest,
)
from .basin_schema import (
    FILLS,
    VARIABLES,
    resumable_as,
    root_attrs,
)
from .dataset import Basin
from .zarr_v3 import (
    PARTIAL,
    ArraySpec,
    create_store,
    is_store,
    remove_partials,
    tidy,
    write_atomically,
)


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

    def to_dict(self) -> dict:
        total = int(self.done.size)
        unrepaired = [k for k in self.metadata if k not in self.repaired]
        return {"path": self.path, "intact": self.intact, "tiles": total,
                "tiles_done": self.tiles_done,
                "not_computed": total - self.tiles_done - len(self.damaged),
                "damaged": [{"tile": list(t), "reason": why}
                            for t, why in sorted(self.damaged.items())],
                "metadata": unrepaired, "parameters_changed": list(self.problems),
                "leftover_temporary_files": self.leftovers, "seconds": self.seconds}

    def __repr__(self) -> str:
        return (f"StoreCheck({self.path!r}, intact={self.intact}, {self.tiles_done} of "
                f"{self.done.size} tiles done, {len(self.damaged)} damaged, "
                f"{len(self.metadata)} metadata files differing)")


class BasinStore(StoreRecords):
    """A basin store at ``path``: opened (its metadata read, once) on first use, by
    :meth:`open`, or by :meth:`create_or_resume` for a sweep about to write to it (which is
    what the sweep engine's :meth:`prepare` does). Picklable: a Dask worker writes its tiles
    through the same object."""

    def __init__(self, path: str | os.PathLike, view: StoreView | None = None):
        self.path = Path(path)
        self._view = view  # its metadata as read (None: read on first use)
        self.read_only = False  # a complete store that cannot be written: a sweep only reads it

    def __repr__(self) -> str:
        return f"BasinStore({str(self.path)!r})"

    @property
    def name(self) -> str:
        return str(self.path)

    def exists(self) -> bool:
        """Whether a store is there (of this sweep or not: :meth:`open` says); one whose
        root ``zarr.json`` is lost is (:func:`root_lost`)."""
        return is_store(self.path) or root_lost(self.path)

    # -- opening ------------------------------------------------------------------------------
    @classmethod
    def open(cls, path: str | os.PathLike, grid: Grid | None = None,
             wanted: dict | None = None) -> BasinStore:
        """Open a basin store; ParameterError (one line) if it is none, or if its metadata
        cannot be read, StoreDamaged if the parameters its tiles were computed with cannot be
        recovered. ``grid``: the sweep's grid when known (else from the attributes);
        ``wanted``: the attributes of a sweep about to resume it (they are tried too).

        When the three copies of the sweep attributes differ (one was damaged or edited), the
        one a computed tile verifies under is the one the tiles were computed with; without
        any tile, the one that matches its digest. The copies that differ from it are listed
        in ``problems`` (a resume rewrites them)."""
        return cls(path, read_view(Path(path), grid, wanted))

    @property
    def view(self) -> StoreView:
        if self._view is None:
            self._view = read_view(self.path)
        return self._view

    @property
    def attrs(self) -> dict:
        return self.view.attrs

    @property
    def grid(self) -> Grid:
        return self.view.grid

    @property
    def parameters(self) -> bytes:
        return self.view.parameters

    @property
    def problems(self) -> list[str]:
        return list(self.view.problems)

    @property
    def specs(self) -> dict[str, ArraySpec]:
        return self.view.specs

    def create_or_resume(self, attrs: dict, grid: Grid,
                         overwrite: bool = False) -> StoreCheck:
        """Create the store, or open an existing one with the same parameters, and check it:
        which tiles are done (verified), which damaged. A store with other parameters (those
        its tiles were computed with, whatever its metadata say now) is refused with a message
        naming them unless ``overwrite``. Metadata that differ from those of the parameters
        are rewritten (keeping what a user added). Several processes may call this at once on
        one path: one creates the store, the others open it."""
        path = self.path
        if path.exists() and not path.is_dir():
            raise ParameterError(f"{path} exists and is not a directory")
        if path.is_dir() and not self.exists() and any(path.iterdir()):
            raise ParameterError(f"{path} exists and is not a Zarr store: refusing to touch it")
        if overwrite and root_lost(path):  # no store to Zarr (create_store): removed here
            shutil.rmtree(path)
        if overwrite or not self.exists():
            path.parent.mkdir(parents=True, exist_ok=True)
            create_store(path, lambda: template(attrs, grid), replace=overwrite,
                         folders=(RECORDS,), side=legacy_records_dir(path))
        elif not self.read_only:
            tidy(path)
            remove_dead_probes(path)
        self._view = read_view(path, grid, wanted=attrs)
        earlier = resumable_as(self.attrs, attrs)  # a store of an earlier version: resumed as is
        if earlier is not None and not meta.differences(self.attrs, earlier):
            attrs = root_attrs(earlier)
        diff = meta.differences(self.attrs, attrs)
        if diff:
            changed = ""
            if self.problems:
                when = ("its tiles were computed" if self.view.proof == "tiles"
                        else "it was created")
                changed = f" (its metadata were changed after {when}: {self.problems[0]})"
            raise ParameterError(f"{path} holds a different sweep: {'; '.join(diff[:4])}"
                                 f"{' ...' if len(diff) > 4 else ''}{changed}. Run again with "
                                 "the store's parameters to resume it, or overwrite to "
                                 "replace it", parameters=("overwrite",))
        if not self.read_only:
            self.records_dir.mkdir(exist_ok=True)
        return self.check(repair_with=attrs)

    def check_writable(self, overwrite: bool = False) -> None:
        """Raise NotWritable (one line, :func:`check_store_writable`) unless a sweep can write
        the store, before any work; but a store complete and intact already needs no write
        (unless ``overwrite``): on a read-only mount or a full disk it is opened
        :attr:`read_only`, and a sweep of it has nothing to do."""
        from ..files import NotWritable

        try:
            check_store_writable(self.path)
        except NotWritable:
            if overwrite or not self.exists() or not self._complete():
                raise
            self.read_only = True

    def _complete(self) -> bool:
        """Whether every tile is done and verified, and every metadata file whole (read)."""
        try:
            found = BasinStore.open(self.path).check()
        except (ParameterError, OSError):
            return False
        return found.intact and bool(found.done.all()) and not found.problems

    def prepare(self, plan, overwrite: bool = False) -> Prepared:
        """The sweep engine's start (:func:`coincli.engines.basin.run_sweep`): the store of
        ``plan`` created or resumed (:meth:`create_or_resume`), and what it holds."""
        found = self.create_or_resume(plan.attrs, plan.grid, overwrite)
        return Prepared(found.done, dict(found.damaged), tuple(found.repaired),
                        self.parameters)

    def shared(self) -> BasinStore:
        """The store as Dask workers open it: by its absolute path (the same on every machine
        of a cluster sharing its file system)."""
        return BasinStore(self.path.resolve(), self.view)

    # -- reading ------------------------------------------------------------------------------
    def read_chunk(self, name: str, tile: tuple[int, int]) -> np.ndarray:
        """One tile's chunk of array ``name``, cut to the tile (ChunkError, OSError if it
        cannot be read; a missing chunk file is FileNotFoundError)."""
        return self.specs[name].read(self.path, tile)

    def read_tile(self, tile: tuple[int, int]) -> tuple[dict | None, str | None]:
        """One tile's arrays, or why they cannot be read."""
        return read_tile(self.specs, self.path, tile)

    def digests(self, tiles=None) -> tuple[np.ndarray, set]:
        """The ``done`` digests (of ``tiles`` only, if given; 0 where a tile has none), and the
        tiles whose digest cannot be read."""
        flags = np.zeros(self.grid.tile_grid, dtype=np.uint32)
        unreadable = set()
        for tile in (np.ndindex(*self.grid.tile_grid) if tiles is None else tiles):
            try:
                flags[tile] = self.read_chunk("done", tile)[0, 0]
            except FileNotFoundError:
                pass  # not done
            except Exception:  # noqa: BLE001 - any failure to read is damage
                unreadable.add(tuple(tile))
        return flags, unreadable

    def scan(self, *, with_data: bool = False,
             tiles: Iterable[tuple[int, int]] | None = None) -> Iterator[tuple]:
        """Check every tile (or ``tiles``): yield (tile, Tile state, arrays or None, why
        damaged). Arrays are given for DONE tiles when ``with_data``. Tiles are read one at a
        time (one chunk file per array), so memory stays flat."""
        wanted = None if tiles is None else [tuple(t) for t in tiles]
        flags, unreadable = self.digests(wanted)
        for tile in (np.ndindex(*self.grid.tile_grid) if wanted is None else wanted):
            if tile in unreadable:
                yield tile, Tile.DAMAGED, None, "its done digest cannot be read"
                continue
            if not flags[tile]:
                yield tile, Tile.MISSING, None, None
                continue
            data, why = self.read_tile(tile)
            if data is None:
                yield tile, Tile.DAMAGED, None, why
            elif tile_digest(tile, data, self.parameters) != int(flags[tile]):
                yield tile, Tile.DAMAGED, None, ("its data do not match its digest (a chunk "
                                                 "from another tile, or changed on disk)")
            else:
                yield tile, Tile.DONE, (data if with_data else None), None

    def has_digest(self, tile: tuple[int, int]) -> bool:
        """Whether a tile's ``done`` chunk exists (one stat). Written last, after all its data,
        so a digest that appears while a sweep runs means another process finished it."""
        return self.specs["done"].file(self.path, tile).is_file()

    def tile_done(self, tile: tuple[int, int]) -> bool:
        """Whether one tile is done and verified (read now, from disk)."""
        if not self.has_digest(tile):
            return False
        return any(state is Tile.DONE for _, state, _, _ in self.scan(tiles=[tuple(tile)]))

    def read(self) -> Basin:
        """The whole basin, every tile checked: cells of tiles not done, or damaged, read as
        not computed (their tiles are listed in ``Basin.damaged``)."""
        grid = self.grid
        arrays = {name: np.full(grid.shape, FILLS[name], dtype=VARIABLES[name][0])
                  for name in ARRAY_NAMES}
        done = np.zeros(grid.tile_grid, dtype=np.uint8)
        damaged = []
        for tile, state, data, _ in self.scan(with_data=True):
            if state is Tile.DONE:
                s0, s1 = grid.tile_slices(tile)
                for name in ARRAY_NAMES:
                    arrays[name][s0, s1] = data[name]
                done[tile] = 1
            elif state is Tile.DAMAGED:
                damaged.append(tile)
        tile_seconds, runs = self.costs()
        return Basin(attrs=self.attrs, arrays=arrays, done=done, tile_seconds=tile_seconds,
                     runs=runs, path=str(self.path), damaged=damaged)

    def stats(self) -> BasinStats:
        """Its statistics (:func:`coincli.basin_stats`), read one tile at a time, each checked,
        so memory stays flat at any resolution; damaged tiles count as not computed."""
        counts = BasinCounts()
        done = np.zeros(self.grid.tile_grid, np.uint8)
        damaged = []
        for tile, state, data, _ in self.scan(with_data=True):
            if state is Tile.DONE:
                counts.add(data["quarter_turns"], data["status"], data["certainty"])
                done[tile] = 1
            else:
                counts.add_not_computed(self.grid.tile_cells(tile))
                if state is Tile.DAMAGED:
                    damaged.append(tile)
        seconds, runs = self.costs()
        return BasinStats(counts, done, damaged, seconds, runs, self.damaged_metadata(),
                          self.problems)

    def costs(self) -> tuple[np.ndarray, list]:
        """Per-tile CPU seconds (NaN where unknown) and the run records."""
        seconds = np.full(self.grid.tile_grid, math.nan)
        records = self.records_dir
        if records.is_dir():
            for f in records.glob("tile_*.json"):
                try:
                    i, j = (int(x) for x in f.stem.split("_")[1:3])
                    if i < seconds.shape[0] and j < seconds.shape[1]:
                        seconds[i, j] = json.loads(f.read_text())["cpu_seconds"]
                except (ValueError, KeyError, TypeError, OSError):
                    pass  # a damaged cost record loses the cost, never the results
        return seconds, self.runs()

    # -- checking and repairing ---------------------------------------------------------------
    def damaged_metadata(self) -> list[str]:
        """Keys of the metadata files and coordinate chunks that do not hold what the store's
        (proven) parameters give."""
        return [key for key, data in template(self.attrs, self.grid).items()
                if meta.differs(self.path / key, data)]

    def leftovers(self) -> int:
        """Temporary files (``*.partial``) of writers that died."""
        return sum(1 for _ in self.path.glob(f"*/c/**/*{PARTIAL}"))

    def check(self, *, repair_with: dict | None = None) -> StoreCheck:
        """Check every tile and every metadata file (read only, unless ``repair_with`` gives
        the attributes to rewrite differing metadata from: what the sweep wrote is rewritten,
        what a user added to it is kept)."""
        t0 = time.perf_counter()
        attrs = repair_with if repair_with is not None else self.attrs
        files = template(attrs, self.grid)
        metadata = [key for key, data in files.items() if meta.differs(self.path / key, data)]
        repaired = []
        if repair_with is not None:
            for key in metadata:
                target = self.path / key
                target.parent.mkdir(parents=True, exist_ok=True)
                write_atomically(target, meta.repaired(target, files[key]))
                repaired.append(key)
        done = np.zeros(self.grid.tile_grid, dtype=bool)
        damaged = {}
        for tile, state, _, why in self.scan():
            if state is Tile.DONE:
                done[tile] = True
            elif state is Tile.DAMAGED:
                damaged[tile] = why
        return StoreCheck(str(self.path), self.attrs, self.grid, done, damaged, metadata,
                          repaired, self.leftovers(), time.perf_counter() - t0,
                          list(self.problems))

    # -- writing ------------------------------------------------------------------------------
    def _remove_partials(self, tile: tuple[int, int]) -> None:
        """Temporary chunk files of this tile's chunks left by a writer that died (only the
        owner of a tile's claim writes it, so any such file is an orphan)."""
        for name in (*ARRAY_NAMES, "done"):
            remove_partials(self.specs[name].file(self.path, tile))

    def write_tile(self, result: TileResult, parameters: bytes | None = None) -> None:
        """Write one tile's arrays, its cost, and last its ``done`` digest, which binds the
        parameters digest ``parameters`` (by default, the store's as opened: a sweep passes
        the digest of the parameters it computed with, whatever another process may have
        written into the metadata meanwhile)."""
        parameters = self.parameters if parameters is None else parameters
        tile = result.tile
        self._remove_partials(tile)
        for name in ARRAY_NAMES:
            self.specs[name].write(self.path, tile, result.arrays[name])
        cost = {"cpu_seconds": result.cpu_seconds, "host": socket.gethostname(),
                "pid": os.getpid()}
        if result.mirror_of is not None:
            cost["mirror_of"] = list(result.mirror_of)
        write_atomically(self.records_dir / f"tile_{tile[0]}_{tile[1]}.json",
                         json.dumps(cost).encode())
        self.specs["done"].write(self.path, tile,
                                 np.array([[tile_digest(tile, result.arrays, parameters)]]))


__all__ = ["BasinStore", "StoreCheck", "Tile"]
