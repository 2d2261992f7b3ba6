"""How a `coin` command ends early, for every command in one place: Ctrl-C in two steps (the
first finishes the work in flight, the second stops at once: :class:`GracefulStop`), SIGTERM and
SIGHUP taken as a second Ctrl-C, and a lost Dask scheduler said in one line.

A batch scheduler (Slurm, Kubernetes) sends SIGTERM some seconds before it kills a job, and a
closed terminal sends SIGHUP. By default either ends Python at once, like ``kill -9``: no run
record, claims left for other hosts to wait out. The `coin` command (only it: a program or
notebook that imports coincli keeps its own handlers) takes them as a Ctrl-C that stops at once,
as a second Ctrl-C does: the work in flight stops unwritten, the claims are released, the run is
recorded as interrupted, and the command says how to resume and exits 128 + the signal's number
(143 for SIGTERM, 129 for SIGHUP), as a shell reports a process the signal ended. Not the
gentler first Ctrl-C, which lets the tiles in flight finish: nobody knows how long the sender
waits before its SIGKILL, and after a SIGHUP nobody is there to press Ctrl-C a second time.
"""

import signal
import sys
import threading

from .common import err_console
from .text import command, say

TERMINATING = (signal.SIGTERM, signal.SIGHUP)
SCHEDULER_LOST = 3  # exit code: the run could not go on, the store is fine, resume it

_received: list[int] = []  # the termination signals that arrived, in order
_installed = False


def stop_on_termination() -> None:
    """From now on SIGTERM and SIGHUP raise KeyboardInterrupt in the main thread (a second one
    too, so a second signal stops the clean-up of the first). A signal ignored already stays
    ignored (``nohup`` ignores SIGHUP). For the `coin` command's main thread only."""
    global _installed
    for signum in TERMINATING:
        if signal.getsignal(signum) is not signal.SIG_IGN:
            signal.signal(signum, _interrupt)
    _installed = True


def _interrupt(signum, frame):
    _received.append(signum)
    raise KeyboardInterrupt(signal.Signals(signum).name)


def received() -> signal.Signals | None:
    """The first termination signal that arrived, if any."""
    return signal.Signals(_received[0]) if _received else None


def stopped_by() -> str:
    """'SIGTERM: ' after a SIGTERM, etc.; '' otherwise (a message's prefix)."""
    signum = received()
    return f"{signum.name}: " if signum is not None else ""


def exit_code(code: int) -> int:
    """The command's exit code, or 128 + the signal's number if a termination signal stopped
    it: whatever the command made of the KeyboardInterrupt (130 as for Ctrl-C, 1 from click's
    abort), and 0 too (it may have finished the last piece of work as the signal came; the
    sender asked for an end all the same). An error code of its own (2, 3) stays."""
    signum = received()
    if signum is None or code not in (0, 1, 130):
        return code
    return 128 + signum


def ended_by_signal(run) -> int:
    """``run()``'s exit code, as :func:`exit_code` makes it. After a termination signal, a
    KeyboardInterrupt that got out (a second signal during the clean-up of the first) or an
    OSError (the terminal a SIGHUP closed cannot be written to) ends it quietly with the
    signal's code: the run record and the claims were dealt with before any message."""
    try:
        return exit_code(run())
    except (KeyboardInterrupt, OSError):
        if received() is None:
            raise
        return exit_code(130)


class GracefulStop:
    """First Ctrl-C: say ``message`` and set ``event`` (the work in flight finishes, no more
    starts); second: KeyboardInterrupt (stop at once). For the block it guards, in the main
    thread; a SIGINT ignored already (a background job) stays ignored."""

    def __init__(self, message: str):
        self.message = message
        self.event = threading.Event()
        self.previous = None

    @property
    def requested(self) -> bool:
        return self.event.is_set()

    def __enter__(self):
        self.previous = signal.getsignal(signal.SIGINT)
        if self.previous is signal.SIG_IGN:
            self.previous = None
            return self
        try:
            signal.signal(signal.SIGINT, self._handle)
        except ValueError:  # not the main thread: Ctrl-C is not ours to handle
            self.previous = None
        return self

    def _handle(self, signum, frame):
        if self.requested:
            raise KeyboardInterrupt
        self.event.set()
        say(err_console, f"[yellow]interrupt:[/] {self.message} (Ctrl-C again to stop at "
                         "once)")

    def __exit__(self, *exc):
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)
        return False


def resume_command() -> str:
    """The command line to run again, quoted for the shell: this process's own when it is the
    `coin` command, else a description."""
    if _installed:
        return command("coin", *sys.argv[1:])
    return "the same command"


def lost_scheduler(exc, kept: str) -> str:
    """One line for a :class:`coincli.engines.executors.SchedulerLost`: what happened, that the
    store keeps what was finished (``kept``: 'every finished tile'), and how to resume."""
    return f"{exc}; the store keeps {kept}: resume with {resume_command()}"


__all__ = ["GracefulStop", "SCHEDULER_LOST", "TERMINATING", "ended_by_signal", "exit_code",
           "lost_scheduler", "received", "resume_command", "stop_on_termination", "stopped_by"]
