"""Names that a light module of the API offers but another, heavier module of the package
defines, loaded on first use (a module's ``__getattr__``, PEP 562).

:mod:`.options`, :mod:`.words` and :mod:`.errors` are imported by every command module of the
command line at start-up, so they import at module level only what `coin --help` loads anyway
(the parameters, the presets, the defaults); a parser that needs numpy, a check of a path
that needs the file module, an exception of an engine load when first named. Each module
lists its names with the function that imports their module (a plain ``from .. import
grid``, which the layer tests read), so that nothing is imported by a name in a string."""

from __future__ import annotations

from collections.abc import Callable


def lazy_names(namespace: dict, table: dict[str, tuple[Callable, str]]):
    """The ``__getattr__`` of the module whose ``globals()`` is ``namespace``: ``table`` maps
    each lazy name to (a function that imports and returns the module defining it, the name
    there); a name loaded is kept in the namespace (as :mod:`coincli.api` keeps its own)."""

    def __getattr__(name: str):
        entry = table.get(name)
        if entry is None:
            raise AttributeError(f"module {namespace['__name__']!r} has no attribute {name!r}")
        load, attribute = entry
        value = getattr(load(), attribute)
        namespace[name] = value  # loaded once
        return value

    return __getattr__


__all__ = ["lazy_names"]
