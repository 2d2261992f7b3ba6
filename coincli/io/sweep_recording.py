"""The live recording of a sweep (`coin basin STORE --rrd/--spawn/--connect`), made by a process
of its own that reads the tiles from the store as the sweep writes them
(:func:`coincli.io.live.record_tiles`).

Why a process: importing Rerun, the store's code and pandas (which pyarrow imports at its first
conversion) and sending the first objects costs about half a second of CPU. In the sweep's
process it would be taken from the sweep (one interpreter lock); in a process of its own,
started before the sweep's process has planned anything (:meth:`SweepRecorder.start`), most of
it falls while that process is still starting up on one thread and the other core is idle.
The sweep's process only says, a JSON line per update, which tiles were written.

This module imports nothing heavy: the sweep's command starts the process before it imports
the sweep's own code.
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

# The recording process: this Python, running recording_process.
RECORDER = "from coincli.io.sweep_recording import recording_process; recording_process()"
# The commands of `coin basin` (`coin basin STORE ...` is short for `coin basin sweep STORE
# ...`), and the options of a live recording: see start_early (both tested against the CLI).
BASIN_COMMANDS = frozenset({"analyze", "export", "inspect", "render", "show", "stats", "sweep",
                            "verify"})
RECORDING_OPTIONS = ("--rrd", "--spawn", "--connect")


class RecordingFailed(RuntimeError):
    """A live recording that could not be made or finished (why, in one line)."""


class SweepRecorder:
    """The live recording of a sweep: :meth:`start` the process as early as possible, say what
    to record with :meth:`record`, then use it as a context manager around the sweep, whose
    :meth:`progress` takes the sweep's SweepProgress (in the thread that runs the sweep).

    The process is told the store, its attributes and where to record by :meth:`begin`, when
    the sweep starts its work (its ``on_start``, else its first progress; or on leaving, if
    there was neither: a store complete already), not before: a sweep refused before any work
    (a store of another sweep, one too long) records nothing and opens no viewer. On leaving,
    its input is closed: it reads any tile done that it has not drawn (those of other
    processes too), sends the last map, the store's, closes the recording and says how it
    went; leaving waits for that. A recording that cannot be made (no viewer, no file) leaves
    ``error`` set and the sweep alone. A process started for a recording that will not be
    made (the command failed first) is ended by :meth:`cancel`, or ends by itself as soon as
    its input closes (this process's end closes it).

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

    def record(self, path, attrs: dict, where, *, verified: bool) -> SweepRecorder:
        """What to record: the sweep into the store at ``path`` with attributes ``attrs``
        (``verified``: its labels carry a certainty), and where to (``where``: a
        :class:`coincli.io.live.Destination`); returns self."""
        self._setup = {"path": str(Path(path)), "attrs": attrs, "verified": verified,
                       "rrd": None if where.rrd is None else str(where.rrd),
                       "spawn": where.spawn, "connect": where.connect,
                       "min_interval": self.min_interval}
        return self

    def cancel(self) -> None:
        """End a process started for a recording that will not be made: it ends at once
        when its input closes before it was told what to record."""
        if self._process is None:
            return
        process, self._process = self._process, None
        try:
            with contextlib.suppress(OSError):
                process.stdin.close()
        finally:
            process.wait()
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


_started_early: SweepRecorder | None = None  # by start_early, for this command line's sweep


def sweep_recording_asked(args: list[str]) -> bool:
    """Whether the command line ``args`` (those after `coin`) looks like a sweep with a live
    recording: `coin basin [sweep] STORE ... --rrd FILE | --spawn | --connect URL`. A guess,
    made before the command line is parsed: the sweep's command decides (a wrong guess
    costs a process that ends at once)."""
    if len(args) < 2 or args[0] != "basin" or "--help" in args:
        return False
    if args[1] in BASIN_COMMANDS - {"sweep"}:
        return False
    return any(arg.split("=", 1)[0] in RECORDING_OPTIONS for arg in args[1:])


def start_early(args: list[str]) -> None:
    """Start the recording's process for the command line ``args`` (those after `coin`) if it
    asks for a sweep with a live recording (:func:`sweep_recording_asked`). `coin` calls this
    first of all, before it imports the command line's parser and its commands (0.15 s, on
    one core): the recording's own start-up (importing Rerun) then falls in that time, not in
    the sweep's. The sweep's command takes it with :func:`recorder_for`."""
    global _started_early
    if _started_early is None and sweep_recording_asked(args):
        _started_early = SweepRecorder().start()


def recorder_for(asked: bool) -> SweepRecorder | None:
    """The recorder of a sweep whose command line asked for a live recording (``asked``): the
    one :func:`start_early` started, or one started now; None if none was asked (a process
    started early on a wrong guess is ended)."""
    global _started_early
    early, _started_early = _started_early, None
    if not asked:
        if early is not None:
            early.cancel()
        return None
    return early or SweepRecorder().start()


def _inbox(lines, *, end_without_setup: bool = False) -> queue.SimpleQueue:
    """The messages of ``lines`` (JSON, one a line), read by a thread of their own as they
    come, whatever the recording is doing (the sweep never waits on this process); None after
    the last. ``end_without_setup``: lines that end before the first one came end this
    process at once (the command gave up, or was killed, before it said what to record)."""
    inbox: queue.SimpleQueue = queue.SimpleQueue()

    def read() -> None:
        got = False
        try:
            for line in lines:
                inbox.put(json.loads(line))
                got = True
        except ValueError:  # a line cut off: the sweep's process was killed as it wrote it
            pass
        if end_without_setup and not got:
            os._exit(0)  # nothing was recorded: nothing to close or say
        inbox.put(None)

    threading.Thread(target=read, name="coin-sweep-lines", daemon=True).start()
    return inbox


def record_sweep(lines=None, out=None, *, inbox: queue.SimpleQueue | None = None) -> None:
    """The recording of :class:`SweepRecorder`'s process, reading ``lines`` (default stdin;
    or the messages already in ``inbox``): the first (JSON, as all) says what to record and
    where, each further one what the sweep did (elapsed seconds, cells done, the tiles
    written), the last one the time of the last map; their end, that the sweep ended. Writes
    one JSON line to ``out`` (default stdout) when done: ``{"error": null}``, or why the
    recording failed; nothing if the lines ended before the first (nothing was recorded)."""
    out = sys.stdout if out is None else out
    if inbox is None:
        inbox = _inbox(sys.stdin if lines is None else lines)
    try:
        setup = inbox.get()
        if setup is None:  # the sweep's process ended before it said what to record
            return
        from .live import record_tiles

        record_tiles(setup, inbox)
        why = None
    except Exception as exc:  # noqa: BLE001 - any failure is said in one line, not a traceback
        from .paths import explain

        why = explain(exc)
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
    """The recording process's body: the code a recording needs imported at once (most of
    its cost, while the sweep's process is still planning), then :func:`record_sweep` on
    stdin and stdout, then its end at once. The recording is closed and the answer written by
    then; a normal exit would tear the interpreter down first (with Rerun loaded, 0.1 s of
    CPU and more), and the sweep's command waits for this process to end."""
    # a Ctrl-C is the sweep's (this process has a session of its own where there are
    # sessions; elsewhere a console's Ctrl-C reaches every process in it): this one ends
    # when its input does
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    inbox = _inbox(sys.stdin, end_without_setup=True)
    answer = answer_line()
    import rerun as rr
    import rerun.blueprint  # noqa: F401 - imported before they are needed: see above

    from . import live, store  # noqa: F401
    rr.Scalars(0.0)  # pyarrow's first conversion imports pandas (0.15 s): here, not mid-sweep
    record_sweep(inbox=inbox, out=answer)
    os._exit(0)


__all__ = ["BASIN_COMMANDS", "RECORDER", "RECORDING_OPTIONS", "RecordingFailed", "SweepRecorder",
           "answer_line", "record_sweep", "recorder_for", "recording_process", "start_early",
           "sweep_recording_asked"]
