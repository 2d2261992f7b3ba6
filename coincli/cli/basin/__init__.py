"""`coin basin`: the map of the final number n of quarter turns over two initial conditions, in a
resumable Zarr store, and what reads it. One module per subcommand; importing this package adds
the group and its subcommands to the app, in the order of `coin basin --help`."""

from . import (  # noqa: F401, I001 - each adds its subcommand to the group, in this order
    sweep,
    verify,
    render,
    stats,
    analyze,
    export,
    inspect,
)
from .group import basin_app

__all__ = ["basin_app"]
