"""The `coin` command line: typer app assembled from one module per command.

The command modules do without ``from __future__ import annotations``: with it, typer has to
evaluate every option's annotation string, twice, on each start."""

import sys
from typing import Annotated

import typer

app = typer.Typer(
    name="coin",
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
    # Each module adds its command(s) to `app`; imported here so `coin --help` lists them all.
    import importlib

    from . import methods_cmd, presets_cmd, simulate_cmd, stability_cmd  # noqa: F401

    for optional in ("basin_cmd", "inspect_cmd", "accuracy_cmd", "bench_cmd", "fractions_cmd"):
        try:
            importlib.import_module(f"{__name__}.{optional}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{optional}":
                raise


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
