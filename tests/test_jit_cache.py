"""The kernel cache (coincli.jit): numba's own, in a folder keyed by the kernel sources; what
marking a compilation prunes, and what it leaves."""

import inspect
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from coincli import jit


@pytest.fixture
def empty_cache(tmp_path, monkeypatch):
    """coincli's cache in an empty temporary folder (jit.cache_dir follows NUMBA_CACHE_DIR)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba-cache"))
    return jit.cache_dir()


def test_the_cache_folder_is_this_installations_and_named_after_the_sources_and_numba(
        empty_cache):
    folder = jit.kernel_cache_dir()
    assert folder.parent == jit.installation_dir() and folder.parent.parent == empty_cache
    assert folder.name == f"{jit.sources_digest()}-numba-{jit.numba_version()}"


def test_an_edit_of_any_kernel_source_gives_another_cache_folder(tmp_path, monkeypatch):
    """The digest covers every file that defines a kernel (a callee's too: numba itself would
    check only the caller's file), and changes with any byte of any of them."""
    files = jit.source_files()
    for module in jit.KERNEL_MODULES:
        assert inspect.getfile(sys.modules[module]) in files, module
    copies = []
    for i, name in enumerate(files):
        copies.append(tmp_path / f"{i}-{Path(name).name}")
        shutil.copyfile(name, copies[-1])
    assert jit.digest_files(copies) == jit.sources_digest()
    seen = {jit.sources_digest()}
    for copy in copies:
        text = copy.read_bytes()
        copy.write_bytes(text.replace(b"\n", b"\n ", 1))
        seen.add(jit.digest_files(copies))
        copy.write_bytes(text)
    assert len(seen) == len(copies) + 1
    monkeypatch.setattr(jit, "sources_digest", lambda: "0123456789abcdef")
    assert jit.kernel_cache_dir().name.startswith("0123456789abcdef-")


def test_marking_prunes_other_digests_and_gone_installations(empty_cache, tmp_path):
    current = jit.kernel_cache_dir()
    (current / "model").mkdir(parents=True)
    (current / "model" / "kernel-10.py311.nbi").write_bytes(b"index")
    older = current.parent / f"0123456789abcdef-numba-{jit.numba_version()}"  # an edit ago
    (older / "model").mkdir(parents=True)
    other_numba = current.parent / f"{jit.sources_digest()}-numba-0.1.0"
    other_numba.mkdir()
    alive = empty_cache / "install-alive"  # another checkout, still there
    alive.mkdir()
    (alive / jit.INSTALLATION_RECORD).write_text(f"{tmp_path}\n{sys.prefix}\n")
    gone = empty_cache / "install-gone"  # an environment since deleted
    gone.mkdir()
    (gone / jit.INSTALLATION_RECORD).write_text(f"{tmp_path}\n{tmp_path / 'deleted-venv'}\n")
    unknown = empty_cache / "numba-0.68.1"  # not a folder of this layout: left alone
    unknown.mkdir()

    assert not jit.kernels_cached()
    jit.mark_cached()

    assert jit.kernels_cached()
    assert (current / "model" / "kernel-10.py311.nbi").read_bytes() == b"index"
    assert sorted(p.name for p in current.parent.iterdir()) == [current.name,
                                                                 jit.INSTALLATION_RECORD]
    assert sorted(p.name for p in empty_cache.iterdir()) == sorted(
        [current.parent.name, "install-alive", "numba-0.68.1"])


def test_only_the_first_marking_of_a_digest_prunes(empty_cache, monkeypatch):
    """mark_cached prunes when it writes the marker, not each time it is called again; and a
    cache that cannot be written is not pruned."""
    pruned = []
    monkeypatch.setattr(jit, "prune_cache", lambda: pruned.append(jit.kernels_cached()))
    jit.mark_cached()
    jit.mark_cached()
    assert pruned == [True]
    shutil.rmtree(empty_cache)
    empty_cache.parent.mkdir(parents=True, exist_ok=True)
    empty_cache.write_text("not a folder")
    jit.mark_cached()
    assert pruned == [True] and not jit.kernels_cached()


def test_pruning_an_empty_cache_does_nothing(empty_cache):
    jit.prune_cache()
    assert not empty_cache.exists()


def test_numba_caches_the_kernels_in_the_folder_and_keeps_its_own_setting(tmp_path):
    """In a fresh process that imported numba first (as in a notebook), with an empty cache:
    kernels_cached() is False; a kernel run compiled is cached by numba in kernel_cache_dir()
    (and a second process loads it from there), while numba's CACHE_DIR setting for other
    code is the user's still; after mark_cached() (what a whole compilation ends with)
    kernels_cached() is True."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "user-numba-cache")}
    code = """
import sys
import numba
import numpy as np
from coincli import jit
from coincli.models import PAPER, model_params
from coincli.params import Scene
first = sys.argv[1] == "first"
assert jit.kernels_cached() != first
assert not jit.is_built(PAPER)
energy = PAPER.kernels().total_energy
assert jit.is_built(PAPER) and not jit.is_built(PAPER, jit.PYTHON)
assert energy(model_params(Scene()), np.array([0.0, 0.01, 0.0, 0.0, 1.0, 3.0])) > 0
assert numba.config.CACHE_DIR == sys.argv[2], numba.config.CACHE_DIR
hits = sum(energy.stats.cache_hits.values())
assert Path(energy.stats.cache_path).is_relative_to(jit.kernel_cache_dir())
assert hits == (0 if first else 1), energy.stats
if first:
    jit.mark_cached()
    assert jit.kernels_cached()
""".replace("import sys", "import sys\nfrom pathlib import Path")
    for run in ("first", "second"):
        done = subprocess.run([sys.executable, "-c", code, run, env["NUMBA_CACHE_DIR"]],
                              env=env, capture_output=True, text=True)
        assert done.returncode == 0, done.stderr[-2000:]


def test_kernels_compiled_here_give_the_bits_the_cache_gives(tmp_path):
    """The same throws give the same bits in a process that compiled the kernels (the first
    command after installing, a notebook with an empty cache) as in one that loaded them from
    the cache: a store resumed by the one is the other's, byte for byte. numba 0.60 and 0.61
    miss this by a rounding of about one settle time in 300 (4,096 throws of the paper's
    coin: 12 and 15), hence numba >= 0.62. One full compilation, about 40 s."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    code = """
import hashlib
import coincli
from coincli.integrators.batch import run_ladder
from coincli.models import PAPER
from coincli.montecarlo import Draws, initial_states, make_sampling
from coincli.montecarlo.batch import make_fraction_spec
scene = coincli.load_preset("paper")
labeller = make_fraction_spec(scene)
sampling = make_sampling(scene, phi0="-pi:pi")
states = initial_states(scene, sampling, Draws(sampling).batch(0)[:4096])
out = labeller.label(states)
stats = PAPER.kernels()[run_ladder].stats
print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))
print(hashlib.sha256(b"".join(a.tobytes() for a in out)).hexdigest())
"""
    runs = []
    for _ in range(2):
        done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True)
        assert done.returncode == 0, done.stderr[-2000:]
        runs.append(done.stdout.split("\n"))
    (compiled_hits, compiled_misses), (loaded_hits, loaded_misses) = (
        map(int, run[0].split()) for run in runs)
    assert compiled_hits == 0 and compiled_misses > 0  # the first compiled
    assert loaded_hits > 0 and loaded_misses == 0  # the second loaded what it cached
    assert runs[0][1] == runs[1][1]


def test_the_suite_runs_on_compiled_and_marked_kernels():
    """conftest's pytest_configure compiled every kernel (or found them compiled) before any
    test ran, and marked it."""
    assert jit.kernels_cached()
