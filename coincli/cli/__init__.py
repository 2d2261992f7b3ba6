"""The `coin` command line: typer app assembled from one module per command."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="coin",
    help="The plane model of a rigid coin impacting an elastic foundation: simulate one throw, "
         "map which throws make the coin lie or stand, and check the numbers.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)


def _register() -> None:
    # Each module adds its command(s) to `app`; imported here so `coin --help` lists them all.
    import importlib

    from . import methods_cmd, presets_cmd, simulate_cmd, stability_cmd  # noqa: F401

    for optional in ("basin_cmd", "accuracy_cmd", "bench_cmd"):
        try:
            importlib.import_module(f"{__name__}.{optional}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{optional}":
                raise


_register()


def main() -> None:
    app()
