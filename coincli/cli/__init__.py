"""The `coin` command line: the typer app (:mod:`.app`) with one module per command, or per
group of subcommands (:mod:`.basin`), each parsing its options, calling the API and printing.

:func:`run` is the command line's one entry: bad input of any kind (a mistyped option, a value
of the wrong type, a missing argument) is one ``error:`` line and exit code 2, instead of
click's boxed usage message; :func:`main` adds the handling of SIGTERM and SIGHUP
(:mod:`.interruptions`)."""

import typer

from . import (  # noqa: F401 - each adds its command(s) to the app, in this order
    accuracy_cmd,
    basin,
    bench_cmd,
    compile_cmd,
    fractions_cmd,
    methods_cmd,
    presets_cmd,
    simulate_cmd,
    stability_cmd,
)
from .app import app


def run(args: list[str] | None = None) -> int:
    """Run the app on ``args`` (default: this process's command line); its exit code."""
    try:
        code = app(args=args, standalone_mode=False)
    except typer.TyperException as exc:  # every error of typer's click
        if exc.exit_code != 2:  # not a usage error (a file click could not open...): its words
            exc.show()
            return exc.exit_code
        from .common import fail

        ctx = getattr(exc, "ctx", None)  # the command a usage error is about, when known
        command = ctx.command_path if ctx is not None else "coin"
        return fail(f"{exc.format_message().rstrip('.')} (see '{command} --help')").exit_code
    except typer.Abort:
        return 1
    return code if isinstance(code, int) else 0


def main() -> None:
    """The `coin` script."""
    import sys

    from .interruptions import ended_by_signal, stop_on_termination

    stop_on_termination()  # SIGTERM and SIGHUP as Ctrl-C, exit 143 and 129
    sys.exit(ended_by_signal(run))


__all__ = ["app", "main", "run"]
