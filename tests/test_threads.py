"""Thread safety as a notebook uses the library: one throw, a basin sweep, a store opened and the
heavy libraries imported, each on its own thread, all at once, in a fresh interpreter (first
imports are where threads can wait on each other), under a timeout: none may hang or fail."""

from __future__ import annotations

import subprocess
import sys

import pytest

import coincli

TRIALS = 3
TIMEOUT = 120  # seconds a trial may take: about 5 on 2 busy cores with the kernels cached

SCRIPT = r"""
import sys, threading, traceback
import coincli

store = sys.argv[1]
scene = coincli.load_preset("paper")
errors = []


def simulate():
    run = coincli.simulate(scene.with_overrides(vy=1.197, vphi=3.508))
    assert run.quarter_turns == 6, run.quarter_turns


def basin():
    ds = coincli.basin(scene, res=6, threads=2)
    assert ds.quarter_turns.shape == (6, 6)


def open_basin():
    assert coincli.open_basin(store).quarter_turns.shape == (4, 4)


def heavy_imports():
    import dask.distributed, matplotlib.figure, rerun, scipy.linalg, xarray, zarr  # noqa


def on_thread(work):
    def body():
        start.wait()
        try:
            work()
        except BaseException:
            errors.append(traceback.format_exc())
    return threading.Thread(target=body, name=work.__name__, daemon=True)


work = (simulate, basin, open_basin, heavy_imports)
start = threading.Barrier(len(work))
threads = [on_thread(w) for w in work]
for thread in threads:
    thread.start()
for thread in threads:
    thread.join(float(sys.argv[2]))
stuck = [thread.name for thread in threads if thread.is_alive()]
assert not stuck, f"still running: {stuck}"
assert not errors, "\n".join(errors)
print("all done")
"""


@pytest.fixture(scope="module")
def small_store(tmp_path_factory):
    store = tmp_path_factory.mktemp("threads") / "small.zarr"
    coincli.basin(coincli.load_preset("paper"), res=4, store=store)
    return store


@pytest.mark.parametrize("trial", range(TRIALS))
def test_simulate_basin_open_basin_and_imports_on_threads_at_once(small_store, trial):
    try:
        done = subprocess.run([sys.executable, "-c", SCRIPT, str(small_store), str(TIMEOUT)],
                              capture_output=True, text=True, timeout=TIMEOUT + 30)
    except subprocess.TimeoutExpired as exc:  # hung where the threads' join could not see it
        pytest.fail(f"trial {trial} hung: {exc.stderr}")
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.splitlines()[-1] == "all done"
