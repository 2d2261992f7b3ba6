"""`coin basin export STORE OUT.nc|OUT.csv`: a basin store written out for other tools
(:func:`coincli.api.export_basin` does the work)."""

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ..common import console, err_console, fail, user_errors
from ..text import counted, say
from .group import basin_app, damaged_note, metadata_note


@basin_app.command("export")
def export_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    out: Annotated[Path, typer.Argument(help="The file to write: .nc (NetCDF-4, every variable "
                                             "and attribute) or .csv (one row per cell). An "
                                             "existing file is replaced.",
                                        metavar="OUT.nc|OUT.csv")],
) -> None:
    """Write a basin store to NetCDF-4 or CSV, by OUT's extension.

    NetCDF: the Dataset of coincli.open_basin, which xarray.open_dataset and coincli.open_basin read back (quarter_turns NaN where a cell has no label; nested attributes as JSON text). CSV: one row per cell, the first swept axis outermost: the two swept values, n, pose, status, certainty, settle_time, steps, rung; header names with units; empty fields where a value is missing. Cells of tiles not computed (or damaged) are exported as not computed.
    """  # noqa: E501
    from ... import api
    from ...api.basins import open_store
    from ...api.options import check_export_path, check_writable
    from ...api.words import describe_error

    with user_errors():
        check_export_path(out)
        store = open_store(path)
        basin = store.read()
        check_writable(out, what="export")  # before the work
        try:
            api.export_basin(basin, out)
        except OSError as exc:
            raise fail(describe_error(exc, f"cannot write {out}")) from None
        done, total = int((basin.done != 0).sum()), int(basin.done.size)
        n0, n1 = basin.arrays["status"].shape
        console.print(f"wrote {escape(str(out))} ({n0} x {n1} cells)", soft_wrap=True,
                      highlight=False)  # a path on one line, to copy
        if done < total:
            say(err_console, f"[yellow]partial:[/] {done} of {counted(total, 'tile')} "
                             "computed; the cells of the others are exported as not computed")
        metadata_note(store)
        damaged_note(path, basin.damaged, "exported as not computed")
