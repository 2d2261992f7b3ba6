"""Claims on tiles (and on the batches of `coin fractions`), so that several processes (on one
machine or several sharing the store's file system) can run the same work together without
computing a piece twice.

A claim is a file ``out.zarr/.coin/claims/tile_I_J`` (the store's records folder,
:func:`coincli.stores.basin_layout.records_dir`) holding its owner: host, pid, the pid's
start time and a random token; it is written to a draft and hard-linked into place, which fails
if the claim exists (exactly one process can create it), so a claim is never seen empty. While
the owner computes the tile a heartbeat thread touches the file every :data:`HEARTBEAT`
seconds; the owner removes it once the tile is written (or abandoned). A claim is *stale*, and
taken over by whoever needs the tile, when its heartbeat is older than :data:`STALE` seconds,
or at once when its owner ran on this host and its process is gone (a ``kill -9``, a crash, a
reboot). Taking over renames the stale file out of the way, checks that what it moved is the
claim it judged stale (restoring it otherwise), and then claims as usual, so two processes
taking over the same tile cannot both win.

:class:`ClaimQueue`, the one queue of both engines, hands out the pieces (tiles, batches) one
process should compute: it claims each before handing it out and checks, once claimed, that
nobody finished it meanwhile; pieces claimed by live others are watched until they are done, or
until their claim is dropped or goes stale, in which case it claims and computes them itself. So
when a queue is :attr:`~ClaimQueue.finished`, every piece is done, whoever computed it.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import secrets
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from pathlib import Path

HEARTBEAT = 10.0  # s between touches of the claims a process holds
STALE = 60.0  # s without a heartbeat after which a claim is taken over
POLL = 0.5  # s between looks at the tiles other processes hold
# what os.link raises on a file system without hard links (FAT, exFAT, some network shares)
NO_HARD_LINKS = {errno.EPERM, errno.EOPNOTSUPP, errno.ENOTSUP, errno.ENOSYS}

HOST = socket.gethostname()
_live_tokens: set[str] = set()  # claims held by this process (any queue)


def _start_time(pid: int) -> str | None:
    """A process's start time (clock ticks since boot, Linux), to tell a reused pid apart."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            text = fh.read().decode(errors="replace")
        return text[text.rindex(")") + 2:].split()[19]
    except (OSError, ValueError, IndexError):
        return None


def pid_alive(pid: int, start: str | None = None) -> bool:
    """Whether process ``pid`` of this host still runs (and is the one that started at
    ``start``, when given and knowable)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # alive, someone else's
    if start is not None:
        now = _start_time(pid)
        if now is not None and now != start:
            return False
    return True


MY_START = _start_time(os.getpid())


def claim_name(tile: tuple[int, int]) -> str:
    return f"tile_{tile[0]}_{tile[1]}"


def read_claim(path: Path) -> tuple[dict | None, float | None]:
    """(owner, mtime) of a claim file; owner None when unreadable (being written, or damaged);
    mtime None when there is no claim."""
    try:
        mtime = path.stat().st_mtime
    except FileNotFoundError:
        return None, None
    try:
        owner = json.loads(path.read_text())
        if not isinstance(owner, dict):
            owner = None
    except (OSError, ValueError):
        owner = None
    return owner, mtime


def is_stale(owner: dict | None, mtime: float, now: float | None = None) -> bool:
    """A claim whose heartbeat stopped, or whose owner on this host is gone."""
    now = time.time() if now is None else now
    if now - mtime > STALE:
        return True
    if owner is None:
        return False  # being written: give it its heartbeat's time
    if owner.get("host") == HOST:
        pid = int(owner.get("pid", -1))
        if pid == os.getpid():
            return owner.get("token") not in _live_tokens  # ours from before (an earlier sweep)
        return not pid_alive(pid, owner.get("start"))
    return False


def describe_owner(owner: dict | None) -> str:
    if not owner:
        return "another process"
    return f"pid {owner.get('pid')} on {owner.get('host')}"


class Claims:
    """The claims one sweep holds in ``folder``, kept alive by a heartbeat thread."""

    def __init__(self, folder: str | os.PathLike, heartbeat: float = HEARTBEAT):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.token = secrets.token_hex(8)
        self.held: dict[tuple[int, int], str] = {}
        self.lost: set[tuple[int, int]] = set()
        self._lock = threading.Lock()
        self._closed = threading.Event()
        self._serial = 0
        _live_tokens.add(self.token)
        self._thread = threading.Thread(target=self._beat, args=(heartbeat,), daemon=True,
                                        name="coin-claims-heartbeat")
        self._thread.start()

    @property
    def _draft_suffix(self) -> str:
        return f".draft-{self.token}"

    def path(self, tile: tuple[int, int]) -> Path:
        return self.folder / claim_name(tile)

    def _content(self, tile) -> bytes:
        return json.dumps({"host": HOST, "pid": os.getpid(), "start": MY_START,
                           "token": self.token, "tile": list(tile),
                           "since": time.time()}).encode()

    def try_claim(self, tile: tuple[int, int]) -> bool:
        """Claim ``tile`` if nobody holds it, taking over a stale claim; False if a live
        process holds it."""
        tile = tuple(tile)
        for _ in range(3):
            path = self.path(tile)
            try:
                self._create(path, tile)
            except FileNotFoundError:  # the folder went with another process's last claim
                self.folder.mkdir(parents=True, exist_ok=True)
                continue
            except FileExistsError:
                owner, mtime = read_claim(path)
                if mtime is None:
                    continue  # released meanwhile: try again
                if not is_stale(owner, mtime):
                    return False
                self._take_over(path, mtime)
                continue
            with self._lock:
                self.held[tile] = self.token
            return True
        return False

    def _create(self, path: Path, tile: tuple[int, int]) -> None:
        """Make the claim ``path``, with our content, whole or not at all (FileExistsError if it
        exists): written to a draft of ours, then linked into place, so that no claim is ever
        empty, not even one a signal (a KeyboardInterrupt in the `coin` command) interrupted
        between its creation and its write, which nobody could then tell as ours. A draft such
        a signal leaves carries our token: :meth:`close` removes it. Where the file system has
        no hard links, the claim is created exclusively, then written."""
        draft = path.with_name(f".{path.name}{self._draft_suffix}")
        try:
            draft.write_bytes(self._content(tile))
            os.link(draft, path)
        except OSError as exc:
            if exc.errno not in NO_HARD_LINKS:
                raise
            self._create_in_place(path, tile)
        finally:
            with contextlib.suppress(OSError):
                os.unlink(draft)

    def _create_in_place(self, path: Path, tile: tuple[int, int]) -> None:
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        try:
            os.write(fd, self._content(tile))
        except BaseException:
            os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(path)
            raise
        os.close(fd)

    def _take_over(self, path: Path, seen_mtime: float) -> None:
        """Move a stale claim out of the way, unless it changed since it was judged."""
        with self._lock:
            self._serial += 1
            grave = path.with_name(f".{path.name}.stale-{self.token}-{self._serial}")
        try:
            os.rename(path, grave)
        except FileNotFoundError:
            return  # someone else did
        try:
            if grave.stat().st_mtime != seen_mtime:
                # a new claim was made between our look and the rename: put it back
                with contextlib.suppress(OSError):  # EEXIST: claimed again meanwhile
                    os.link(grave, path)
        finally:
            with contextlib.suppress(OSError):
                os.unlink(grave)

    def owns(self, tile: tuple[int, int]) -> bool:
        owner, _ = read_claim(self.path(tile))
        return owner is not None and owner.get("token") == self.token

    def release(self, tile: tuple[int, int]) -> None:
        """Drop the claim on ``tile`` (if it is still ours)."""
        tile = tuple(tile)
        with self._lock:
            if self.held.pop(tile, None) is None:
                return
        if self.owns(tile):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self.path(tile))

    def _beat(self, period: float) -> None:
        while not self._closed.wait(period):
            with self._lock:
                tiles = list(self.held)
            for tile in tiles:
                try:
                    if self.owns(tile):
                        os.utime(self.path(tile))
                    else:  # taken over after our heartbeat stalled (a suspended process)
                        self.lost.add(tile)
                except OSError:
                    pass

    def close(self) -> None:
        """Stop the heartbeat and drop every claim still held."""
        self._closed.set()
        with self._lock:
            tiles = list(self.held)
        for tile in tiles:
            with contextlib.suppress(OSError):
                self.release(tile)
        # a claim made as a signal came (linked into place, not yet recorded as held) is ours
        # all the same: it carries our token; so is a draft, which our token names (one a
        # signal cut off before its content was written is empty)
        with contextlib.suppress(OSError):
            for path in self.folder.iterdir():
                owner, _ = read_claim(path)
                if path.name.endswith(self._draft_suffix) or (
                        owner is not None and owner.get("token") == self.token):
                    with contextlib.suppress(OSError):
                        path.unlink()
        _live_tokens.discard(self.token)
        with contextlib.suppress(OSError):
            self.folder.rmdir()  # empty once nobody holds a claim


class ClaimQueue:
    """The pieces of one job as one process sees them: a sweep's tiles or a Monte Carlo run's
    batches, from a *source* that knows which piece comes next and what its task is. Both
    engines hand their executor such a queue (:mod:`coincli.engines.executors`).

    :meth:`take` hands out a piece this process has claimed (and that nobody finished since),
    or None when every piece left is held by another live process; those are *watched*
    (:attr:`poll`) until done elsewhere, or claimed here once their owner lets go or goes
    stale. Without ``claims`` (an in-memory sweep, a run without a store) it hands the pieces
    out in the source's order. :attr:`finished` is True once the source needs nothing more
    and no piece is out or watched: every piece is done, whoever computed it.

    The source (:class:`TileSource`, :class:`coincli.engines.fractions.BatchSource`) has
    ``next()`` (the next piece to try, marked as tried, or None), ``needed(key)`` (a watched
    piece may still be needed), ``done_elsewhere(key)`` (another process finished it: the
    source takes note), ``task(key)`` and ``key(task)``, ``held(key)`` (another process holds
    it), ``dropped(key)`` (handed out, but this run will not write it) and ``exhausted()``;
    ``release_on_settle`` says whether a piece's claim goes when its task returns (a tile's
    task writes it) or later, once the engine has written it (a batch's result comes back)."""

    def __init__(self, source, claims: Claims | None = None, poll: float = POLL):
        self.source = source
        self.claims = claims
        self.poll = poll
        self.watched: set = set()  # held by others
        self.out: set = set()  # handed out, not yet settled
        self.done_elsewhere: list = []
        self._last_look = 0.0

    def _elsewhere(self, key) -> bool:
        if self.claims is not None and self.source.done_elsewhere(key):
            self.done_elsewhere.append(key)
            return True
        return False

    def _claim(self, key) -> bool | None:
        """True: claimed here, to compute; False: done elsewhere; None: held by another."""
        if self.claims is None:
            return True
        if self._elsewhere(key):
            return False
        if not self.claims.try_claim(key):
            return None
        if self._elsewhere(key):  # finished between our look and our claim
            self.claims.release(key)
            return False
        return True

    def _hand_out(self, key):
        self.out.add(key)
        return self.source.task(key)

    def take(self):
        """A task to compute, or None for now."""
        while (key := self.source.next()) is not None:
            got = self._claim(key)
            if got:
                return self._hand_out(key)
            if got is None:
                self.watched.add(key)
                self.source.held(key)
        self.watched = {key for key in self.watched if self.source.needed(key)}
        if self.watched and time.monotonic() - self._last_look >= self.poll:
            self._last_look = time.monotonic()
            for key in sorted(self.watched):
                got = self._claim(key)
                if got is not None:
                    self.watched.discard(key)
                if got:
                    return self._hand_out(key)
        return None

    def settle(self, task) -> None:
        """A handed-out task is back (its piece written, or to be written by the engine)."""
        key = self.source.key(task)
        self.out.discard(key)
        if self.source.release_on_settle and self.claims is not None:
            self.claims.release(key)

    def drop(self, task) -> None:
        """A handed-out task that this run will not write (stopping, failed): its claim goes."""
        key = self.source.key(task)
        self.out.discard(key)
        self.source.dropped(key)
        if self.claims is not None:
            self.claims.release(key)

    @property
    def finished(self) -> bool:
        return not self.out and not self.watched and self.source.exhausted()

    def pause(self) -> None:
        """Sleep until the next look at the others' pieces (Ctrl-C interrupts it)."""
        time.sleep(max(0.01, self.poll - (time.monotonic() - self._last_look)))


class TileSource:
    """A sweep's tiles for a :class:`ClaimQueue`, in work order; a tile held by another process
    sends this one to the middle of the tiles it has left, so that processes spread over the
    grid rather than take turns tile by tile."""

    release_on_settle = True  # a tile's task writes the tile

    def __init__(self, tiles: Iterable[tuple[int, int]],
                 is_done: Callable[[tuple[int, int]], bool] | None = None):
        self.pending = deque(tuple(t) for t in tiles)
        self.is_done = is_done

    def next(self):
        return self.pending.popleft() if self.pending else None

    def needed(self, tile) -> bool:
        return True

    def done_elsewhere(self, tile) -> bool:
        return self.is_done is not None and self.is_done(tile)

    def held(self, tile) -> None:
        self.pending.rotate(-(len(self.pending) // 2))

    def task(self, tile):
        return tile

    def key(self, tile):
        return tuple(tile)

    def dropped(self, tile) -> None:
        pass

    def exhausted(self) -> bool:
        return not self.pending


def tile_queue(tiles, claims: Claims | None = None, is_done=None, poll: float = POLL):
    """The :class:`ClaimQueue` of a sweep's tiles."""
    return ClaimQueue(TileSource(tiles, is_done), claims, poll)


__all__ = ["ClaimQueue", "Claims", "HEARTBEAT", "POLL", "STALE", "TileSource", "describe_owner",
           "is_stale", "pid_alive", "read_claim", "tile_queue"]
