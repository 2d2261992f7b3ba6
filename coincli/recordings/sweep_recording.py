"""The live recording of a sweep into a store (`coin basin STORE --rrd/--spawn/--connect`,
``coincli.basin(..., store=..., rrd=...)``): the map as it fills in, read back from the store
(:class:`coincli.recordings.basin_view.StoreMap`), fed by the sweep's progress.

Two recorders, one interface (a context manager around the sweep, whose ``progress`` takes each
SweepProgress, and ``error`` set if the recording failed; the sweep goes on either way):

- :class:`SweepRecorder` makes the recording in a process of its own, which reads the tiles from
  the store as the sweep writes them: importing Rerun and sending the maps costs the sweep's
  process next to nothing (it only says, a JSON line per update, which tiles were written), and
  the recording ends with the store's map whatever happens to the sweep (Ctrl-C, a signal,
  ``kill -9``: its input closes, and it reads the store one last time).
- :class:`InlineSweep` makes it in this process, for a viewer in a notebook's cell (the viewer
  belongs to the kernel).

:func:`sweep_recorder` gives the one a destination needs.
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from .basin_view import StoreMap
from .stream import Destination, InProcessRecording

# The recording process: this Python, running recording_process.
RECORDER = "from coincli.recordings.sweep_recording import recording_process; recording_process()"


class RecordingFailed(RuntimeError):
    """A live recording that could not be made or finished (why, in one line)."""


def sweep_recorder(plan, store, where: Destination | None):
    """The recorder of a sweep of ``plan`` into ``store`` at ``where`` (None if nowhere): in
    this process for a notebook's viewer, else in a process of its own, started now (it
    imports Rerun while this one opens the store)."""
    if where is None:
        return None
    verified = plan.spec.labeller.verified
    if where.notebook is not False:
        return InlineSweep(store, plan.attrs, where, verified=verified)
    return SweepRecorder().start().record(store, plan.attrs, where, verified=verified)


class SweepRecorder:
    """The live recording of a sweep by a process of its own: :meth:`start` the process (as
    early as possible: it imports Rerun meanwhile), say what to record with :meth:`record`, then
    use it as a context manager around the sweep.

    The process is told the store, its attributes and where to record by :meth:`begin`, when
    the sweep starts its work (its ``on_start``, else its first progress; or on leaving, if
    there was neither: a store complete already), not before: a sweep refused before any work
    (a store of another sweep, one too long) records nothing and opens no viewer. On leaving,
    its input is closed: it reads any tile done that it has not drawn (those of other
    processes too), sends the last map, the store's, closes the recording and says how it
    went; leaving waits for that. A recording that cannot be made (no viewer, no file) leaves
    ``error`` set and the sweep alone. A process started for a recording that will not be made
    (the command failed first) is ended by :meth:`cancel`.

    The process has a session of its own: a Ctrl-C at the terminal, or a signal to this
    process's group, reaches only the sweep, which ends and closes the line; if this process
    is killed, the line closes all the same. Either way the recording ends with the store's
    map, and the process with it."""

    def __init__(self, *, min_interval: float = 0.5):
        self.min_interval = min_interval
        self.error: Exception | None = None  # why the recording failed (the sweep goes on)
        self._process: subprocess.Popen | None = None
        self._setup: dict | None = None
        self._told = False  # whether the process was told what to record
        self._started: float | None = None  # the sweep's start, on this process's clock

    def start(self) -> SweepRecorder:
        """Start the recording process (it imports Rerun meanwhile); returns self."""
        if self._process is None and self.error is None:
            try:
                self._process = subprocess.Popen(  # -P: no module of the current folder
                    [sys.executable, "-P", "-c", RECORDER], stdin=subprocess.PIPE,
                    stdout=subprocess.PIPE, text=True, start_new_session=True)
            except OSError as exc:
                self.error = exc
        return self

    def record(self, path, attrs: dict, where: Destination, *,
               verified: bool) -> SweepRecorder:
        """What to record: the sweep into the store at ``path`` with attributes ``attrs``
        (``verified``: its labels carry a certainty), and where to; returns self."""
        self._setup = {"path": str(Path(path)), "attrs": attrs, "verified": verified,
                       "rrd": None if where.rrd is None else str(where.rrd),
                       "spawn": where.spawn, "connect": where.connect,
                       "min_interval": self.min_interval}
        return self

    def cancel(self) -> None:
        """End a process started for a recording that will not be made (nothing recorded)."""
        if self._process is None:
            return
        process, self._process = self._process, None
        try:
            process.terminate()
        finally:
            process.wait()
            with contextlib.suppress(OSError):
                process.stdin.close()
            process.stdout.close()

    def __enter__(self):
        if self._setup is None:
            raise ValueError("record(path, attrs, where, verified=...) says what to record "
                             "before the recording begins")
        return self.start()

    def begin(self) -> None:
        """Tell the process what to record (once): the sweep has passed its checks (its
        ``on_start``), or made its first progress."""
        if self._process is not None and not self._told:  # (no process: it could not start)
            self._told = True
            self._tell(self._setup)

    def _tell(self, message: dict) -> None:
        """One line to the recording process (if it is gone, its answer says why)."""
        line = self._process.stdin
        if line.closed:
            return
        try:
            line.write(json.dumps(message) + "\n")
            line.flush()
        except OSError:  # it ended early (it could not record): no more lines
            with contextlib.suppress(OSError):
                line.close()

    def progress(self, update) -> None:
        if self._process is None:
            return
        self.begin()
        self._started = time.perf_counter() - update.elapsed
        self._tell({"elapsed": update.elapsed, "cells_done": update.cells_done,
                    "written": [list(tile) for tile in update.written]})

    def __exit__(self, exc_type, *exc):
        if self._process is None:
            return False
        if exc_type is not None and not self._told:  # refused before any work: no recording
            self.cancel()
            return False
        self.begin()  # a sweep with nothing to do: the store's map all the same
        if self._started is not None:  # the time of the last map
            self._tell({"elapsed": time.perf_counter() - self._started})
        process, self._process = self._process, None
        try:
            with contextlib.suppress(OSError):
                process.stdin.close()
            answer = process.stdout.readline().strip()
        finally:  # a Ctrl-C meanwhile still leaves no pipe open nor a process unwaited for
            process.stdout.close()
            code = process.wait()
        try:
            why = json.loads(answer)["error"]
        except (IndexError, ValueError, KeyError, TypeError):
            how = (f"killed by {signal.Signals(-code).name}" if -code in signal.valid_signals()
                   else f"exit code {code}")
            why = f"the recording process ended before it was done ({how})"
        if why is not None:
            self.error = RecordingFailed(why)
        return False


class InlineSweep(InProcessRecording):
    """The live map of a sweep into the store at ``path`` in a notebook's viewer: the same
    :class:`StoreMap` as a sweep's recording process makes, here in this process (a notebook's
    viewer belongs to its kernel); :meth:`progress` takes each SweepProgress. The map is
    opened with the first progress (or on leaving, if there was none: a store complete
    already), not for a sweep refused before any work. A map that cannot be shown leaves
    ``error`` set and the sweep alone."""

    def __init__(self, path, attrs: dict, where: Destination, *, verified: bool,
                 min_interval: float = 0.5):
        super().__init__(where)
        self.path, self.attrs = Path(path), attrs
        self.verified, self.min_interval = verified, min_interval
        self.map: StoreMap | None = None
        self.elapsed: float | None = None
        self.tried = False

    def begin(self) -> None:
        """Open the map: the sweep has passed its checks (its ``on_start``), or made its first
        progress."""
        self._start()

    def _start(self) -> None:
        if not self.tried:
            self.tried = True
            if self.open(f"coin basin {self.path}"):
                self.map = StoreMap(self.rec, self.path, self.attrs, verified=self.verified,
                                    min_interval=self.min_interval)

    def progress(self, update) -> None:
        self._start()
        if self.map is None:
            return
        self.elapsed = update.elapsed
        self.map.update(update.written, [(update.elapsed, update.cells_done)])

    def __exit__(self, exc_type, *exc):
        if exc_type is None:
            self._start()
        try:
            if self.map is not None:
                self.map.end(self.elapsed)
        finally:
            super().__exit__(exc_type, *exc)
        return False


# -- the recording process ------------------------------------------------------------------------
def _inbox(lines) -> queue.SimpleQueue:
    """The messages of ``lines`` (JSON, one a line), read by a thread of their own as they
    come, whatever the recording is doing (the sweep never waits on this process); None after
    the last (a line cut off by a killed sweep ends them too)."""
    inbox: queue.SimpleQueue = queue.SimpleQueue()

    def read() -> None:
        try:
            for line in lines:
                inbox.put(json.loads(line))
        except ValueError:  # a line cut off: the sweep's process was killed as it wrote it
            pass
        inbox.put(None)

    threading.Thread(target=read, name="coin-sweep-lines", daemon=True).start()
    return inbox


def record_sweep(lines=None, out=None, *, inbox: queue.SimpleQueue | None = None) -> None:
    """The recording of :class:`SweepRecorder`'s process, reading ``lines`` (default stdin;
    or the messages already in ``inbox``): the first (JSON, as all) says what to record and
    where, each further one what the sweep did (elapsed seconds, cells done, the tiles
    written), the last one the time of the last map; their end, that the sweep ended. Writes
    one JSON line to ``out`` (default stdout) when done: ``{"error": null}``, or why the
    recording failed; nothing if the lines ended before the first (nothing was recorded), nor
    if nobody reads it any more (the sweep's process was killed)."""
    out = sys.stdout if out is None else out
    if inbox is None:
        inbox = _inbox(sys.stdin if lines is None else lines)
    setup = inbox.get()
    if setup is None:  # the sweep's process ended before it said what to record
        return
    try:
        from .basin_view import record_tiles

        record_tiles(setup, inbox)
        why = None
    except Exception as exc:  # noqa: BLE001 - any failure is said in one line, not a traceback
        from ..files import explain

        why = explain(exc)
    with contextlib.suppress(OSError):  # BrokenPipeError: the sweep is gone, nobody asks
        out.write(json.dumps({"error": why}) + "\n")
        out.flush()


def answer_line():
    """This process's stdout as a file only it writes to; stdout itself now goes nowhere. A
    viewer spawned for the recording inherits stdout: the sweep's command, which reads this
    process's answer up to its end, would otherwise wait for the viewer to be closed."""
    answer = os.fdopen(os.dup(1), "w")  # a duplicate is not inherited by children
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    os.close(null)
    return answer


def recording_process() -> None:
    """The recording process's body: :func:`record_sweep` on stdin and an answer line of its
    own. A Ctrl-C is the sweep's (this process has a session of its own where there are
    sessions; elsewhere a console's Ctrl-C reaches every process in it): this one ends when its
    input does."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    inbox = _inbox(sys.stdin)
    answer = answer_line()
    try:
        record_sweep(inbox=inbox, out=answer)
    finally:
        with contextlib.suppress(OSError):
            answer.close()


__all__ = ["InlineSweep", "RECORDER", "RecordingFailed", "SweepRecorder", "answer_line",
           "record_sweep", "recording_process", "sweep_recorder"]
