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

        return fail(usage_error(exc)).exit_code
    except typer.Abort:
        return 1
    return code if isinstance(code, int) else 0


def usage_error(exc) -> str:
    """A usage error's line: click's words and the command whose --help to see; for a command
    the user did not name (`coin basin STORE` runs `coin basin sweep`), which it was; for an
    option the command lacks, the commands beside it that take it (`coin basin x.zarr -o
    out.png`: -o is `coin basin render`'s)."""
    from .app import SHORT_FOR

    message = exc.format_message().rstrip(".")
    ctx = getattr(exc, "ctx", None)  # the command a usage error is about, when known
    if ctx is None:
        return f"{message} (see 'coin --help')"
    see = ctx.command_path
    ran = ctx.meta.get(SHORT_FOR) if ctx.parent is not None else None
    option = getattr(exc, "option_name", None)
    # the commands of a group (`coin basin ...`) work on one thing, so another's option may be
    # what was meant; `coin`'s commands are tools apart, and are not searched
    group = ctx.parent.command if ctx.parent is not None and ctx.parent.parent is not None \
        else None
    siblings = [(name, group.get_command(ctx.parent, name))
                for name in group.list_commands(ctx.parent)] if group and option else []
    takers = [f"{ctx.parent.command_path} {name}" for name, sibling in siblings
              if sibling is not None and sibling is not ctx.command
              and not getattr(sibling, "hidden", False)
              and any(option in param.opts for param in sibling.params)]
    if takers:  # click's guesses at a near name (--out: --dt, --quiet) would lead astray
        message, see = f"No such option: {option}", takers[0]
        takes = (f"{option} is an option of {' and '.join(takers)}"
                 + (f", not of {ctx.command_path}" if not ran else ""))
        return f"{message}: {ran + ', which has none; ' if ran else ''}{takes} (see " \
               f"'{see} --help')"
    return f"{message}{f': {ran}' if ran else ''} (see '{see} --help')"


def main() -> None:
    """The `coin` script."""
    import sys

    from .interruptions import ended_by_signal, stop_on_termination

    stop_on_termination()  # SIGTERM and SIGHUP as Ctrl-C, exit 143 and 129
    sys.exit(ended_by_signal(run))


__all__ = ["app", "main", "run"]
