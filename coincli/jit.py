"""Kernels: plain Python functions registered once (:func:`kernel`), and the kernel sets built from
them for one model and one backend (:func:`kernels`), with the cache that keeps their machine
code.

**A kernel set.** The integrators call the model through the names of the seam
(:mod:`coincli.models.interface`: placeholders, :func:`placeholder`), and each other by name.
:func:`kernels` builds, for a model and a backend, a copy of every registered kernel whose
global names are looked up in a namespace of the set's own: the seam's names are the model's
functions, every other kernel name the set's copy of that kernel. The backend then makes each
copy what runs: numba's compiled dispatcher (:data:`NUMBA`), or the copy itself, run by CPython
(:data:`PYTHON`: no compilation, the faster choice for one short run). No module's names are
ever rebound: a kernel set is a value, and a process may hold several, of several models and
backends (what a GPU backend, compiling the same sources for another target, would need). The
seam is a compile-time choice: numba resolves a global function when it compiles its caller,
and inlines it where the callee is marked so; nothing is called through a pointer.

Why kernels are not ``numba.njit`` at import: importing numba and loading cached machine code
take a good part of a second, and most commands need neither (``coin --help``, a table, one
short throw, which CPython runs). Kernels are written in the subset of Python that numba
compiles and CPython runs alike, with the same operations in the same order.

Compiled, a multiply followed by an add may be fused into one FMA instruction (numba's
``fastmath={"contract"}``, nothing else of fast-math: no reassociation, NaN and infinity keep
their meaning), rounding once instead of twice: the Runge-Kutta stages are sums of products,
and fused they run markedly faster (docs/libraries.md). So the compiled kernels and CPython
agree to rounding, not to the bit: the same labels, steps and statuses on the tests' throws,
states equal to 1e-13 of their scale after one bounce and to 1e-7 after a second of them,
rounding growing along the motion (tests/test_engines.py). Compiled results are the same on
every machine whose CPU has FMA (x86-64 since 2013, ARM64).

``@kernel(inline=True)`` marks a small helper of a hot loop that numba inlines into each caller
before typing it (``inline="always"``): no call, and the caller's code optimised across it.
numba then compiles a copy of the helper, and of everything inlined into it, at every call
site, so each such mark costs compile time and memory in every caller: helpers of paths that
run seldom (locating a contact event) are compiled once, as functions of their own, and called.

:func:`derive` makes another instance of a module's kernels in which some global names mean
something else (the adaptive driver with DOP853's step): one source, several drivers, in every
kernel set.

The cache is numba's own (``cache=True``), in a folder of this installation named after a
digest of every kernel source and numba's version (:func:`kernel_cache_dir`); each model's
copies are named after it (numba keys its cache on a function's qualified name), so the
models' machine code sits side by side. numba checks only the timestamp of the file that
defines a function, not those of the files whose kernels it calls; in a folder that only these
sources use, an edit of a callee cannot leave stale machine code in use. numba is given the
folder through ``numba.config.CACHE_DIR`` (what ``NUMBA_CACHE_DIR`` sets) while the dispatchers
are made, which is when numba fixes each one's cache folder, and the setting is put back at
once: numba may have been imported before coincli (in a notebook), and its cache for other
code stays where its user put it. A marker per model written after a whole compilation
(:func:`mark_cached`) is what :func:`kernels_cached` reads; the first marking of a digest
removes this installation's folders of other digests and the folders of installations that are
gone (:func:`prune_cache`).
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import os
import shutil
import sys
import threading
import types
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
# Every module that defines kernels (or derives them, or declares the seam): all are imported
# before any kernel set is built, so that every set holds every kernel.
KERNEL_MODULES = ("coincli.models.interface", "coincli.models.rotation",
                  "coincli.models.rectangle", "coincli.models.paper", "coincli.models.friction",
                  "coincli.models.tables", "coincli.integrators.rodas",
                  "coincli.integrators.switching",
                  "coincli.integrators.common", "coincli.integrators.fixed",
                  "coincli.integrators.dopri", "coincli.integrators.dop853",
                  "coincli.integrators.flight", "coincli.integrators.adaptive",
                  "coincli.integrators.pairs", "coincli.integrators.batch")
_KERNELS: list = []  # the registered Python functions, in definition order
_INLINE: set = set()  # kernels numba inlines into their callers (small helpers on hot paths)
_SETS: dict = {}  # (model name, backend name) -> KernelSet
_LOCK = threading.Lock()

# About how long the first compilation takes on 2 cores (coin compile, or the first command
# that runs kernels): the one figure every notice gives (docs/performance.md, "First compile").
FIRST_COMPILE_SECONDS = 60

MARKER = "compiled"  # in a kernel cache folder: a model's kernels were all compiled into it
INSTALLATION_RECORD = "installation.txt"  # in an installation's folder: its package, its prefix


def kernel(fn=None, *, inline: bool = False):
    """Register ``fn`` as a kernel (see the module docstring); returns it unchanged.
    ``@kernel(inline=True)`` marks a small helper that numba inlines into every caller (no
    call: the hot loops stay one function in the compiled code)."""
    if fn is None:
        return lambda f: kernel(f, inline=inline)
    _KERNELS.append(fn)
    if inline:
        _INLINE.add(fn)
    return fn


class Placeholder:
    """A name of the model seam (:mod:`coincli.models.interface`): what a model gives a meaning
    to. Calling it outside a kernel set is an error: code that needs the model asks a set."""

    def __init__(self, name: str, doc: str):
        self.name = name
        self.__doc__ = doc

    def __repr__(self) -> str:
        return f"<seam name {self.name}>"

    def __call__(self, *args, **kwargs):
        raise TypeError(f"{self.name} is a name of the model seam: call it from a kernel set "
                        f"(coincli.jit.kernels(model, backend).{self.name})")


def placeholder(name: str, doc: str) -> Placeholder:
    """A name of the model seam, documented by ``doc`` (its arguments and result)."""
    return Placeholder(name, doc)


def derive(module, suffix: str, **substitutions) -> types.SimpleNamespace:
    """Another instance of every kernel defined in ``module``, in which the global names given
    as keywords mean something else: e.g. the adaptive driver with another Runge-Kutta pair's
    ``step``. One source, several kernels: each copy shares the original's code but looks its
    globals up in a copy of the module's namespace with the substitutions, and so do the copies
    of the module's other kernels it calls. The copies are registered kernels, named with
    ``suffix`` (numba keys its cache on the name, so they cannot load each other's machine
    code). Returns the namespace of the copies (attribute access)."""
    namespace = dict(vars(module))
    unknown = set(substitutions) - set(namespace)
    if unknown:
        raise NameError(f"{module.__name__} has no global {sorted(unknown)}")
    namespace.update(substitutions)
    # a kernel of the module that a substitution replaces is not copied: the substitute stands
    originals = [(name, fn) for name, fn in vars(module).items()
                 if callable(fn) and fn in _KERNELS and name not in substitutions
                 and getattr(fn, "__module__", None) == module.__name__]
    for name, fn in originals:
        copy = types.FunctionType(fn.__code__, namespace, fn.__name__ + suffix,
                                  fn.__defaults__, fn.__closure__)
        copy.__qualname__ = fn.__qualname__ + suffix
        copy.__doc__ = fn.__doc__
        copy.__module__ = fn.__module__
        namespace[name] = kernel(copy, inline=fn in _INLINE)
    return types.SimpleNamespace(**{name: namespace[name] for name, _ in originals})


# -- backends ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Backend:
    """What runs the kernels of a set: ``make(copies)`` turns the set's copies of the kernels
    (registered kernel -> its copy) into what runs (registered kernel -> runnable). A new
    target (a GPU) is a ``make`` and its entry in :data:`BACKENDS`."""

    name: str
    summary: str
    compiled: bool  # machine code (loaded from the cache, or compiled the first time)
    make: Callable[[dict], dict]


def _numba_cpu(copies: dict) -> dict:
    """numba's dispatchers, cached. numba fixes a dispatcher's cache folder when it is made:
    this sources' folder then (numba's setting put back after), or no cache where that folder
    cannot be written (numba would cache elsewhere, where a stale callee could load)."""
    import numba

    folder = kernel_cache_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        cache = os.access(folder, os.W_OK)
    except OSError:
        cache = False
    previous = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = str(folder)
    try:
        return {fn: numba.njit(cache=cache, nogil=True, fastmath={"contract"},
                               inline="always" if fn in _INLINE else "never")(copy)
                for fn, copy in copies.items()}
    finally:
        numba.config.CACHE_DIR = previous


NUMBA = Backend("numba", "numba's machine code for this CPU, cached on disk", True, _numba_cpu)
PYTHON = Backend("python", "CPython on the same source: no compilation, for one short run",
                 False, dict)
BACKENDS = {b.name: b for b in (NUMBA, PYTHON)}


def backend_named(name) -> Backend:
    """The backend of that name (a Backend is its own name)."""
    if isinstance(name, Backend):
        return name
    try:
        return BACKENDS[str(name)]
    except KeyError:
        raise ValueError(f"unknown backend {name!r}; known: {', '.join(BACKENDS)}") from None


# -- kernel sets --------------------------------------------------------------------------------
class KernelSet:
    """Every kernel of one model for one backend (:func:`kernels`): ``ks[fn]`` is the set's
    version of the registered kernel ``fn``; ``ks.name`` that of the kernel or seam name
    ``name`` (a name several kernels share, as the pairs' ``step``, only by ``ks[fn]``)."""

    def __init__(self, model, backend: Backend, copies: dict, seam: dict):
        self.model, self.backend = model, backend
        self._copies, self._seam = copies, seam
        by_name: dict = {}
        for fn, made in copies.items():
            by_name.setdefault(fn.__name__, []).append(made)
        self._by_name = by_name

    def __repr__(self) -> str:
        return f"KernelSet({self.model.name}, {self.backend.name})"

    def __getitem__(self, fn):
        if isinstance(fn, Placeholder):
            return self._seam[fn.name]
        return self._copies[fn]

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        if name in self._seam:
            return self._seam[name]
        found = self._by_name.get(name, [])
        if len(found) != 1:
            raise AttributeError(f"{self!r} has {len(found)} kernels named {name!r}")
        return found[0]


def kernels(model, backend=NUMBA) -> KernelSet:
    """The kernel set of ``model`` (a :class:`coincli.models.Model`) for ``backend`` (a Backend
    or its name), built once per process."""
    backend = backend_named(backend)
    key = (model.name, backend.name)
    found = _SETS.get(key)
    if found is None:
        with _LOCK:
            found = _SETS.get(key)
            if found is None:
                found = _SETS[key] = _build(model, backend)
    return found


def is_built(model, backend=NUMBA) -> bool:
    """Whether this process holds the kernel set already (its machine code loaded or compiled
    when a kernel of it first ran)."""
    return (model.name, backend_named(backend).name) in _SETS


def _build(model, backend: Backend) -> KernelSet:
    _import_kernel_modules()
    implementations = model.implementations()
    registered = set(_KERNELS)

    def is_kernel(value) -> bool:
        return isinstance(value, types.FunctionType) and value in registered

    suffix = f"__{model.name}"
    spaces: dict[int, dict] = {}  # id of a kernel's globals -> the set's copy of them
    copies: dict = {}
    for fn in _KERNELS:
        space = spaces.get(id(fn.__globals__))
        if space is None:
            space = spaces[id(fn.__globals__)] = dict(fn.__globals__)
        copy = types.FunctionType(fn.__code__, space, fn.__name__ + suffix, fn.__defaults__,
                                  fn.__closure__)
        copy.__qualname__ = fn.__qualname__ + suffix
        copy.__doc__ = fn.__doc__
        copy.__module__ = fn.__module__
        copies[fn] = copy
    made = backend.make(copies)
    seam = {name: made[value] if is_kernel(value) else value
            for name, value in implementations.items()}
    for space in spaces.values():
        for name, value in list(space.items()):
            if isinstance(value, Placeholder):
                space[name] = seam[value.name]
            elif is_kernel(value):
                space[name] = made[value]
    return KernelSet(model, backend, made, seam)


# -- the cache ------------------------------------------------------------------------------------
def cache_dir() -> Path:
    """Where coincli keeps its compiled kernels: ``$NUMBA_CACHE_DIR/coincli`` if that is set,
    else ``coincli`` in the user's cache folder (``$XDG_CACHE_HOME``, ``~/.cache``). It may be
    deleted at any time: the kernels then compile again."""
    base = os.environ.get("NUMBA_CACHE_DIR")
    if base:
        return Path(base) / "coincli"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "coincli"


def installation_dir() -> Path:
    """The folder of this installation's kernel caches: one per package folder and Python
    environment (two checkouts, or two environments of one checkout, compile apart)."""
    place = hashlib.sha256(f"{_PACKAGE}\n{sys.prefix}".encode()).hexdigest()[:12]
    return cache_dir() / f"install-{place}"


@functools.cache
def numba_version() -> str:
    """The installed numba's version, read without importing numba."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("numba")
    except PackageNotFoundError:
        return "unknown"


def kernel_cache_dir() -> Path:
    """The folder numba caches these kernel sources in, compiled by this numba: named after
    both, so that no other sources (an edit, another version) ever load from it."""
    return installation_dir() / f"{sources_digest()}-numba-{numba_version()}"


def marker(model_name: str = "paper") -> str:
    """The name of the file that says a model's kernels are all compiled."""
    return MARKER if model_name == "paper" else f"{MARKER}-{model_name}"


def kernels_cached(model_name: str = "paper") -> bool:
    """Whether this installation has compiled a model's kernels of these sources already (so
    that using them takes a second, not a minute): the marker :func:`mark_cached` writes."""
    return (kernel_cache_dir() / marker(model_name)).exists()


def mark_cached(model_name: str = "paper") -> None:
    """Record that every kernel of a model of these sources is compiled into
    :func:`kernel_cache_dir`; the first marking of these sources prunes what other sources
    left (:func:`prune_cache`)."""
    folder = kernel_cache_dir()
    first = not any(folder.glob(f"{MARKER}*")) if folder.is_dir() else True
    try:
        folder.mkdir(parents=True, exist_ok=True)
        (folder.parent / INSTALLATION_RECORD).write_text(f"{_PACKAGE}\n{sys.prefix}\n")
        (folder / marker(model_name)).touch()
    except OSError:
        return  # an unwritable cache only means the notice shows again
    if first:
        prune_cache()


def prune_cache() -> None:
    """Remove what no process of this installation, nor any other installation still there,
    loads any more: this installation's folders of other digests (an upgrade or an edit of the
    package, another numba) and the folders of installations whose package or environment is
    gone (each records both, :data:`INSTALLATION_RECORD`). Never raises: a cache that cannot
    be pruned only takes room."""
    current = kernel_cache_dir()
    try:
        for folder in current.parent.iterdir():
            if folder != current and folder.is_dir():
                shutil.rmtree(folder, ignore_errors=True)
        for installation in cache_dir().glob("install-*"):
            record = installation / INSTALLATION_RECORD
            if installation != current.parent and record.is_file() and not all(
                    Path(line).is_dir() for line in record.read_text().splitlines()):
                shutil.rmtree(installation, ignore_errors=True)
    except OSError:
        pass


def _import_kernel_modules() -> None:
    import importlib

    for module in KERNEL_MODULES:
        importlib.import_module(module)


def digest_files(files) -> str:
    """A short hash of the contents of ``files`` (paths), in the order given."""
    digest = hashlib.sha256()
    for name in files:
        digest.update(Path(name).read_bytes())
    return digest.hexdigest()[:16]


def source_files() -> list[str]:
    """Every file that defines a kernel, derives kernels (:func:`derive`) or a type the kernels
    use, sorted (every kernel module imported first, so that the list is whole whoever asks
    first)."""
    _import_kernel_modules()
    return sorted({inspect.getfile(fn) for fn in _KERNELS}
                  | {inspect.getfile(sys.modules[name]) for name in KERNEL_MODULES}
                  | {str(_PACKAGE / name) for name in ("jit.py", "params.py", "enums.py")})


@functools.cache  # the sources do not change under a running process; hashing them is 3 ms
def sources_digest() -> str:
    """Hash of :func:`source_files`: what the kernel cache's folder is named after."""
    return digest_files(source_files())


__all__ = ["BACKENDS", "Backend", "FIRST_COMPILE_SECONDS", "INSTALLATION_RECORD",
           "KERNEL_MODULES", "KernelSet", "MARKER", "NUMBA", "PYTHON", "Placeholder",
           "backend_named", "cache_dir", "derive", "digest_files", "installation_dir",
           "is_built", "kernel", "kernel_cache_dir", "kernels", "kernels_cached",
           "mark_cached", "marker", "numba_version", "placeholder", "prune_cache",
           "source_files", "sources_digest"]
