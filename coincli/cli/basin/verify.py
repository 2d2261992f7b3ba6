"""`coin basin verify STORE`: every checksum, tile digest and metadata copy of a store checked,
nothing computed."""

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ..common import (
    JsonOpt,
    console,
    err_console,
    in_cli_words,
    print_json,
    user_errors,
)
from ..text import (
    counted,
    say,
)
from .group import basin_app


@basin_app.command("verify")
def verify_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    json_out: JsonOpt = False,
) -> None:
    """Check a store without computing anything: checksums, digests and metadata.

    Every chunk's checksum, every tile's data against its digest, every metadata file.

    Exit code 0 if the store is intact (complete or not), 1 if anything is damaged (listed: rerunning the sweep command recomputes those tiles), 2 if it is no basin store.
    """  # noqa: E501 (typer keeps a docstring's line breaks)
    from ... import api
    from ...api.errors import StoreDamaged

    damage = None
    with user_errors():
        try:
            found = api.verify_basin(path)
        except StoreDamaged as exc:  # its metadata: no tile can be checked
            damage = exc
    if damage is not None:
        exc = damage
        if json_out:
            print_json({"path": str(path), "intact": False, "error": in_cli_words(exc)})
        else:
            say(err_console, f"[bold red]damaged:[/] {escape(in_cli_words(exc))}")
        raise typer.Exit(code=1) from None
    total = int(found.done.size)
    unrepaired = [k for k in found.metadata if k not in found.repaired]
    if json_out:
        print_json({"path": str(path), "intact": found.intact, "tiles": total,
                    "tiles_done": found.tiles_done, "not_computed": total - found.tiles_done
                    - len(found.damaged),
                    "damaged": [{"tile": list(t), "reason": why}
                                for t, why in sorted(found.damaged.items())],
                    "metadata": unrepaired, "parameters_changed": found.problems,
                    "leftover_temporary_files": found.leftovers, "seconds": found.seconds})
    elif found.intact:
        missing = total - found.tiles_done
        say(console, f"{path}: intact: {found.tiles_done} of {total} tiles done and verified"
                     + (f", {missing} not computed yet" if missing else "")
                     + f" ({found.seconds:.2f} s)")
    else:
        what = [counted(len(found.damaged), "tile")] if found.damaged else []
        what += [counted(len(unrepaired), "metadata file")] if unrepaired else []
        say(console, f"{path}: DAMAGED: {' and '.join(what)}; {found.tiles_done} of {total} "
                     f"tiles intact ({found.seconds:.2f} s). Rerun the sweep command (with the "
                     "store's parameters) to "
                     + " and ".join((["recompute the damaged tiles"] if found.damaged else [])
                                    + (["rewrite the metadata"] if unrepaired else [])) + ".")
        for problem in found.problems:
            say(console, f"  parameters changed in {problem}")
        for tile, why in sorted(found.damaged.items()):
            say(console, f"  tile {tile}: {why}")
        for key in unrepaired:
            say(console, f"  metadata {key}: differs from what the parameters of its tiles "
                         "give")
    if found.leftovers and not json_out:
        say(err_console, f"note: {found.leftovers} temporary file(s) of interrupted writes "
                         "(*.partial); the next sweep removes them")
    if not found.intact:
        raise typer.Exit(code=1)
