"""The kernel cache (coincli.jit): what a first compilation prunes, and what it leaves."""

import pickle
from pathlib import Path

from coincli import jit

VERSION = "0.68.1"


def write_index(path: Path, stamp: str, data_names, version: str = VERSION) -> None:
    """An index file as numba writes one: its version, then (stamp, {key: data file name})."""
    with open(path, "wb") as f:
        pickle.dump(version, f, protocol=-1)
        f.write(pickle.dumps((stamp, {f"key{i}": name for i, name in enumerate(data_names)})))


def test_a_first_compilation_prunes_what_no_process_can_load(tmp_path):
    root = tmp_path / "numba-0.68.1"
    source = tmp_path / "site-packages" / "coincli"
    source.mkdir(parents=True)
    ours = root / "coincli_0123"
    ours.mkdir(parents=True)
    write_index(ours / "kernel-10.py311.nbi", "new", ["kernel-10.py311.1.nbc"])
    write_index(ours / "kernel-12.py311.nbi", "old", ["kernel-12.py311.1.nbc"])  # an edit ago
    write_index(ours / "other-5.py311.nbi", "new", [], version="0.60.0")
    (ours / "broken-7.py311.nbi").write_bytes(b"not a pickle")
    for name in ("kernel-10.py311.1.nbc", "kernel-10.py311.2.nbc", "kernel-12.py311.1.nbc"):
        (ours / name).write_bytes(b"machine code")
    gone = root / "coincli_4567"  # an installation since deleted
    gone.mkdir()
    (gone / jit.SOURCE_RECORD).write_text(str(tmp_path / "deleted-venv" / "coincli"))
    (gone / "kernel-10.py311.1.nbc").write_bytes(b"machine code")
    alive = root / "coincli_89ab"  # another checkout, still there
    alive.mkdir()
    (alive / jit.SOURCE_RECORD).write_text(str(source))
    (alive / "kernel-10.py311.1.nbc").write_bytes(b"machine code")
    legacy = root / "integrators_cdef"  # from before directories recorded their sources
    legacy.mkdir()
    (legacy / "kernel-10.py311.1.nbc").write_bytes(b"machine code")
    marker = root / "compiled-new-aaaa"
    for name in ("compiled-new-aaaa", "compiled-old-aaaa", "compiled-old-bbbb"):
        (root / name).touch()

    jit._prune(root, {ours: source}, "new", VERSION, marker)

    assert sorted(path.name for path in ours.iterdir()) == [
        "broken-7.py311.nbi", "kernel-10.py311.1.nbc", "kernel-10.py311.nbi", jit.SOURCE_RECORD]
    assert (ours / jit.SOURCE_RECORD).read_text() == str(source)
    assert not gone.exists() and alive.is_dir() and legacy.is_dir()
    assert sorted(path.name for path in root.glob("compiled-*")) == [
        "compiled-new-aaaa", "compiled-old-bbbb"]


def test_pruning_an_empty_cache_does_nothing(tmp_path):
    root = tmp_path / "numba-0.68.1"
    root.mkdir()
    jit._prune(root, {root / "coincli_0123": tmp_path}, "new", VERSION, root / "compiled-new-a")
    assert list(root.iterdir()) == []


def test_only_the_first_marking_of_a_version_prunes(tmp_path, monkeypatch):
    """mark_cached prunes when it writes this version's marker, not each time it is called
    again; and a cache that cannot be written is not pruned."""
    marker = tmp_path / "numba-0.68.1" / "compiled-new-aaaa"
    pruned = []
    monkeypatch.setattr(jit, "_marker", lambda: marker)
    monkeypatch.setattr(jit, "prune_cache", lambda: pruned.append(marker.exists()))
    jit.mark_cached()
    jit.mark_cached()
    assert marker.exists() and pruned == [True]
    monkeypatch.setattr(jit, "_marker", lambda: tmp_path / "a-file" / "compiled-new-aaaa")
    (tmp_path / "a-file").write_text("not a directory")
    jit.mark_cached()
    assert pruned == [True]


def test_the_cache_directories_pruned_are_where_numba_keeps_this_packages_kernels(paper):
    """prune_cache looks where the compiled kernels are: a kernel run compiled (or loaded) leaves
    its index in the cache directory that _cache_dirs gives for its source directory. numba
    finds that directory through our cache locator (jit._install_locator)."""
    import numba
    import numpy as np

    from coincli import model
    from coincli.params import model_params

    state = np.array([0.0, 0.01, 0.0, 0.0, 1.0, 3.0])
    assert jit.compiled(model.total_energy)(model_params(paper), state) > 0
    ours = jit._cache_dirs(jit.cache_dir() / f"numba-{numba.__version__}")
    (directory,) = [d for d, source in ours.items() if source == Path(model.__file__).parent]
    assert list(directory.glob("model.total_energy-*.nbi")), sorted(directory.iterdir())


def test_pruning_never_raises_on_a_numba_it_does_not_know(monkeypatch):
    """A numba whose internals differ (here: the cache directories cannot be found) leaves its
    cache unpruned; the compilation that asked for the pruning goes on."""
    def unknown_layout(root):
        raise ImportError("cannot import name '_CacheLocator' from 'numba.core.caching'")

    monkeypatch.setattr(jit, "_cache_dirs", unknown_layout)
    jit.prune_cache()


def test_a_numba_without_our_hooks_keeps_its_own_caching_and_loading(monkeypatch):
    """Where numba's cache locators or its dispatcher's cache are not as we expect, the kernels
    are cached and loaded as numba does it by itself; and only the numba versions the suite
    has run on load cached code without numba's refresh."""
    import types

    import numba
    import numba.core.caching as caching

    before = list(caching.CacheImpl._locator_classes)
    monkeypatch.delattr(caching, "_CacheLocator")
    jit._install_locator(numba)
    assert caching.CacheImpl._locator_classes == before
    other = types.SimpleNamespace(_cache=types.SimpleNamespace(load_overload=len))
    jit._refresh_on_miss(other)
    assert other._cache.load_overload is len
    monkeypatch.setattr(numba, "__version__", "0.99.0")
    assert not jit.loads_without_refresh()
