"""Kernels: plain Python functions that numba compiles on first use, and the cache that keeps
their machine code.

Why kernels are not ``numba.njit`` at import: importing numba and loading cached machine code
take a good part of a second, and most commands need neither (``coin --help``, a table, one
short throw). So :func:`kernel` only registers a function and returns it unchanged: it runs as
ordinary Python until :func:`compiled` is first called. That call imports numba, wraps every
registered kernel in a cached ``njit`` dispatcher and rebinds the names in the ``coincli``
modules to the dispatchers (numba resolves a kernel's callees through its module's globals), so
from then on every caller in the package runs compiled code. Kernels are written in the subset
of Python that numba compiles and CPython runs alike, with the same operations in the same
order.

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

The cache is numba's own (``cache=True``), in a folder of this installation named after a
digest of every kernel source and numba's version (:func:`kernel_cache_dir`). numba checks
only the timestamp of the file that defines a function, not those of the files whose kernels
it calls; in a folder that only these sources use, an edit of a callee cannot leave stale
machine code in use. numba is given the folder through ``numba.config.CACHE_DIR`` (what
``NUMBA_CACHE_DIR`` sets) while the dispatchers are made, which is when numba fixes each one's
cache folder, and the setting is put back at once: numba may have been imported before coincli
(in a notebook), and its cache for other code stays where its user put it. A marker written
after a whole compilation (:func:`mark_cached`) is what :func:`kernels_cached` reads; the first
marking of a digest removes this installation's folders of other digests and the folders of
installations that are gone (:func:`prune_cache`).
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
from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
# Every module that defines kernels: all are imported before numba sees any of them, so that a
# kernel's callees are dispatchers whatever was imported first.
KERNEL_MODULES = ("coincli.model", "coincli.integrators.common", "coincli.integrators.fixed",
                  "coincli.integrators.dopri", "coincli.integrators.dop853",
                  "coincli.integrators.flight", "coincli.integrators.adaptive",
                  "coincli.integrators.pairs", "coincli.integrators.batch")
_KERNELS: list = []  # the registered Python functions, in definition order
_INLINE: set = set()  # kernels numba inlines into their callers (small helpers on hot paths)
_NAMESPACES: list = []  # the globals of derived kernels (see derive), rebound like modules'
_DISPATCHERS: dict = {}  # Python function -> numba dispatcher (after activation)
_LOCK = threading.Lock()

# About how long the first compilation takes on 2 cores (coin compile, or the first command
# that runs kernels): the one figure every notice gives (docs/performance.md, "First compile").
FIRST_COMPILE_SECONDS = 60

MARKER = "compiled"  # in a kernel cache folder: its kernels were all compiled into it
INSTALLATION_RECORD = "installation.txt"  # in an installation's folder: its package, its prefix


def kernel(fn=None, *, inline: bool = False):
    """Register ``fn`` as a kernel (see the module docstring); returns it unchanged.
    ``@kernel(inline=True)`` marks a small helper that numba inlines into every caller (no
    call: the hot loops stay one function in the compiled code)."""
    if fn is None:
        return lambda f: kernel(f, inline=inline)
    if _DISPATCHERS:
        raise RuntimeError(f"kernel {fn.__qualname__} defined after numba was activated: add its "
                           "module to coincli.jit.KERNEL_MODULES")
    _KERNELS.append(fn)
    if inline:
        _INLINE.add(fn)
    return fn


def derive(module, suffix: str, **substitutions) -> types.SimpleNamespace:
    """Another instance of every kernel defined in ``module``, in which the global names given
    as keywords mean something else: e.g. the adaptive driver with another Runge-Kutta pair's
    ``step``. One source, several compiled kernels: each copy shares the original's code but
    looks its globals up in a copy of the module's namespace with the substitutions, and so do
    the copies of the module's other kernels it calls. The copies are named with ``suffix``
    (numba keys its cache on the name, so they cannot load each other's machine code).
    Returns the namespace of the copies (attribute access)."""
    if _DISPATCHERS:
        raise RuntimeError(f"derive({module.__name__}) after numba was activated: add the "
                           "deriving module to coincli.jit.KERNEL_MODULES")
    namespace = dict(vars(module))
    unknown = set(substitutions) - set(namespace)
    if unknown:
        raise NameError(f"{module.__name__} has no global {sorted(unknown)}")
    namespace.update(substitutions)
    originals = [(name, fn) for name, fn in vars(module).items()
                 if callable(fn) and fn in _KERNELS
                 and getattr(fn, "__module__", None) == module.__name__]
    for name, fn in originals:
        copy = types.FunctionType(fn.__code__, namespace, fn.__name__ + suffix,
                                  fn.__defaults__, fn.__closure__)
        copy.__qualname__ = fn.__qualname__ + suffix
        copy.__doc__ = fn.__doc__
        copy.__module__ = fn.__module__
        namespace[name] = kernel(copy, inline=fn in _INLINE)
    _NAMESPACES.append(namespace)
    return types.SimpleNamespace(**{name: namespace[name] for name, _ in originals})


def is_active() -> bool:
    """Whether the kernels have been handed to numba in this process."""
    return bool(_DISPATCHERS)


def compiled(fn):
    """The numba dispatcher of kernel ``fn`` (activating numba for every kernel first)."""
    if not _DISPATCHERS:
        _activate()
    return _DISPATCHERS.get(fn, fn)  # fn may already be a dispatcher (rebound name)


def python(fn):
    """The plain Python form of a kernel (also after activation), e.g. to apply the model's
    formulas to numpy arrays."""
    return getattr(fn, "py_func", fn)


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


def kernels_cached() -> bool:
    """Whether this installation has compiled these kernel sources already (so that using them
    takes a second, not a minute): the marker :func:`mark_cached` writes."""
    return (kernel_cache_dir() / MARKER).exists()


def mark_cached() -> None:
    """Record that every kernel of these sources is compiled into :func:`kernel_cache_dir`;
    the first time, prune what other sources left (:func:`prune_cache`)."""
    folder = kernel_cache_dir()
    first = not (folder / MARKER).exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        (folder.parent / INSTALLATION_RECORD).write_text(f"{_PACKAGE}\n{sys.prefix}\n")
        (folder / MARKER).touch()
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


def _activate() -> None:
    with _LOCK:
        if _DISPATCHERS:
            return
        import numba

        _import_kernel_modules()
        folder = kernel_cache_dir()
        try:
            folder.mkdir(parents=True, exist_ok=True)
            cache = os.access(folder, os.W_OK)
        except OSError:
            cache = False  # numba would cache elsewhere, where a stale callee could load
        previous = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = str(folder)
        try:
            dispatchers = {fn: numba.njit(cache=cache, nogil=True, fastmath={"contract"},
                                          inline="always" if fn in _INLINE else "never")(fn)
                           for fn in _KERNELS}
        finally:
            numba.config.CACHE_DIR = previous
        # rebind every name in the package that refers to a kernel, so that numba finds
        # dispatchers when it resolves a kernel's callees and Python callers run compiled code
        namespaces = [vars(module) for name, module in list(sys.modules.items())
                      if module is not None and (name == "coincli"
                                                 or name.startswith("coincli."))]
        for namespace in namespaces + _NAMESPACES:
            for attr, value in list(namespace.items()):
                if callable(value) and value in dispatchers:
                    namespace[attr] = dispatchers[value]
        _DISPATCHERS.update(dispatchers)


__all__ = ["FIRST_COMPILE_SECONDS", "INSTALLATION_RECORD", "KERNEL_MODULES", "MARKER",
           "cache_dir", "compiled", "derive", "digest_files", "installation_dir", "is_active",
           "kernel", "kernel_cache_dir", "kernels_cached", "mark_cached", "numba_version",
           "prune_cache", "python", "source_files", "sources_digest"]
