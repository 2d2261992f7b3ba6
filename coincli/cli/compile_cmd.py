"""`coin compile`: compile the numerical kernels now, as a step of its own (``make install``
runs it), instead of in the first command that needs them."""

from typing import Annotated

import typer

from .app import app
from .common import compile_first, console
from .text import say


@app.command("compile")
def compile_command(
    quiet: Annotated[bool, typer.Option("--quiet", "-q", metavar="",
                                        help="One line before and one after, "
                                        "no live line.")] = False,
) -> None:
    """Compile the numerical kernels for this machine now (once after installing or updating; otherwise the first command that needs them does)."""  # noqa: E501
    from ..api.throws import cache_dir, kernels_cached

    if kernels_cached():
        say(console, f"the numerical kernels are compiled already (cached in {cache_dir()})")
        return
    compile_first(quiet)


__all__ = ["compile_command"]
