"""`coin compile`: compile the numerical kernels now, as a step of its own (``make install``
runs it), instead of in the first command that needs them: the paper's model's by default,
the friction model's (a scene with --mu > 0) with --friction, every model's with --all."""

from typing import Annotated

import typer

from .app import app
from .common import compile_first, console, fail
from .text import say


@app.command("compile")
def compile_command(
    quiet: Annotated[bool, typer.Option("--quiet", "-q", metavar="",
                                        help="One line before and one after, "
                                        "no live line.")] = False,
    friction: Annotated[bool, typer.Option("--friction", metavar="",
                                           help="Compile the friction model's kernels (what "
                                           "a scene with --mu > 0 runs) instead of the "
                                           "paper's.")] = False,
    every: Annotated[bool, typer.Option("--all", metavar="",
                                        help="Compile every model's kernels: the paper's and "
                                        "the friction model's.")] = False,
) -> None:
    """Compile the numerical kernels for this machine now (once after installing or updating; otherwise the first command that needs them does): the paper's model's, the friction model's with --friction, both with --all."""  # noqa: E501
    from ..api.throws import cache_dir, kernels_cached, model_names

    if friction and every:
        raise fail("give --friction or --all, not both")
    models = model_names() if every else ("friction",) if friction else ("paper",)
    for name in models:
        what = "the numerical kernels" if name == "paper" else \
            f"the {name} model's numerical kernels"
        if kernels_cached(model=name):
            say(console, f"{what} are compiled already (cached in {cache_dir()})")
            continue
        compile_first(quiet, model=name)


__all__ = ["compile_command"]
