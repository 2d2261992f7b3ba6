"""The Rerun options of every command that records (--rrd, --spawn, --connect, --log-every),
checked before any work; the policy for --spawn without a display (one warning line before the
run, the work and its output as usual, any --rrd file written, exit 1 at the end); and where a
recording went, said in the command's last lines."""

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from .common import console, err_console, fail, in_cli_words, number_option, warn
from .text import LABEL_WIDTH, command, print_rows, say

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


MAX_FRAMES = 1_000_000


SpawnOpt = Annotated[bool, typer.Option("--spawn", metavar="",
                                        help="Open a Rerun viewer and stream the "
                                        "recording to it (without a display: says so, prints "
                                        "the outcome, writes any --rrd file, exit 1).",
                                        rich_help_panel=REC)]


ConnectOpt = Annotated[str | None, typer.Option("--connect", metavar="URL", help="Stream the "
                                                "recording to a running viewer, e.g. "
                                                "rerun+http://127.0.0.1:9876/proxy.",
                                                rich_help_panel=REC)]


LogEveryOpt = Annotated[float, typer.Option("--log-every", metavar="SECONDS", help="Simulated "
                                            "time between frames of the recording and rows of "
                                            "--csv (contact onsets and lift-offs are added to "
                                            "the recording at their exact times).",
                                            rich_help_panel=REC, parser=number_option)]


def check_log_every(scene, log_every, no_rrd_helps: bool = False) -> None:
    """Fail in one line, before the run, on an unusable display rate: too many frames says the
    smallest --log-every that fits, and --no-rrd where that alone makes the run need none."""
    if isinstance(log_every, bool) or not math.isfinite(log_every) or log_every <= 0:
        raise fail(f"--log-every must be a positive number of seconds, got {log_every}")
    from ..models import horizon_text, scene_horizon

    horizon = scene_horizon(scene)  # t_end, or the throw's cap (infinite: from a non-finite start)
    frames = horizon / log_every if math.isfinite(horizon) else 0.0
    if frames > MAX_FRAMES:
        remedy = f"--log-every {smallest_log_every(horizon)} or more"
        if no_rrd_helps:
            remedy = f"--no-rrd to write no recording, or {remedy}"
        raise fail(f"--log-every {log_every:g} s makes {frames:.3g} frames over "
                   f"{horizon:g} s ({horizon_text(scene)}; at most {MAX_FRAMES:,}): {remedy}")


def smallest_log_every(horizon: float) -> str:
    """The smallest --log-every of two significant digits that makes at most MAX_FRAMES frames
    over ``horizon`` seconds, as text."""
    text = f"{horizon / MAX_FRAMES:.2g}"
    while horizon / float(text) > MAX_FRAMES:  # rounded down: one more in the second digit
        text = f"{float(text) + 10.0 ** (math.floor(math.log10(float(text))) - 1):.2g}"
    return text


def print_recording(info) -> None:
    print_rows(console, [("recording", f"{'; '.join(places(info))}: {info.frames:,} frames, "
                              f"{info.events} contact events")], LABEL_WIDTH)


def destination(rrd: Path | None, spawn: bool, connect: str | None):
    """The checked destination of a recording (None if none was asked for), and whether a
    --spawn was dropped for want of a display (then said in one line: the caller exits 1 once
    its work is done). Fails in one line, before any work, on an unusable path or URL."""
    if rrd is None and not spawn and connect is None:
        return None, False  # nothing asked: Rerun's code is not even imported
    from ..params import ParameterError
    from ..recordings.stream import NO_DISPLAY, check_destination, display_available

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
    """Record one throw (:func:`coincli.recordings.rrd.write_recording`): (its RecordingInfo, None),
    or (None, why it was not written, in one line) for the command to say after its outcome."""
    from ..files import describe
    from ..recordings.rrd import write_recording

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
        from ..files import explain

        why = explain(recorder.error)
        if exit_code is None:
            say(err_console, f"[bold red]error:[/] could not write the recording: {escape(why)}")
            return
        raise fail(f"could not write the recording: {why}")
    if no_viewer and exit_code is not None:
        raise typer.Exit(code=exit_code)


__all__ = ["ConnectOpt", "LiveConnectOpt", "LiveRrdOpt", "LiveSpawnOpt", "LogEveryOpt",
           "MAX_FRAMES", "REC", "SpawnOpt", "check_log_every", "destination", "finish",
           "print_recording", "smallest_log_every",
           "recorded"]
