"""`coin basin render STORE -o FILE` (the map as PNG, SVG or PDF in the paper's colours) and
`coin basin show STORE` (the map in the Rerun viewer)."""

from pathlib import Path
from typing import Annotated

import typer

from ...api import ParameterError
from .. import recording
from ..common import (
    console,
    err_console,
    fail,
    user_errors,
    whole_option,
)
from ..recording import LiveConnectOpt, LiveRrdOpt, LiveSpawnOpt
from ..text import (
    command,
    counted,
    say,
)
from .group import basin_app, damaged_note, metadata_note


def _mark(text: str) -> tuple[str, str]:
    """--mark V,W as its two values (read as the swept axes' quantities by the render)."""
    from ...api.options import shown

    parts = text.split(",")
    if len(parts) != 2:
        raise ParameterError(f"--mark '{shown(text)}' is not V,W (the values of the two swept "
                             "axes)")
    return parts[0], parts[1]


@basin_app.command("render")
def render_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    out: Annotated[Path | None, typer.Option("--out", "-o", metavar="FILE", help="PNG, SVG or "
                                             "PDF to write (default: the store's name with "
                                             ".png).")] = None,
    title: Annotated[str | None, typer.Option("--title", help="Title of the picture.")] = None,
    dpi: Annotated[int, typer.Option("--dpi", help="Resolution of the PNG.",
                                     parser=whole_option, metavar="N")] = 150,
    n_max: Annotated[int | None, typer.Option("--n-max", metavar="N", help="Colour scale up "
                                              "to |n| = N (larger |n| take its ends) "
                                              "[dim]\\[24][/dim]", parser=whole_option)] = None,
    field: Annotated[str, typer.Option("--field", metavar="NAME", help="What to draw: n (the "
                                       "outcome) or settle_time (when it was decided).")]
    = "n",
    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also save the map to this Rerun "
                                             "recording (SegmentationImage with an "
                                             "AnnotationContext).")] = None,
    mark: Annotated[list[str] | None, typer.Option("--mark", metavar="V,W", help="Mark the "
                                                   "throw at V (first swept axis), W (second) "
                                                   "with a white circle; repeatable. `coin "
                                                   "basin inspect STORE` with the same values "
                                                   "replays it.")] = None,
) -> None:
    """Draw a basin store to a PNG, SVG or PDF in the paper's colours, or its settle-time map.

    n < 0 (clockwise) yellow to red, n > 0 (counter-clockwise) green to blue, n = 0 white, standing (odd n) black; uncertain cells grey, no outcome by t_end purple, non-finite magenta, not computed hatched. Works on partial stores.
    """  # noqa: E501
    from ... import api
    from ...api.basins import open_store
    from ...api.options import check_rrd_path, check_writable
    from ...api.words import describe_error

    with user_errors():
        if dpi < 10 or dpi > 1200:
            raise ParameterError(f"--dpi must be between 10 and 1200, got {dpi}")
        if rrd is not None and rrd.suffix != ".rrd":
            raise ParameterError(f"--rrd {rrd}: the file name must end in .rrd")
        target = out if out is not None else path.with_suffix(".png")
        if target.suffix.lower() not in (".png", ".svg", ".pdf"):
            raise ParameterError(f"-o {target}: the file name must end in .png, .svg or .pdf")
        if n_max is not None and n_max < 1:
            raise ParameterError(f"--n-max must be at least 1, got {n_max}")
        marks = [_mark(text) for text in mark or ()]
        store = open_store(path)
        basin = store.read()
        check_writable(target, what="picture")  # before drawing
        if rrd is not None:
            check_rrd_path(rrd)
        try:
            api.render_basin(basin, target, title=title, dpi=dpi, n_max=n_max, field=field,
                             marks=marks)
        except OSError as exc:
            raise fail(describe_error(exc, f"cannot write {target}")) from None
        console.print(f"wrote {target}")
        metadata_note(store)
        damaged_note(path, basin.damaged, "drawn as not computed")
        if rrd is not None:
            try:
                api.show_basin(basin, rrd=rrd)  # as `coin basin show --rrd`
            except OSError as exc:
                raise fail(describe_error(exc, f"cannot write {rrd}")) from None
            say(console, f"wrote {rrd} (open with: {command('rerun', rrd)})")


@basin_app.command("show")
def show_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    rrd: LiveRrdOpt = None, spawn: LiveSpawnOpt = False, connect: LiveConnectOpt = None,
) -> None:
    """Open a basin store in the Rerun viewer: the map of n in the paper's colours (hover a cell: "n = 7, standing"), the uncertain and unfinished cells over it, cells not computed left grey.

    Opens a viewer unless --rrd or --connect is given (--spawn as well: both). Works on partial stores.

    Example:

    coin basin show out.zarr --rrd out.rrd
    """  # noqa: E501
    from ... import api
    from ...api.basins import open_store

    with user_errors():
        store = open_store(path)
        basin = store.read()
    if rrd is None and connect is None:  # a viewer, then, or nothing to do
        from ...api.recording import NO_DISPLAY, display_available

        if not display_available():
            say(err_console, f"[bold red]error:[/] {NO_DISPLAY} here: write the recording "
                             "with --rrd FILE (open it with `rerun FILE` where there is one), "
                             "or stream it to a running viewer with --connect URL")
            raise typer.Exit(code=1)
        spawn = True
    where_to, no_viewer = recording.destination(rrd, spawn, connect)
    metadata_note(store)
    damaged_note(path, basin.damaged, "shown as not computed")
    try:
        api.show_basin(basin, rrd=where_to.rrd, spawn=where_to.spawn, connect=where_to.connect)
    except (OSError, RuntimeError) as exc:
        from ...api.words import describe_error

        raise fail("could not write the recording: "
                   + (describe_error(exc) if isinstance(exc, OSError) else str(exc))) from None
    done, total = int(basin.done.sum()), int(basin.done.size)
    say(console, f"{path}: {done} of {counted(total, 'tile')} computed; "
                 f"{recording.recorded(where_to)}")
    if no_viewer:
        raise typer.Exit(code=1)
