"""The Rerun options of `coin basin`, `coin basin show` and `coin fractions` (--rrd, --spawn,
--connect), checked before any work, and the policy for --spawn without a display (as
`coin simulate`'s: one warning line before the run, the work and its output as usual, any
--rrd file written, exit 1 at the end)."""

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from .common import err_console, fail, in_cli_words, warn
from .text import command, say

REC = "Recording (Rerun)"

LiveRrdOpt = Annotated[Path | None, typer.Option(
    "--rrd", metavar="FILE", help="Write the recording to this .rrd file (open it with "
    "`rerun FILE`).", rich_help_panel=REC)]
LiveSpawnOpt = Annotated[bool, typer.Option(
    "--spawn", metavar="", help="Open a Rerun viewer and stream to it as the work goes (without a "
    "display: says so, does the work, writes any --rrd file, exit 1).", rich_help_panel=REC)]
LiveConnectOpt = Annotated[str | None, typer.Option(
    "--connect", metavar="URL", help="Stream to a running viewer, e.g. "
    "rerun+http://127.0.0.1:9876/proxy.", rich_help_panel=REC)]


def destination(rrd: Path | None, spawn: bool, connect: str | None):
    """The checked destination of a recording (None if none was asked for), and whether a
    --spawn was dropped for want of a display (then said in one line: the caller exits 1 once
    its work is done). Fails in one line, before any work, on an unusable path or URL."""
    if rrd is None and not spawn and connect is None:
        return None, False  # nothing asked: Rerun's code is not even imported
    from ..io.live import check_destination
    from ..io.rrd import NO_DISPLAY, display_available
    from ..params import ParameterError

    no_viewer = spawn and not display_available()
    try:
        where = check_destination(rrd, spawn and not no_viewer, connect)
    except ParameterError as exc:
        raise fail(in_cli_words(exc)) from None
    except OSError as exc:  # ConnectionError: no viewer at --connect
        raise fail(str(exc)) from None
    if no_viewer:
        to = (f"the recording is written to {rrd} (open it with {command('rerun', rrd)} "
              "where there is a display)" if rrd is not None else
              "record it with --rrd FILE (open it with `rerun FILE` where there is a "
              "display)")
        warn(f"--spawn: {NO_DISPLAY}; the work is done and its result printed; {to}, or "
             "stream it with --connect URL")
    return where, no_viewer


def places(where) -> list[str]:
    """Where a recording went (anything with ``rrd``, ``spawn`` and ``connect``), a phrase
    each."""
    out = []
    if where.rrd is not None:
        out.append(f"{where.rrd} (open with: {command('rerun', where.rrd)})")
    if where.spawn:
        out.append("streamed to a new viewer")
    if where.connect is not None:
        out.append(f"streamed to {where.connect}")
    return out


def recorded(where) -> str:
    """Where a recording went, for the last line of a command."""
    out = places(where)
    if where.rrd is not None:
        out[0] = f"wrote {out[0]}"
    return "; ".join(out)


def record_throw(run, *, rrd, spawn: bool, connect, log_every: float):
    """Record one throw (:func:`coincli.io.rrd.write_recording`): (its RecordingInfo, None), or
    (None, why it was not written, in one line) for the command to say after its outcome."""
    from ..io.paths import describe
    from ..io.rrd import write_recording

    try:
        return write_recording(run, rrd=rrd, spawn=spawn, connect=connect,
                               log_every=log_every), None
    except OSError as exc:
        return None, describe(exc)
    except (RuntimeError, ValueError) as exc:
        return None, str(exc)


def finish(recorder, no_viewer: bool, exit_code: int | None = 1) -> None:
    """After the work and its output: say why a recording asked for failed, and exit
    ``exit_code`` (None: leave the exit to the caller) if it did, or if --spawn found no
    display."""
    if recorder is not None and recorder.error is not None:
        from ..io.paths import explain

        why = explain(recorder.error)
        if exit_code is None:
            say(err_console, f"[bold red]error:[/] could not write the recording: {escape(why)}")
            return
        raise fail(f"could not write the recording: {why}")
    if no_viewer and exit_code is not None:
        raise typer.Exit(code=exit_code)


__all__ = ["LiveConnectOpt", "LiveRrdOpt", "LiveSpawnOpt", "destination", "finish",
           "recorded"]
