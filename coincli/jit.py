"""Kernels: plain Python functions that numba compiles on first use, with a cache that cannot go
stale and that leaves numba's settings for other code alone.

Why kernels are not ``numba.njit`` at import: importing numba costs about 0.3 s and loading the
cached machine code 0.1 s more (0.3 s more as numba itself loads it, :func:`_refresh_on_miss`), and
most commands need neither (``coin --help``, a table, one short throw). So :func:`kernel` only
registers a function and returns it unchanged: it runs as ordinary Python until :func:`compiled` is
first called. That call imports numba, wraps every registered kernel in a cached ``njit``
dispatcher and rebinds the names in the ``coincli`` modules to the dispatchers (numba resolves a
kernel's callees through its module's globals), so from then on every caller in the package runs
compiled code. Kernels are written in the subset of Python that numba compiles and CPython runs
alike, with the same operations in the same order.

Compiled, a multiply followed by an add may be fused into one FMA instruction (numba's
``fastmath={"contract"}``, nothing else of fast-math: no reassociation, NaN and infinity keep
their meaning), rounding once instead of twice: the Runge-Kutta stages are sums of products,
and the kernels run 1.38 times faster (0.0165 against 0.0227 ms a trajectory, three
interleaved rounds). So the compiled kernels and CPython agree to rounding, not to the bit: the
same labels, steps and statuses on the tests' throws, states equal to 1e-13 of their scale
after one bounce and to 1e-7 after a second of them, rounding growing along the motion
(tests/test_engines.py); on 5,632 throws of the paper and thick coins, no certain label changed.
Compiled results are the same on every machine whose CPU has FMA (x86-64 since 2013, ARM64).

Kernels are compiled without numba's runtime (NRT, numba's ``_nrt=False``): none allocates an
array (callers pass every array in, :func:`coincli.integrators.batch.unrecorded`), so arrays
passed between them carry no reference counts, and loading them needs no runtime. A kernel that
allocated would fail to compile, not misbehave.

The cache: numba checks only the timestamp of the file that defines a function, not of the
files whose kernels it calls, so an edit to a callee could leave stale machine code in use. Our
cache locator (used only for files of this package) stamps every entry with a hash of all kernel
sources and keeps it in ``~/.cache/coincli`` (or ``$NUMBA_CACHE_DIR/coincli``). The first
compilation of a version prunes there what no process can load any more (:func:`prune_cache`).
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import os
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


def kernel(fn=None, *, inline: bool = False):
    """Register ``fn`` as a kernel (see the module docstring); returns it unchanged.
    ``@kernel(inline=True)`` marks a small helper that numba inlines into every caller (no
    call, no array passing: the hot loops stay one function in the compiled code)."""
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


# About how long the first compilation takes on 2 cores, its two drivers compiling at once
# (coincli.integrators.batch.warm_up): 84 s measured on idle cores, 142 s beside other work (load
# 3 to 5; numba 0.60, a cold cache). The one figure every notice and document gives.
FIRST_COMPILE_SECONDS = 120


def _marker() -> Path:
    """The file that says these sources are compiled for this installation: numba's cache entries
    are keyed by the path of the source file, so a second checkout of the same version compiles
    afresh, and must say so as well."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        numba_version = version("numba")
    except PackageNotFoundError:
        numba_version = "unknown"
    place = hashlib.sha256(str(_PACKAGE).encode()).hexdigest()[:8]
    return cache_dir() / f"numba-{numba_version}" / f"compiled-{sources_digest()}-{place}"


def kernels_cached() -> bool:
    """Whether this machine has compiled this version of the kernels already (so that using
    them takes a second, not a minute): a marker written by :func:`mark_cached`."""
    return _marker().exists()


def mark_cached() -> None:
    """Record that the kernels of these sources are compiled and cached; the first time, prune
    what other sources left in the cache (:func:`prune_cache`)."""
    marker = _marker()
    first = not marker.exists()
    try:
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.touch()
    except OSError:
        return  # an unwritable cache only means the notice shows again
    if first:
        prune_cache()


SOURCE_RECORD = "source.txt"  # in each cache directory of ours: the source directory it serves


def prune_cache() -> None:
    """Remove from the cache what no process can load any more. numba keeps a directory of
    entries for each source directory, names an entry after its function's line, and finds an
    entry stale only when it reads it; so every upgrade or edit of the package left its machine
    code behind (3 MB a version), and so did every deleted checkout or environment. Removed: in
    this installation's directories, the entries stamped with other sources and the data files
    no current entry names; this installation's markers of other sources; and the directories
    of installations whose sources are gone (each directory records its source directory, now;
    directories from before are left alone). Never raises: a cache that cannot be pruned only
    takes room."""
    import numba

    root = cache_dir() / f"numba-{numba.__version__}"
    try:
        _prune(root, _cache_dirs(root), sources_digest(), numba.__version__, _marker())
    except (OSError, ImportError, AttributeError):
        pass


def _cache_subdir(py_file: str) -> str:
    """The name of the cache directory of the kernels of ``py_file``: the name of its directory
    and a hash of that directory's path, as numba names its own (the caches of earlier versions
    are where they were)."""
    source_dir = os.path.dirname(os.path.abspath(py_file))
    return f"{os.path.basename(source_dir)}_{hashlib.sha1(source_dir.encode()).hexdigest()}"


def _cache_dirs(root: Path) -> dict:
    """This installation's cache directories under ``root``, each with its source directory."""
    return {root / _cache_subdir(name): Path(name).parent
            for name in {inspect.getfile(fn) for fn in _KERNELS}}


def _prune(root: Path, ours: dict, stamp: str, version: str, marker: Path) -> None:
    """:func:`prune_cache` under ``root``: ``ours`` maps this installation's cache directories
    to their source directories, ``stamp`` is the digest of the sources, ``version`` numba's,
    ``marker`` the current marker."""
    import pickle
    import shutil

    for directory, source in ours.items():
        if not directory.is_dir():
            continue
        (directory / SOURCE_RECORD).write_text(str(source))
        data = set(directory.glob("*.nbc"))  # listed before the indexes are read: numba
        current = set()  # writes an index before the data file it names
        for index in directory.glob("*.nbi"):
            try:
                with open(index, "rb") as f:
                    header = pickle.load(f)
                    body = f.read()
                entry_stamp, entries = pickle.loads(body) if header == version else (None, {})
            except Exception:  # noqa: BLE001 - unreadable: numba passes it over, and so do we
                continue
            if entry_stamp == stamp:
                current |= {directory / name for name in entries.values()}
            else:
                index.unlink(missing_ok=True)
        for path in data - current:
            path.unlink(missing_ok=True)
    for directory in root.iterdir():
        record = directory / SOURCE_RECORD
        if directory not in ours and record.is_file() and not Path(record.read_text()).is_dir():
            shutil.rmtree(directory, ignore_errors=True)
    place = marker.name.rsplit("-", 1)[-1]
    for other in root.glob(f"compiled-*-{place}"):
        if other != marker:
            other.unlink(missing_ok=True)


def cache_dir() -> Path:
    base = os.environ.get("NUMBA_CACHE_DIR")
    if base:
        return Path(base) / "coincli"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "coincli"


def _import_kernel_modules() -> None:
    import importlib

    for module in KERNEL_MODULES:
        importlib.import_module(module)


@functools.cache  # the sources do not change under a running process; hashing them is 3 ms
def sources_digest() -> str:
    """Hash of every file that defines a kernel or a type the kernels use (every kernel module
    imported first, so that the set is whole whoever asks first)."""
    _import_kernel_modules()
    files = sorted({inspect.getfile(fn) for fn in _KERNELS}
                   | {str(_PACKAGE / name) for name in ("jit.py", "params.py", "enums.py")})
    digest = hashlib.sha256()
    for name in files:
        digest.update(Path(name).read_bytes())
    return digest.hexdigest()[:16]


def _activate() -> None:
    with _LOCK:
        if _DISPATCHERS:
            return
        import numba

        fast_load = loads_without_refresh()
        _import_kernel_modules()

        _install_locator(numba)
        dispatchers = {fn: numba.njit(cache=True, nogil=True, fastmath={"contract"}, _nrt=False,
                                      inline="always" if fn in _INLINE else "never")(fn)
                       for fn in _KERNELS}
        if fast_load:
            for dispatcher in dispatchers.values():
                _refresh_on_miss(dispatcher)
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


# numba versions (major, minor) on which the test suite has run with cached code loaded without
# the refresh: code loaded without what it needs would crash the process, not raise
LOADS_WITHOUT_REFRESH = {(0, 68)}


def loads_without_refresh() -> bool:
    """Whether this numba is one of LOADS_WITHOUT_REFRESH."""
    import numba

    return tuple(int(part) for part in numba.__version__.split(".")[:2]) in LOADS_WITHOUT_REFRESH


def _refresh_on_miss(dispatcher) -> None:
    """Have ``dispatcher`` load its machine code from the cache without first loading all of
    numba's compiler (its target context's ``refresh``: 0.2-0.3 s of imports, numba.np.arraymath
    among them), which only compiling needs: the cached code is complete and linked. Numba
    refreshes before every cache lookup; here the lookup comes first, and a miss refreshes before
    numba compiles. Nor is numba's runtime started for it (which compiles the runtime's own
    functions, 0.04 s): the kernels are compiled without it (see the module docstring). Only on
    the numba versions of LOADS_WITHOUT_REFRESH: on others what cached code needs loaded first
    may change, and numba's own way is safe."""
    cache = getattr(dispatcher, "_cache", None)
    if cache is None or not hasattr(cache, "_load_overload") or not hasattr(
            cache, "_guard_against_spurious_io_errors"):
        return  # another numba layout: its own behaviour

    def load_overload(sig, target_context):
        with cache._guard_against_spurious_io_errors():
            result = cache._load_overload(sig, target_context)
            if result is not None:
                return result
        target_context.refresh()
        return None

    cache.load_overload = load_overload


def _install_locator(numba) -> None:
    """Put a cache locator for this package's files in front of numba's own ones (numba has no
    public way to say where a function's cache goes: its locator classes are its own)."""
    try:
        from numba.core.caching import CacheImpl, _CacheLocator, _SourceFileBackedLocatorMixin
        locators = CacheImpl._locator_classes
    except (ImportError, AttributeError):  # another numba layout: numba's default caching
        return
    stamp = sources_digest()
    root = cache_dir() / f"numba-{numba.__version__}"

    class CoincliCacheLocator(_SourceFileBackedLocatorMixin, _CacheLocator):
        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._cache_path = str(root / _cache_subdir(py_file))

        def get_cache_path(self):
            return self._cache_path

        def get_source_stamp(self):
            return stamp

        @classmethod
        def from_function(cls, py_func, py_file):
            if not Path(py_file).resolve().is_relative_to(_PACKAGE):
                return None  # not ours: numba's own locators decide
            return super().from_function(py_func, py_file)

    locators.insert(0, CoincliCacheLocator)


__all__ = ["FIRST_COMPILE_SECONDS", "LOADS_WITHOUT_REFRESH", "cache_dir",
           "compiled", "derive", "is_active", "kernel", "kernels_cached", "loads_without_refresh",
           "mark_cached", "prune_cache", "python", "sources_digest"]
