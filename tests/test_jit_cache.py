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


def test_the_cache_directories_pruned_are_where_numba_keeps_this_packages_kernels():
    """prune_cache looks where the compiled kernels are: every kernel's cache directory is one
    of _cache_dirs, with the directory of its source."""
    import numba

    from coincli import model

    dispatcher = jit.compiled(model.total_energy)
    root = jit.cache_dir() / f"numba-{numba.__version__}"
    ours = jit._cache_dirs(root)
    assert Path(dispatcher._cache._cache_path) in ours
    assert ours[Path(dispatcher._cache._cache_path)] == Path(model.__file__).parent
