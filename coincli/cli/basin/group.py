"""The `coin basin` group: `coin basin STORE ...` runs `coin basin sweep STORE ...`, and the
subcommands of :mod:`coincli.cli.basin` read, check, draw, analyse and export a store. What
several of them say the same way lives here."""

import typer
from typer.core import TyperGroup

from ..app import SHORT_FOR, app, help_only
from ..common import err_console, warn
from ..text import counted, say


class BasinGroup(TyperGroup):
    """`coin basin PATH ...` runs `sweep`; `coin basin render|stats|sweep ...` as usual."""

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ctx.help_option_names:
            args = ["sweep", *args]
            # a usage error says what ran (cli.usage_error)
            ctx.meta[SHORT_FOR] = f"{ctx.command_path} STORE runs {ctx.command_path} sweep STORE"
        return super().parse_args(ctx, args)


basin_app = typer.Typer(
    cls=BasinGroup,
    invoke_without_command=True,  # `coin basin` alone: the help (see _group)
    help="Map the final number n of quarter turns over two initial conditions.\n\n"
         "coin basin OUT.zarr [OPTIONS] runs (or resumes) a sweep: it is short for "
         "`coin basin sweep OUT.zarr`, whose --help lists the options. Then "
         "`coin basin render OUT.zarr -o basin.png`, `coin basin stats OUT.zarr`, "
         "`coin basin show OUT.zarr` (in the Rerun viewer), and "
         "`coin basin verify OUT.zarr` to check a store.",
)
app.add_typer(basin_app, name="basin")


@basin_app.callback()
def _group(ctx: typer.Context) -> None:
    if ctx.invoked_subcommand is None:
        help_only(ctx)


def tile_list(tiles, most: int = 8) -> str:
    """'(0, 1), (2, 3) and 5 more'."""
    text = ", ".join(f"({i}, {j})" for i, j in list(tiles)[:most])
    return text + (f" and {len(tiles) - most} more" if len(tiles) > most else "")


def metadata_note(store) -> None:
    """One warning line when the metadata of ``store`` (a BasinStore, opened) are damaged, as
    `coin basin verify` finds them: a copy of the parameters changed or lost, or a metadata
    file that differs from what they give. The store is read with the parameters its tiles (or
    its other copies) prove; a resume rewrites the rest."""
    files = store.damaged_metadata()
    if not store.problems and not files:
        return
    what = store.problems[0] if store.problems else (
        f"{counted(len(files), 'metadata file')} {'differs' if len(files) == 1 else 'differ'} "
        "from its parameters: " + ", ".join(files[:3]) + (" ..." if len(files) > 3 else ""))
    more = len(store.problems) - 1 if store.problems else 0
    warn(f"{store.path}: damaged metadata ({what}{f', and {more} more' if more else ''}); "
         f"read with the parameters {READ_WITH[store.view.proof]}. `coin basin verify` lists "
         "the damage; the sweep command, run again, rewrites it")


# how the parameters a store is read with are known (BasinStore.view.proof)
READ_WITH = {"tiles": "its computed tiles prove", "digest": "of the copy its digest confirms",
             "agree": "its copies agree on"}


def damaged_note(path, damaged, treated: str) -> None:
    """One warning line naming the tiles of ``path`` that failed their check and how they
    were ``treated`` (drawn, exported... as not computed)."""
    if damaged:
        say(err_console, f"[yellow]damaged:[/] {counted(len(damaged), 'tile')} of {path} "
                         f"failed the integrity check, {treated}: {tile_list(damaged)}; rerun "
                         "the sweep command to recompute")
