"""A Rerun recording stream and where it goes: an .rrd file (complete or absent), a spawned
viewer, a running viewer, or a viewer in a notebook's cell (:func:`open_stream`); a destination
given by a user, checked before any work (:class:`Destination`, :func:`check_destination`);
and a recording made in this process beside the work it shows, which never fails that work
(:class:`InProcessRecording`). Every recording of the package (a throw, a sweep, a store, an
estimate, an analysis) goes through here, and its file is written by this module, not by Rerun
(:class:`FileWriter`: a full disk is one OSError). Rerun is imported inside the functions that
need it.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import threading
import uuid
from dataclasses import dataclass
from pathlib import Path

from ..files import atomic_output

APPLICATION_ID = "coin"


def display_available() -> bool:
    """Whether a spawned viewer has a display to open its window on: on Linux and the other
    Unixes an X11 or Wayland display named in the environment; macOS and Windows always have
    one. Without it the viewer dies at once and the recording waits for it (20 s) in vain."""
    if sys.platform == "darwin" or sys.platform.startswith("win"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


NO_DISPLAY = "no display to open a viewer on (DISPLAY and WAYLAND_DISPLAY are unset)"


def _sinks(rr, rec, rrd: str | None, spawn: bool, connect: str | None, port: int):
    sinks = []
    if rrd is not None:
        sinks.append(rr.FileSink(rrd))
    urls = []
    if spawn:
        exe = shutil.which("rerun")
        if exe is None:
            candidate = Path(sys.executable).with_name("rerun")
            exe = str(candidate) if candidate.exists() else None
        rr.spawn(port=port, connect=False, executable_path=exe, recording=rec)
        urls.append(f"rerun+http://127.0.0.1:{port}/proxy")
    if connect is not None and connect not in urls:
        urls.append(connect)
    sinks.extend(rr.GrpcSink(url) for url in urls)
    return sinks


@contextlib.contextmanager
def open_stream(name: str, *, rrd: Path | None = None, spawn: bool = False,
                connect: str | None = None, notebook: bool = False, width: int | None = None,
                height: int | None = None, port: int = 9876, flush_timeout: float = 30.0):
    """A new Rerun recording stream named ``name``, sent to an ``.rrd`` file (written through
    a temporary file renamed into place on success: complete or absent, checked to read back),
    a spawned viewer and/or the viewer at ``connect``; flushed and closed on leaving. Shared by
    every command that records (simulate, basin, fractions). The paths and URL are taken as
    checked (:func:`check_rrd_path`, :func:`check_connect_url`); ``spawn`` without a display
    raises RuntimeError (:func:`display_available`).


    ``notebook`` (alone): True, the stream goes to a Rerun viewer displayed in the notebook's
    cell now (``width`` and ``height`` in pixels); it shows what was logged once the cell has
    ended: Jupyter hands the kernel the viewer's "ready" only between cells (Rerun's wait for
    it, ``block_until_ready``, timed out in JupyterLab 4 with ipykernel 7 in a real browser).
    Or a viewer shown in an earlier cell (:func:`notebook_viewer`): it is ready, and shows
    what is logged as it comes."""
    import rerun as rr


    if notebook is not False:
        viewer_type = viewer_class()
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=uuid.uuid4())
        if notebook is True:
            viewer_type(width=width, height=height, recording=rec).display()
        else:  # a viewer shown in an earlier cell (notebook_viewer): ready, so live
            notebook.add_recording(rec)
        rec.send_recording_name(name)
        try:
            yield rec
        finally:
            rec.flush(timeout_sec=flush_timeout)
        return
    if rrd is None and not spawn and connect is None:
        raise ValueError("a recording needs a destination: rrd, spawn or connect")
    if spawn and not display_available():
        raise RuntimeError(f"{NO_DISPLAY}: write the recording to a file (rrd=...) and open it "
                           "where there is one, or stream it to a running viewer (connect=...)")
    with contextlib.ExitStack() as outputs:
        file_out = outputs.enter_context(atomic_output(rrd)) if rrd is not None else None
        pipe = outputs.enter_context(FileWriter(file_out, rrd)) if file_out is not None else None
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=uuid.uuid4())
        rec.set_sinks(*_sinks(rr, rec, pipe.sink_path if pipe else None, spawn, connect, port))
        if pipe is not None:
            pipe.opened()  # Rerun holds the pipe's write end now
        rec.send_recording_name(name)
        try:
            yield rec
        finally:
            try:
                rec.flush(timeout_sec=flush_timeout)
            finally:
                rec.disconnect()  # closes the file sink (writes its footer), hangs up on viewers
        if pipe is not None:
            pipe.close(flush_timeout)  # OSError if the file could not be written (a full disk)
            _check_complete(file_out)


class FileWriter:
    """Rerun's file sink writes a recording into a pipe, and a thread of ours drains it into
    ``path`` as the data come: a recording's file is written by this module, not by Rerun.
    Rerun's own writer, on a full disk, prints its errors (ERROR and WARN lines, coloured), and
    could hang the command; ours keeps reading (so Rerun never waits on the disk) and
    :meth:`close` raises the OSError the write met. It adds no memory to Rerun's own however
    long the recording: the pipe holds 64 KiB at most. Reading Rerun's stream out in pieces
    (``binary_stream``, ``memory_recording``) would not do: each piece ends with a footer of its
    own, and pieces put together are no valid .rrd (RrdReader fails their checksum).

    Where the system has no /dev/fd (Windows), Rerun writes ``path`` itself. ``name``: the
    file that errors name (``path`` is its temporary file)."""

    def __init__(self, path: Path, name: Path | None = None):
        self.path = Path(path)
        self.name = Path(name or path)
        self.error: OSError | None = None
        self._write_end: int | None = None
        self._thread: threading.Thread | None = None
        if not Path("/dev/fd").is_dir():
            self.sink_path = str(self.path)
            return
        out = open(self.path, "wb")  # noqa: SIM115 - the thread closes it (fails here at once)
        read_end, self._write_end = os.pipe()
        self.sink_path = f"/dev/fd/{self._write_end}"
        self._thread = threading.Thread(target=self._drain, args=(read_end, out), daemon=True,
                                        name="coin-rrd-writer")
        self._thread.start()

    def _drain(self, read_end: int, out) -> None:
        with os.fdopen(read_end, "rb", buffering=0) as pipe:
            while data := pipe.read(1 << 16):
                if self.error is None:  # after a failed write: read on (Rerun never waits)
                    try:
                        out.write(data)
                    except Exception as exc:  # noqa: BLE001 - said by close(), in one line
                        self.error = self._named(exc)
        try:
            out.close()
        except Exception as exc:  # noqa: BLE001
            self.error = self.error or self._named(exc)

    def _named(self, exc: Exception) -> OSError:
        """The error as an OSError naming the recording's file (not its temporary one)."""
        if isinstance(exc, OSError) and exc.errno:
            return OSError(exc.errno, exc.strerror, str(self.name))
        return OSError(f"cannot write '{self.name}': {exc}")

    def opened(self) -> None:
        """Rerun has opened the pipe (its sinks are set): ours closes, so that the pipe ends
        when Rerun closes its file."""
        if self._write_end is not None:
            os.close(self._write_end)
            self._write_end = None

    def close(self, timeout: float) -> None:
        """Wait for the file to be written whole (Rerun has closed its sink); OSError if it
        could not be."""
        self.opened()
        if self._thread is not None:
            self._thread.join(timeout)
            if self._thread.is_alive():
                raise OSError(f"the recording was not written within {timeout:g} s")
        if self.error is not None:
            raise self.error

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if exc[0] is not None:  # the recording failed: the pipe ends, the thread with it
            with contextlib.suppress(OSError):
                self.close(5.0)
        return False


NOTEBOOK_EXTRA = 'pip install "coincli[notebook]"'


class NotebookMissing(ImportError):
    """Rerun's notebook viewer (the package rerun-notebook) is not installed."""


def viewer_class():
    """rerun.notebook.Viewer, or NotebookMissing (one line naming the extra to install)."""
    try:
        import rerun_notebook  # noqa: F401  (rerun.notebook imports without it, then fails)
        from rerun.notebook import Viewer
    except ImportError:
        raise NotebookMissing(f"showing a recording in a notebook needs Rerun's notebook "
                              f"viewer: {NOTEBOOK_EXTRA}") from None
    return Viewer


def in_notebook() -> bool:
    """Whether this runs in a notebook's kernel (Jupyter, VS Code, Colab; or marimo), where a
    viewer can be displayed."""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    if shell is not None and getattr(shell, "kernel", None) is not None:
        return True
    widget = sys.modules.get("rerun_notebook")  # imported by viewer_class
    return bool(widget is not None and widget.running_in_marimo())


# What to do outside a notebook instead of notebook=True, for the live recordings of the API.
LIVE_ELSEWHERE = ("record it with rrd='FILE.rrd' and open it with `rerun FILE.rrd`, or stream "
                  "it with spawn=True")


THROW_ELSEWHERE = ("write it with coincli.record(run, rrd='throw.rrd') and open it with "
                   "`rerun throw.rrd`, or coincli.record(run, spawn=True)")


def require_notebook(what: str, instead: str = THROW_ELSEWHERE) -> None:
    """NotebookMissing without rerun-notebook (wherever this runs), then RuntimeError (one line,
    naming what to do ``instead``) outside a notebook: ``what`` is the call that needs one."""
    viewer_class()
    if not in_notebook():
        raise RuntimeError(f"nothing to show it in: {what} draws in a notebook (Jupyter); "
                           f"here {instead}")


def notebook_viewer(*, width: int | None = None, height: int | None = None):
    """A Rerun viewer displayed in the notebook's cell now, for the recordings of later cells
    (``notebook=viewer``): by the time they run it is ready, and shows them live. Outside a
    notebook RuntimeError, without rerun-notebook NotebookMissing (one line each)."""
    require_notebook("coincli.viewer()", LIVE_ELSEWHERE)
    viewer = viewer_class()(width=width, height=height, use_global_recording=False)
    viewer.display()
    return viewer


def _check_complete(path: Path) -> None:
    """Raise OSError unless ``path`` reads back as a whole recording: Rerun's file sink does not
    report a failed write (a full disk left a 0-byte or truncated file behind)."""
    import warnings

    from rerun.chunk import RrdReader


    try:
        with warnings.catch_warnings():  # a truncated file also warns: one line is enough
            warnings.simplefilter("ignore")
            complete = bool(RrdReader(path).recordings())
    except (RuntimeError, ValueError) as exc:
        raise OSError(f"the recording did not read back ({exc}); is the disk full?") from None
    if not complete:
        raise OSError("the recording did not read back whole; is the disk full?")


@dataclass
class Destination:
    """Where a recording goes: an .rrd file, a spawned viewer, a running viewer's URL; or,
    alone, a viewer in the notebook's cell."""

    rrd: Path | None = None
    spawn: bool = False
    connect: str | None = None
    notebook: object = False  # True (a new viewer in the cell), or a viewer shown before

    def __bool__(self) -> bool:
        return (self.rrd is not None or self.spawn or self.connect is not None
                or self.notebook is not False)

    def stream(self, name: str):
        """:func:`coincli.recordings.rrd.open_stream` to this destination."""
        return open_stream(name, rrd=self.rrd, spawn=self.spawn, connect=self.connect,
                           notebook=self.notebook)


def check_destination(rrd=None, spawn: bool = False, connect: str | None = None,
                      notebook=False) -> Destination | None:
    """The destination of a live recording (None if none is asked for), checked before any
    work: ParameterError (naming ``rrd``, ``spawn``, ``connect`` or ``notebook``) for an
    ``rrd`` whose name does not end in .rrd, ``spawn`` without a display, a ``connect`` that is
    no viewer's URL, ``notebook`` with another destination; OSError for an ``rrd`` that cannot
    be written, ConnectionError when no viewer answers at ``connect``; for ``notebook``,
    ImportError without rerun-notebook and RuntimeError outside a notebook."""
    from ..files import DEFAULT_CONNECT_URL, check_rrd_path, probe_viewer
    from ..params import ParameterError

    if notebook is not False and notebook is not None:
        if rrd is not None or spawn or connect is not None:
            raise ParameterError("notebook=True shows the recording in the cell, and goes "
                                 "alone: record to a file (rrd=PATH) or a viewer in another "
                                 "call", parameters=("notebook",))
        require_notebook("notebook=True", LIVE_ELSEWHERE)
        if notebook is not True and not hasattr(notebook, "add_recording"):
            raise ParameterError(f"notebook must be True or a viewer of coincli.viewer(), got "
                                 f"{type(notebook).__name__}", parameters=("notebook",))
        return Destination(notebook=notebook)

    if rrd is not None:
        rrd = check_rrd_path(rrd)
        if rrd.suffix != ".rrd":
            raise ParameterError(f"rrd must be a file name ending in .rrd, got '{rrd}'",
                                 parameters=("rrd",))
    if connect is not None:
        try:
            probe_viewer(connect)
        except ValueError:
            raise ParameterError(f"connect must be the URL of a running Rerun viewer, e.g. "
                                 f"{DEFAULT_CONNECT_URL}, got {connect!r}",
                                 parameters=("connect",)) from None
    if spawn and not display_available():
        raise ParameterError(f"spawn: {NO_DISPLAY}; record to a file (rrd=PATH) or stream to "
                             "a running viewer (connect=URL)", parameters=("spawn",))
    where = Destination(rrd, bool(spawn), connect)
    return where if where else None


class InProcessRecording:
    """A recording made in this process to ``where`` (a :class:`Destination`) beside the work
    it shows: :meth:`open` opens the stream (``rec``); one that cannot be opened leaves
    ``error`` set and ``rec`` None, and the work goes on without it. Used as a context
    manager: leaving closes the stream (a failure then is ``error`` too)."""

    def __init__(self, where: Destination):
        self.where = where
        self.error: Exception | None = None
        self.rec = None
        self._streams = contextlib.ExitStack()

    def open(self, name: str) -> bool:
        """Open the stream named ``name``; whether it is open."""
        try:
            self.rec = self._streams.enter_context(self.where.stream(name))
        except (OSError, RuntimeError, ValueError) as exc:
            self.error, self.rec = exc, None
        return self.rec is not None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        try:
            self._streams.close()
        except (OSError, RuntimeError) as error:
            self.error = error
        return False


__all__ = ["APPLICATION_ID", "LIVE_ELSEWHERE", "NO_DISPLAY", "NOTEBOOK_EXTRA", "THROW_ELSEWHERE",
           "Destination", "FileWriter", "InProcessRecording", "NotebookMissing",
           "check_destination", "display_available", "in_notebook", "notebook_viewer",
           "open_stream", "require_notebook", "viewer_class"]
