"""The `coin` typer app, to which each command module adds its command(s) (:mod:`coincli.cli`
imports them all, in the order `coin --help` lists them after MAIN_COMMANDS).

The command modules do without ``from __future__ import annotations``: with it, typer has to
evaluate every option's annotation string, twice, on each start."""

import inspect
from typing import Annotated

import typer
from typer.core import TyperGroup

# The commands `coin --help` lists first, each with an example; the others follow in the order
# their modules register them.
MAIN_COMMANDS = {
    "simulate": "coin simulate --vy 1.197 --vphi 3.508",
    "basin": "coin basin out.zarr --res 128",
    "fractions": "coin fractions --phi0 -pi:pi --vx -0.5:0.5 --samples 64k",
    "stability": "coin stability --k 250",
}
# The key of a click context's meta under which a group that runs a command the user did not
# name says so ("coin basin STORE runs coin basin sweep STORE"), for its usage errors.
SHORT_FOR = "coincli.short_for"


class CommandList(TyperGroup):
    """The `coin` group: lists MAIN_COMMANDS first (typer lists a group such as `basin` after
    every plain command), each with its example under its summary."""

    def get_params(self, ctx):
        return _bare_flags(super().get_params(ctx))

    def list_commands(self, ctx) -> list[str]:
        names = super().list_commands(ctx)
        return ([name for name in MAIN_COMMANDS if name in names]
                + [name for name in names if name not in MAIN_COMMANDS])

    def get_command(self, ctx, name: str):
        command = super().get_command(ctx, name)
        if command is not None and name in MAIN_COMMANDS and command.short_help is None:
            summary = inspect.cleandoc(command.help or "").split("\n\n")[0]
            command.short_help = f"{summary}\n[dim]e.g.[/dim] {MAIN_COMMANDS[name]}"
        if command is not None:
            _bare_flags_below(command, ctx)
        return command


def _bare_flags(params):
    """A flag takes no value, so its help line shows none: typer gives a flag without a metavar
    (--help, the completion options) the type `<bool>`."""
    for param in params:
        if getattr(param, "is_flag", False) and param.metavar is None:
            param.metavar = ""
    return params


def _bare_flags_below(command, ctx) -> None:
    """_bare_flags on ``command`` and, if it is a group, on every command under it."""
    _bare_flags(command.get_params(ctx))
    for subcommand in getattr(command, "commands", {}).values():
        _bare_flags_below(subcommand, ctx)


app = typer.Typer(
    name="coin",
    cls=CommandList,
    help="The plane model of a rigid coin impacting an elastic foundation: simulate one throw, "
         "map which throws make the coin lie or stand, and check the numbers. Every command "
         "has --help; the documentation (docs/ in the repository) has a tour.",
    invoke_without_command=True,  # `coin` alone: the help (see _options)
    pretty_exceptions_enable=False,
    add_completion=True,
)


def _version(value: bool) -> None:
    if value:
        from ..api import __version__

        typer.echo(f"coin (coincli) {__version__}")
        raise typer.Exit()


@app.callback()
def _options(
    ctx: typer.Context,
    version: Annotated[bool, typer.Option("--version", metavar="", callback=_version,
                                          is_eager=True, help="Print the version and exit.")]
    = False,
) -> None:
    """The plane model of a rigid coin impacting an elastic foundation: simulate one throw, map which throws make the coin lie or stand, and check the numbers. Every command has --help; the documentation (docs/ in the repository) has a tour."""  # noqa: E501
    if ctx.invoked_subcommand is None:
        help_only(ctx)


def help_only(ctx: typer.Context) -> None:
    """A group called without a command: its help, and exit 0."""
    typer.echo(ctx.get_help())
    raise typer.Exit()


__all__ = ["MAIN_COMMANDS", "app", "help_only"]
