"""Shared fixtures: the shipped scenes, and one call of the compiled kernel through its
contract (the model's parameters and RunSettings in, a RunResult and the final state out)."""

from __future__ import annotations

import contextlib
import io
import os
import signal
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest

from coincli.enums import Method
from coincli.integrators import new_control
from coincli.integrators.batch import integrate
from coincli.integrators.common import EVENT_COLUMNS, SAMPLE_COLUMNS, RunResult
from coincli.models import PAPER, model_params
from coincli.params import RunSettings
from coincli.presets import load


def pytest_configure(config):
    """Compile the kernels of every model once, here, before pytest-xdist starts its workers,
    which on a cold cache would each compile all of them at the same time (each a minute or
    more of one core and half a gigabyte of memory).

    And first, before any test module imports it, the command line: its consoles
    (coincli.cli.common) are created then, as they would be with the output piped (no
    terminal, so no colour codes, whatever terminal the suite runs in: rich decides a console's
    colours once, when it is made) and with no COLUMNS in the environment (so that they read
    the width at every print, and the width the tests give, :func:`terminal_width` or a test's
    own env={"COLUMNS": ...}, is the one they print at)."""
    for name in ("COLUMNS", "LINES"):
        os.environ.pop(name, None)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        import coincli.cli  # noqa: F401
    if hasattr(config, "workerinput"):
        return  # a worker: the controller has compiled them
    from coincli.jit import kernels_cached
    from coincli.labeller import Labeller
    from coincli.models import MODELS

    paper = load("paper").scene
    # a run of chosen files compiles the other models' kernels only for their tests (the files
    # named after them: test_friction*.py), a run of a folder (the suite) every model's
    models = [m for m in MODELS.values() if m is MODELS["paper"] or not config.args
              or any(Path(arg.split("::")[0]).is_dir() or m.name in Path(arg).name
                     for arg in config.args)]
    for model in models:
        if not kernels_cached(model.name):
            scene = paper.with_overrides(**dict(model.example))
            Labeller.of(scene).compile_all(np.array([0.0, scene.y0, 0.0, 0.0, 1.0, 3.0]))


TEST_COLUMNS = "80"  # the width every command prints at in the tests, as CI has it


@pytest.fixture(autouse=True)
def terminal_width(monkeypatch):
    """Every command a test runs (in this process or as a child) prints for TEST_COLUMNS
    columns, whatever the terminal the suite runs in: tables laid out alike everywhere.
    Paragraphs are never broken when the output is no terminal (coincli.cli.text.say), so
    that a long temporary path changes no line a test reads."""
    monkeypatch.setenv("COLUMNS", TEST_COLUMNS)
    monkeypatch.delenv("LINES", raising=False)


# The scenes of the integrator and model tests run a single pass (verify=False): they test one
# method at one setting. Verification itself is tested on the presets as shipped.
@pytest.fixture(scope="session")
def paper():
    return load("paper").scene.with_overrides(verify=False)


@pytest.fixture(scope="session")
def undamped():
    return load("undamped").scene.with_overrides(verify=False)


@pytest.fixture(scope="session")
def thick():
    return load("thick").scene.with_overrides(verify=False)


class KernelRun(NamedTuple):
    result: RunResult
    final: np.ndarray
    samples: np.ndarray
    events: np.ndarray


def run_kernel(scene, state, *, method: Method | str, t_end: float, dt: float = 1e-6,
               rtol: float = 1e-7, stop_on_settle: bool = False, sample_dt: float = 0.0,
               max_samples: int = 0, max_events: int = 0) -> KernelRun:
    """One compiled run from ``state`` (samples and events cut to what was recorded)."""
    settings = RunSettings(method=int(Method.parse(method)), dt=dt, rtol=rtol, t_end=t_end,
                           stop_on_settle=stop_on_settle, max_steps=10**9, sample_dt=sample_dt)  # noqa: E501
    final = np.empty(6)
    samples = np.empty((max_samples, SAMPLE_COLUMNS))
    events = np.empty((max_events, EVENT_COLUMNS))
    result = PAPER.kernels()[integrate](model_params(scene), settings,
                                        np.ascontiguousarray(state, dtype=np.float64), samples,
                                        events, final, new_control())
    return KernelRun(result, final, samples[:result.n_samples], events[:result.n_events])


def local_cluster(n_workers: int):
    """An in-process Dask cluster for a test: no dashboard, and the scheduler's HTTP server on a
    free port rather than 8787, which the other test process's cluster may hold (distributed
    warns then), as coin's own local clusters do (coincli.engines.executors.open_dask)."""
    from distributed import LocalCluster

    return LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=False,
                        dashboard_address=None,
                        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})


def default_signals():
    """Popen's preexec_fn for a child that must take Ctrl-C and a hang-up as a `coin` started at
    a terminal does: a signal ignored by the test runner is ignored by every child it starts,
    and the runner may be started so (a non-interactive shell's background job ignores SIGINT,
    ``nohup make test`` SIGHUP; CI runs the suite so, .ci/run). The runner itself keeps them
    as it was given them."""
    for signum in (signal.SIGINT, signal.SIGHUP):
        signal.signal(signum, signal.SIG_DFL)


def store_files(path) -> dict[str, bytes]:
    """Every file of a store by its path inside it, but those of its records folder
    (NAME.zarr/.coin/: its runs, its tiles' costs, its claims), which differ from run to run:
    what is byte-identical however the store was computed (its arrays and metadata)."""
    from pathlib import Path

    from coincli.stores.basin_layout import RECORDS

    path = Path(path)
    return {f.relative_to(path).as_posix(): f.read_bytes() for f in sorted(path.rglob("*"))
            if f.is_file() and f.relative_to(path).parts[0] != RECORDS}


@contextlib.contextmanager
def sigint_raises():
    """SIGINT raises KeyboardInterrupt in this process for the block, as at an interactive
    prompt, whatever the test runner inherited."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.fixture
def strict_rerun():
    """Rerun logging mistakes raise instead of warning (for the recording tests)."""
    import rerun as rr

    before = rr.strict_mode()
    rr.set_strict_mode(True)
    yield
    rr.set_strict_mode(before)


def outputs_in_a_kernel(source: str, folder) -> list:
    """The outputs of one code cell ``source`` executed by a real Jupyter kernel in ``folder``
    (skips without rerun-notebook, nbformat or nbclient)."""
    pytest.importorskip("rerun_notebook")
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(source)]
    nbclient.NotebookClient(notebook, timeout=120, kernel_name="python3",
                            resources={"metadata": {"path": str(folder)}}).execute()
    return notebook.cells[0].outputs


def shows_a_widget(outputs: list) -> bool:
    """Whether cell ``outputs`` have no error and display a widget (Rerun's viewer)."""
    return (not [o for o in outputs if o["output_type"] == "error"]
            and any("application/vnd.jupyter.widget-view+json" in o.get("data", {})
                    for o in outputs))
