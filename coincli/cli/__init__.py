"""The `coin` command line: typer app assembled from one module per command.

The command modules do without ``from __future__ import annotations``: with it, typer has to
evaluate every option's annotation string, twice, on each start. typer is held below 0.29
(pyproject.toml), which coerces every option's value through a pydantic adapter: importing
pydantic and building the adapters adds 0.15-0.2 s to every command that takes an option."""

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

    for optional in ("basin_cmd", "accuracy_cmd", "bench_cmd", "fractions_cmd"):
        try:
            importlib.import_module(f"{__name__}.{optional}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{optional}":
                raise


_register()


def main() -> None:
    from ..jit import skip_blas_probe

    skip_blas_probe()
    app()
