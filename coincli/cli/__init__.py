"""The `coin` command line: typer app assembled from one module per command.

The command modules do without ``from __future__ import annotations``: with it, typer has to
evaluate every option's annotation string, twice, on each start."""

import inspect
import sys
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


class CommandList(TyperGroup):
    """The `coin` group: lists MAIN_COMMANDS first (typer lists a group such as `basin` after
    every plain command), each with its example under its summary."""

    def list_commands(self, ctx) -> list[str]:
        names = super().list_commands(ctx)
        return ([name for name in MAIN_COMMANDS if name in names]
                + [name for name in names if name not in MAIN_COMMANDS])

    def get_command(self, ctx, name: str):
        command = super().get_command(ctx, name)
        if command is not None and name in MAIN_COMMANDS and command.short_help is None:
            summary = inspect.cleandoc(command.help or "").split("\n\n")[0]
            command.short_help = f"{summary}\n[dim]e.g.[/dim] {MAIN_COMMANDS[name]}"
        return command


app = typer.Typer(
    name="coin",
    cls=CommandList,
    help="The plane model of a rigid coin impacting an elastic foundation: simulate one throw, "
         "map which throws make the coin lie or stand, and check the numbers. Every command "
         "has --help; the README has a tour.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=True,
)


def _version(value: bool) -> None:
    if value:
        from ..version import __version__

        typer.echo(f"coin (coincli) {__version__}")
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[bool, typer.Option("--version", metavar="", callback=_version,
                                          is_eager=True, help="Print the version and exit.")]
    = False,
) -> None:
    """The plane model of a rigid coin impacting an elastic foundation: simulate one throw, map which throws make the coin lie or stand, and check the numbers. Every command has --help; the README has a tour."""  # noqa: E501


def _register() -> None:
    # Each module adds its command(s) to `app`; imported here so `coin --help` lists them all,
    # in this order after MAIN_COMMANDS.
    from . import (  # noqa: F401
        accuracy_cmd,
        basin_cmd,
        bench_cmd,
        compile_cmd,
        fractions_cmd,
        inspect_cmd,
        methods_cmd,
        presets_cmd,
        simulate_cmd,
        stability_cmd,
    )


_register()


def _click_exceptions():
    try:  # typer 0.28 on carries its own click, and exports only BadParameter of its errors
        from typer._click import exceptions
    except ImportError:  # a typer that uses click itself
        from click import exceptions
    return exceptions


def run(args: list[str] | None = None) -> int:
    """Run the app; its exit code. A mistyped command line (an unknown option, a value of the
    wrong type, a missing argument) is one ``error:`` line and code 2, like every other bad
    input, instead of click's boxed usage message."""
    exceptions = _click_exceptions()
    try:
        code = app(args=args, standalone_mode=False)
    except exceptions.NoArgsIsHelpError as exc:  # `coin` alone: typer has printed the help
        if exc.format_message():
            exc.show()
        return exc.exit_code
    except exceptions.UsageError as exc:
        from .common import fail

        command = exc.ctx.command_path if exc.ctx is not None else "coin"
        return fail(f"{exc.format_message().rstrip('.')} (see '{command} --help')").exit_code
    except exceptions.ClickException as exc:
        exc.show()
        return exc.exit_code
    except typer.Abort:
        return 1
    return code if isinstance(code, int) else 0


def main() -> None:
    from .interruptions import ended_by_signal, stop_on_termination

    stop_on_termination()  # SIGTERM and SIGHUP as Ctrl-C, exit 143 and 129
    exit_now(ended_by_signal(run))


def exit_now(code: int) -> None:
    """End the process with ``code`` without tearing the interpreter down: with numba and the
    kernels loaded that takes 0.1-0.25 s (freeing every module and object one by one), a tenth
    of a short command. What a normal exit does that matters is done first: the atexit
    handlers (a Rerun recording's last flush, weakref finalizers, multiprocessing's clean-up)
    and the flush of stdout and stderr. Only when no other non-daemon thread is alive (a normal
    exit would wait for it); otherwise, or if a flush fails (a closed pipe), the normal exit."""
    import atexit
    import os
    import threading

    run_handlers = getattr(atexit, "_run_exitfuncs", None)  # CPython's; elsewhere, exit
    if run_handlers is None or any(
            thread.is_alive() and not thread.daemon and thread is not threading.main_thread()
            for thread in threading.enumerate()):
        sys.exit(code)
    run_handlers()  # runs each handler once and clears them: none runs twice below
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except (OSError, ValueError):
        sys.exit(code)
    os._exit(code)
