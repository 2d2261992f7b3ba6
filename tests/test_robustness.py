"""Runs that cannot finish, starts that make no sense, and Ctrl-C: each is reported as such,
never turned into a label, and never hangs."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
from conftest import default_signals
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.enums import Certainty, Status
from coincli.params import ParameterError

COIN = [sys.executable, "-m", "coincli"]


def test_a_spin_no_step_can_follow_ends_on_its_budget():
    scene = coincli.load_preset("paper").with_overrides(vy=1.197, vphi=1e7)
    run = coincli.simulate(scene)
    assert run.status is Status.BUDGET and run.quarter_turns is None
    assert run.certainty is not Certainty.CERTAIN and len(run.rungs) == 1  # no climbing
    assert any("budget" in note for note in run.notes)
    result = CliRunner().invoke(app, ["simulate", "--vy", "1.197", "--vphi", "1e7", "--no-rrd"])
    assert result.exit_code == 1 and "step budget ran out" in result.output


def test_max_steps_bounds_a_run():
    scene = coincli.load_preset("paper").with_overrides(vy=1.197, vphi=3.508, max_steps=20,
                                                        verify=False)
    run = coincli.simulate(scene)
    assert run.status is Status.BUDGET and run.steps <= 20


def test_a_throw_that_never_lands_says_so_in_its_headline():
    # a fixed horizon: without one the cap grows with the throw (6e6 s here) and the step
    # budget ends it first (exit 1, no outcome)
    result = CliRunner().invoke(app, ["simulate", "--vy", "1e6", "--t-end", "2", "--no-rrd"])
    assert result.exit_code == 0
    headline = next(line for line in result.output.splitlines() if line.startswith("outcome"))
    assert "none by t_end" in headline and "lying" not in headline


@pytest.mark.parametrize("args", [["simulate", "--y0", "-1"], ["simulate", "--y0", "0.005",
                                                              "--phi0", "1.57"],
                                  ["basin", "x.zarr", "--y0", "-1:0", "--vy", "1"]])
def test_a_start_deep_in_the_foundation_is_refused(tmp_path, args):
    if args[0] == "basin":
        args = ["basin", str(tmp_path / "x.zarr"), *args[2:]]
    result = CliRunner().invoke(app, [*args, "--no-rrd"] if args[0] == "simulate" else args)
    assert result.exit_code == 2
    assert "deep in the foundation" in result.output and "0.308 mm" in result.output
    assert not (tmp_path / "x.zarr").exists()


def test_a_coin_resting_in_the_foundation_is_a_valid_start():
    scene = coincli.load_preset("paper")
    rest = scene.coin.r_t - scene.coin.mass * scene.g / (2 * scene.foundation.k)
    coincli.classify(scene.with_overrides(y0=rest))  # 1.5 um deep: fine
    with pytest.raises(ParameterError, match="deep in the foundation"):
        coincli.classify(scene.with_overrides(y0=scene.coin.r_t - 0.01))


def test_an_error_in_the_kernels_thread_reaches_the_caller():
    """What the worker thread of interruptible() raises is raised in the caller's thread, as
    itself (not as a missing result)."""
    from coincli.integrators import new_control
    from coincli.integrators.batch import interruptible

    def fails():
        raise ParameterError("from the kernel's thread")

    with pytest.raises(ParameterError, match="kernel's thread"):
        interruptible(fails, new_control())
    assert interruptible(lambda: 42, new_control()) == 42


def test_ctrl_c_stops_a_long_simulation_within_two_seconds(tmp_path):
    # compile (or load) the fixed-step kernels first, so that the SIGINT hits a running kernel
    subprocess.run([*COIN, "simulate", "--method", "symplectic_euler", "--t-end", "0.001",
                    "--single-pass", "--no-rrd"], check=True, capture_output=True, cwd=tmp_path)
    proc = subprocess.Popen([*COIN, "simulate", "--method", "symplectic_euler", "--dt", "1e-9",
                             "--t-end", "100", "--full", "--single-pass", "--no-rrd"],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=default_signals)
    time.sleep(3.0)
    assert proc.poll() is None, proc.communicate()
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=10)
    assert time.monotonic() - sent < 2.0
    assert proc.returncode == 130, (out, err)
    assert "interrupted" in err and "Traceback" not in err
    assert "up to 100,000,000,000 steps" in err  # announced before it started
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("args", [
    ("accuracy", "--res", "16", "-o", "a.png"),  # its references run for a minute
    ("bench", "--basin-res", "0"),  # its timing runs the paper's setting on the main thread
])
def test_ctrl_c_stops_accuracy_and_bench_within_two_seconds(tmp_path, args):
    """The kernels of the long measurements poll a control flag that Ctrl-C sets."""
    proc = subprocess.Popen([*COIN, *args], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=default_signals)
    time.sleep(8.0)
    assert proc.poll() is None, proc.communicate()
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert time.monotonic() - sent < 2.0, (out, err)
    assert proc.returncode == 130, (out, err)
    assert "Traceback" not in err
    assert not list(tmp_path.glob("a.*"))  # no chart, no table
