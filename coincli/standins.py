"""Importing a module without some of what it imports: for a moment, stand-ins take the place of
modules it imports at the top but that a short command never uses, so that they are not loaded
(a library's ``__init__`` that loads every codec it has, a help screen's Markdown parser).

A stand-in is in ``sys.modules`` only while the one import runs, and only while no other thread
can import (the interpreter's import lock), so no other code ever sees it; afterwards importing
its name imports the real module, as usual. A name already loaded is not stood in for."""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import sys
import types


@contextlib.contextmanager
def standing_in(stand_ins: dict[str, types.ModuleType | None]):
    """Within the block the modules of ``stand_ins`` are in ``sys.modules`` under their names
    (those not loaded yet; a None stand-in makes importing its name raise ImportError), and no
    other thread can import; afterwards they are gone."""
    import _imp  # CPython's import lock (numba runs on CPython only)

    placed = [name for name in stand_ins if name not in sys.modules]
    if not placed:  # nothing to stand in: other threads may import as usual
        yield
        return
    _imp.acquire_lock()
    try:
        for name in placed:
            sys.modules[name] = stand_ins[name]
        yield
    finally:
        for name in placed:
            if sys.modules.get(name) is stand_ins[name]:
                del sys.modules[name]
        _imp.release_lock()


def package_stand_in(name: str) -> types.ModuleType | None:
    """An empty package that lets a submodule of package ``name`` import without the package's
    ``__init__`` (None if ``name`` is not an installed package)."""
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        return None
    stand_in = types.ModuleType(name)
    stand_in.__spec__ = spec
    stand_in.__path__ = list(spec.submodule_search_locations)
    return stand_in


class _Deferred(type):
    """The type of a class that stands in for ``_module``'s class of the same name: calling it
    or reading an attribute of it imports that module and hands over to the real class."""

    def real(cls):
        return getattr(importlib.import_module(cls._module), cls.__name__)

    def __call__(cls, *args, **kwargs):
        return cls.real()(*args, **kwargs)

    def __getattr__(cls, name):  # only for what the stand-in itself does not have
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(cls.real(), name)


def deferred_classes(module: str, *names: str) -> types.ModuleType:
    """A stand-in for ``module`` with classes ``names`` that import it when first used (an
    instance is the real class's; ``isinstance`` against the stand-in is always False)."""
    stand_in = types.ModuleType(module)
    for name in names:
        setattr(stand_in, name, _Deferred(name, (), {"_module": module}))
    return stand_in


class _StandInLoader:  # a loader (not importlib.abc's: importing that takes 0.04 s)
    def __init__(self, loader, stand_ins):
        self._loader = loader
        self._stand_ins = stand_ins

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module):
        module.__loader__ = module.__spec__.loader = self._loader
        with standing_in(self._stand_ins()):
            self._loader.exec_module(module)


class _StandInFinder:  # a meta path finder
    def __init__(self, target, stand_ins):
        self._target = target
        self._stand_ins = stand_ins

    def find_spec(self, fullname, path, target=None):
        if fullname != self._target:
            return None
        sys.meta_path.remove(self)  # once: find the real spec without this finder
        spec = importlib.util.find_spec(fullname)
        if spec is not None and spec.loader is not None:
            spec.loader = _StandInLoader(spec.loader, self._stand_ins)
        return spec


def import_with_stand_ins(target: str, stand_ins) -> None:
    """Have the first import of module ``target`` in this process, whoever asks for it and
    whenever, run under ``standing_in(stand_ins())``. Nothing if it is loaded already."""
    if target not in sys.modules:
        sys.meta_path.insert(0, _StandInFinder(target, stand_ins))


__all__ = ["deferred_classes", "import_with_stand_ins", "package_stand_in", "standing_in"]
