"""Extreme and malformed input (issue 28, items 7-9): a throw too large to integrate ends with
status non-finite, never a math domain error nor a false ``unsettled``; numbers are ASCII and a
bad value is quoted short; each rung of a fixed-step ladder has the budget of its own step;
``--spawn`` without a display still prints the outcome and writes the file asked for."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from coincli import simulate
from coincli.cli import app, run
from coincli.enums import Engine, Method, Status
from coincli.grid import compute_tile, make_grid, make_spec, parse_pair, parse_range
from coincli.integrators import new_control
from coincli.integrators.batch import integrate
from coincli.integrators.common import EVENT_COLUMNS, SAMPLE_COLUMNS
from coincli.integrators.ladder import ladder_of
from coincli.integrators.registry import ADAPTIVE_MAX_STEPS, run_settings
from coincli.labeller import Labeller
from coincli.models import PAPER, model_params
from coincli.models.rotation import rotate
from coincli.params import Integration, ParameterError, parse_number, shown
from coincli.presets import load

REPO = Path(__file__).resolve().parent.parent
runner = CliRunner()


@pytest.fixture(autouse=True)
def in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # simulate writes coin.rrd by default
    return tmp_path


def coin(*args):
    return runner.invoke(app, [str(a) for a in args])


def one_error_line(capsys, *args) -> str:
    """The command line as `coin` runs it (click's usage errors made one line too): exit 2,
    nothing on stdout, one `error:` line on stderr."""
    code = run([str(a) for a in args])
    out, err = capsys.readouterr()
    assert code == 2 and out == "", (code, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    return lines[0]


# -- item 7: a state too large to integrate ---------------------------------------------------
@pytest.mark.parametrize("option, value", [("--vphi", "1e308"), ("--vphi", "1e160"),
                                           ("--vx", "1e308"), ("--vy", "-1e300"),
                                           ("--phi0", "1e20")])
def test_a_throw_too_large_to_integrate_is_non_finite_not_a_traceback(option, value):
    """Was `ValueError: math domain error` in rotate (the plain-Python engine)."""
    args = ["simulate", "--vy", "1", option, value, "--no-rrd"]
    result = coin(*args)
    assert result.exit_code == 1, (result.stdout, result.stderr, result.exception)
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert "none: the run went non-finite" in result.stdout
    assert "initial state is beyond what can be integrated" in result.stdout
    assert "Traceback" not in result.stdout + result.stderr
    assert "Warning" not in result.stderr  # no numpy overflow warning either
    data = json.loads(coin(*args, "--json").stdout)
    assert data["status"] == "non-finite" and data["quarter_turns"] is None
    assert len(data["rungs"]) == 1  # no finer setting can start it: the ladder stops


def test_a_non_finite_throw_still_writes_its_recording(in_tmp):
    result = coin("simulate", "--vy", "1", "--vphi", "1e308", "--rrd", "big.rrd")
    assert result.exit_code == 1, (result.stdout, result.stderr, result.exception)
    assert "non-finite" in result.stdout and (in_tmp / "big.rrd").stat().st_size > 0


@pytest.mark.parametrize("method", ["event", "dopri5", "event_dop853", "symplectic_euler",
                                    "rk4"])
def test_both_engines_say_non_finite(method):
    """Compiled and plain-Python kernels agree: status non-finite at t = 0, no step, the state
    left as it was; no math domain error in Python."""
    scene = load("paper").scene
    p = model_params(scene)
    settings = run_settings(scene.integration)._replace(method=int(Method.parse(method)))
    for state in ([0.0, scene.y0, 0.0, 0.0, 1.0, 1e308], [0.0, scene.y0, 0.0, 1e308, 1.0, 0.0],
                  [0.0, scene.y0, 1e300, 0.0, 1.0, 3.0], [0.0, scene.y0, 0.0, 0.0, 1.0, 1e160],
                  [0.0, scene.y0, 1e16, 0.0, 1.0, 3.0]):  # past ANGLE_BOUND: no count
        state = np.array(state)
        for engine in (PAPER.kernels(), PAPER.kernels("python")):
            final = np.empty(6)
            result = engine[integrate](p, settings, state, np.empty((0, SAMPLE_COLUMNS)),
                                       np.empty((0, EVENT_COLUMNS)), final, new_control())
            assert result.status == Status.NONFINITE, (method, engine, state)
            assert result.t == 0.0 and result.steps == 0
            assert np.array_equal(final, state)
    for engine in (Engine.PYTHON, Engine.NUMBA):
        run = simulate(scene.with_overrides(vy=1.0, vphi=1e308), engine=engine)
        assert run.status == Status.NONFINITE and run.quarter_turns is None


def test_rotate_by_an_infinite_angle_is_nan_not_an_error():
    assert all(math.isnan(v) for v in rotate(1.0, 0.0, math.inf))
    assert all(math.isnan(v) for v in rotate(1.0, 0.0, math.nan))
    assert rotate(1.0, 0.0, 2.0) == pytest.approx((math.cos(2.0), math.sin(2.0)), abs=1e-16)


def test_a_basin_over_absurd_spins_labels_them_non_finite_not_unsettled():
    """`coin basin --vphi -1e308:1e308` labelled every cell unsettled after a microsecond (a
    closed-form flight with an infinite angle ended at t_end as if it had landed). That range
    is now refused (its cells' centres would be NaN); one half as wide has finite cells."""
    with pytest.raises(ParameterError, match="too wide"):
        parse_range("vphi", "-1e308:1e308")
    scene = load("paper").scene.with_overrides(vy=1.0)
    ranges = {"vy": (0.5, 1.0), "vphi": parse_range("vphi", "-8e307:8e307")}
    grid = make_grid(scene, ranges, (2, 3), (2, 3))
    tile = compute_tile(make_spec(scene, grid), (0, 0))
    status = tile.arrays["status"]
    ends = status[:, [0, 2]]  # vphi = -1e308 and +1e308
    assert (ends == Status.NONFINITE).all(), status
    assert (status[:, 1] == Status.SETTLED).all(), status  # vphi = 0: an ordinary throw
    assert (tile.arrays["rung"][:, [0, 2]] == 0).all()  # no finer rung tried


def test_the_basin_command_on_absurd_spins(in_tmp, capsys):
    line = one_error_line(capsys, "basin", "sweep", "big.zarr", "--vphi=-1e308:1e308",
                          "--res", "2x3")
    assert "too wide" in line and not (in_tmp / "big.zarr").exists()
    result = coin("basin", "sweep", "big.zarr", "--vphi=-8e307:8e307", "--vy", "0.5:1",
                  "--res", "2x3", "--chunk", "2x3")
    assert result.exit_code == 0, (result.stdout, result.stderr, result.exception)
    stats = coin("basin", "stats", "big.zarr", "--json")
    assert stats.exit_code == 0, (stats.stdout, stats.stderr)
    status = json.loads(stats.stdout)["status"]
    assert status["non-finite"] == 4 and status["settled"] == 2 and status["unsettled"] == 0


# -- item 7: parsing ---------------------------------------------------------------------------
@pytest.mark.parametrize("args", [
    ["simulate", "--vy", "١.٥", "--no-rrd"],
    ["simulate", "--vy", "١٫٥", "--no-rrd"],
    ["simulate", "--vphi", "٣", "--no-rrd"],
    ["simulate", "--max-steps", "١٢", "--no-rrd"],
    ["simulate", "--log-every", "٠.٠١", "--no-rrd"],
    ["basin", "sweep", "s.zarr", "--vphi", "١:٢"],
    ["basin", "sweep", "s.zarr", "--vy", "۱.۵"],  # Extended Arabic-Indic (Persian) digits
    ["basin", "sweep", "s.zarr", "--res", "١٢"],
])
def test_numbers_in_other_scripts_are_refused(args, in_tmp, capsys):
    line = one_error_line(capsys, *args)
    assert "ASCII" in line, line
    assert not (in_tmp / "s.zarr").exists()


def test_parse_number_reads_ascii_only():
    assert parse_number(" 1.5 ") == 1.5 and parse_number("-2e-3") == -2e-3
    for text in ("١.٥", "１.５", "1.5\u00a0", "abc", "inf", "nan", "1e999", ""):
        with pytest.raises(ParameterError):
            parse_number(text)
    assert parse_pair("res", "12x16") == (12, 16)
    with pytest.raises(ParameterError, match="ASCII"):
        parse_pair("res", "١٢")


@pytest.mark.parametrize("args", [
    ["simulate", "--vy", "x" * 100_000, "--no-rrd"],
    ["simulate", "--vy", "7" * 100_000, "--no-rrd"],
    ["simulate", "--max-steps", "x" * 100_000, "--no-rrd"],
    ["basin", "sweep", "s.zarr", "--vphi", "x" * 100_000],
    ["basin", "sweep", "s.zarr", "--vphi", "1:" + "x" * 100_000],
    ["basin", "sweep", "s.zarr", "--res", "9" * 100_000],
    ["basin", "sweep", "s.zarr", "--threads", "x" * 100_000],  # click's own message, clipped
])
def test_a_huge_bad_value_is_quoted_short(args, capsys):
    line = one_error_line(capsys, *args)
    assert len(line) < 400, len(line)
    assert "..." in line or line == "error: vy must be finite, got inf"  # 7777...: a float


def test_shown_cuts_long_values_only():
    assert shown("abc") == "abc" and shown("x" * 43) == "x" * 43
    assert shown("x" * 100) == "x" * 40 + "..."


# -- item 8: each rung's budget follows its own step -------------------------------------------
def test_fixed_step_rungs_get_the_budget_of_their_own_step():
    ladder = ladder_of(Integration(method="symplectic_euler", dt=1e-4, t_end=2.0))
    assert ladder.dts == pytest.approx((1e-4, 1e-5, 1e-6))
    assert ladder.budgets == (20_000, 200_000, 2_000_000)
    rk4 = ladder_of(Integration(method="rk4", dt=1e-4, t_end=2.0))
    assert rk4.budgets == tuple(math.ceil(2.0 / dt - 1e-9) for dt in rk4.dts)
    capped = ladder_of(Integration(method="verlet", dt=1e-4, t_end=2.0, max_steps=1000))
    assert capped.budgets == (1000, math.ceil(1000 * 10 ** 0.5 - 1e-9), 10_000)
    # adaptive ladders keep one budget for every rung, as before
    event = ladder_of(Integration())
    assert set(event.budgets) == {ADAPTIVE_MAX_STEPS} and len(event.budgets) == len(event)
    assert set(ladder_of(Integration(max_steps=77)).budgets) == {77}
    assert "max_steps" in ladder.to_dict()["rungs"][1]


def test_the_papers_method_at_its_coarse_step_gets_an_outcome():
    """`--method symplectic_euler --dt 1e-4` ran out of budget at t = 0.2 s on its second rung
    (dt = 1e-5 with the 20,000 steps of dt = 1e-4). The fig. 2 throw settles: the model as
    stated lies after six quarter turns (README, docs/model.md section 10)."""
    result = coin("simulate", "--vy", "1.197", "--vphi", "3.508", "--method",
                  "symplectic_euler", "--dt", "1e-4", "--no-rrd", "--json")
    assert result.exit_code == 0, (result.stdout, result.stderr)
    data = json.loads(result.stdout)
    assert data["status"] == "settled" and data["quarter_turns"] is not None
    assert all(r["status"] != "budget" for r in data["rungs"]), data["rungs"]
    assert len(data["rungs"]) >= 2


def test_the_sweep_ladder_gives_each_rung_its_budget():
    """The compiled ladder (basin, fractions, accuracy) as simulate's."""
    scene = load("paper").scene.with_overrides(method="symplectic_euler", dt=1e-4)
    states = np.array([[0.0, scene.y0, 0.0, 0.0, 1.197, 3.508]])
    out = Labeller.of(scene).label(states)
    assert out.status[0] == Status.SETTLED and out.rung[0] >= 1
    assert out.steps[0] > 20_000  # the second rung took more steps than the first's budget


# -- item 9: --spawn without a display ---------------------------------------------------------
def test_spawn_without_a_display_prints_the_outcome_and_writes_the_file(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    start = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "coincli", "simulate", "--vy", "1.197",
                           "--vphi", "3.508", "--spawn", "--rrd", "throw.rrd"],
                          capture_output=True, text=True, cwd=tmp_path, env=env, timeout=60)
    seconds = time.monotonic() - start
    if sys.platform == "darwin" or sys.platform.startswith("win"):
        pytest.skip("macOS and Windows always have a display")
    assert seconds < 10, seconds
    assert proc.returncode == 1, (proc.stdout, proc.stderr)
    assert "outcome" in proc.stdout and "n = 6" in proc.stdout
    assert "throw.rrd" in proc.stdout  # the recording line
    assert (tmp_path / "throw.rrd").stat().st_size > 0
    warning = [line for line in proc.stderr.splitlines() if "display" in line]
    assert len(warning) == 1 and "--spawn" in warning[0] and "--connect" in warning[0]
    assert "Traceback" not in proc.stderr and "could not write" not in proc.stderr


def test_spawn_without_a_display_or_a_file_suggests_rrd(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    result = coin("simulate", "--vy", "1.197", "--vphi", "3.508", "--spawn", "--no-rrd")
    assert result.exit_code == 1, (result.stdout, result.stderr, result.exception)
    assert "n = 6" in result.stdout
    assert "--rrd FILE" in result.stderr and not list(tmp_path.iterdir())


def test_write_recording_refuses_to_spawn_without_a_display(monkeypatch):
    from coincli.recordings.rrd import write_recording

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    run = simulate(load("paper").scene.with_overrides(vy=1.0, vphi=3.0), sample_dt=0.01,
                   record_events=True)
    start = time.monotonic()
    with pytest.raises(RuntimeError, match="no display"):
        write_recording(run, spawn=True)
    assert time.monotonic() - start < 1


def test_a_recording_that_fails_after_the_run_comes_after_the_outcome(monkeypatch, capsys):
    """A disk that fills while the recording is written: the outcome is printed all the same,
    then one error line, exit 2."""
    import errno

    import coincli.recordings.rrd

    def full_disk(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", "coin.rrd")

    monkeypatch.setattr(coincli.recordings.rrd, "write_recording", full_disk)
    code = run(["simulate", "--vy", "1.197", "--vphi", "3.508"])
    out, err = capsys.readouterr()
    assert code == 2 and "n = 6" in out, (code, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: could not write the recording")


# -- API errors in API words, the same errors on the command line in option names --------------

PAPER_SCENE = load("paper").scene
API_AND_CLI_WORDS = [
    # (the API call, what its message says, the command line, what the CLI's says)
    (lambda api: api.plan_sweep(PAPER_SCENE, res=1), "res must be at least 2",
     ["basin", "s.zarr", "--res", "1"], "--res must be at least 2"),
    (lambda api: api.plan_sweep(PAPER_SCENE, chunk="2x"), "chunk: '2x' is not N or NxM",
     ["basin", "s.zarr", "--chunk", "2x"], "--chunk: '2x' is not N or NxM"),
    (lambda api: api.plan_sweep(PAPER_SCENE, vy="2:1"), "vy 2:1: empty range",
     ["basin", "s.zarr", "--vy", "2:1"], "--vy 2:1: empty range"),
    (lambda api: api.plan_sweep(PAPER_SCENE, vy=1.0, vphi=2.0),
     "vy and vphi sweep by default: fix one with a plain value (e.g. vy=1.0)",
     ["basin", "s.zarr", "--vy", "1", "--vphi", "2"],
     "--vy and --vphi sweep by default: fix one with a plain value (e.g. --vy=1.0)"),
    (lambda api: api.plan_fractions(PAPER_SCENE, seed=-1), "seed must be a whole number >= 0",
     ["fractions", "--seed", "-1"], "--seed must be a whole number >= 0"),
    (lambda api: api.plan_fractions(PAPER_SCENE, samples=100, precision=0.01),
     "give samples (a fixed count) or precision (stop",
     ["fractions", "--samples", "100", "--precision", "0.01"],
     "give --samples (a fixed count) or --precision (stop"),
    (lambda api: api.plan_fractions(PAPER_SCENE, max_samples=0),
     "max_samples must be a whole number of at least 1",
     ["fractions", "--max-samples", "0"], "--max-samples must be a whole number of at least 1"),
    (lambda api: api.plan_fractions(PAPER_SCENE, of="most"), "of must be all or standing",
     ["fractions", "--of", "most"], "--of must be all or standing"),
    (lambda api: api.plan_fractions(PAPER_SCENE, over="colour=1:2:3"),
     "over colour: not a physical parameter",
     ["fractions", "--over", "colour=1:2:3"], "--over colour: not a physical parameter"),
    (lambda api: api.plan_fractions(PAPER_SCENE, phi0="2r"), "multiples of r are for y0 only",
     ["fractions", "--phi0", "2r"], "--phi0: '2r': multiples of r are for --y0 only"),
    (lambda api: api.fractions(PAPER_SCENE, samples=100, threads=0),
     "threads must be a whole number >= 1", ["fractions", "--samples", "100", "--threads", "0"],
     "--threads must be a whole number >= 1"),
    (lambda api: api.fractions(PAPER_SCENE, samples=100, workers=2, scheduler="tcp://h:1"),
     "give workers (a local cluster) or scheduler (an existing one)",
     ["fractions", "--samples", "100", "--workers", "2", "--scheduler", "tcp://h:1"],
     "give --workers (a local cluster) or --scheduler (an existing one)"),
    (lambda api: api.simulate(PAPER_SCENE.with_overrides(method="rk4", t_end=1e9, dt=1e-9)),
     "t_end / dt is 1e+18 steps", ["simulate", "--method", "rk4", "--t-end", "1e9", "--dt",
                                   "1e-9", "--no-rrd"], "--t-end / --dt is 1e+18 steps"),
]


@pytest.mark.parametrize("call,api_words,args,cli_words", API_AND_CLI_WORDS,
                         ids=[case[3].split()[0] for case in API_AND_CLI_WORDS])
def test_api_errors_name_parameters_and_the_cli_names_options(call, api_words, args,
                                                              cli_words, tmp_path,
                                                              monkeypatch):
    import coincli

    with pytest.raises(ParameterError) as caught:
        call(coincli)
    message = str(caught.value)
    assert api_words in message, message
    assert "--" not in message, message  # no option of the command line in the API's words
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, (result.stdout, result.stderr)
    assert result.stderr.startswith("error: ") and cli_words in result.stderr, result.stderr


def test_a_parameter_named_in_a_preset_file_stays_a_parameter(tmp_path, monkeypatch):
    """The CLI names an option only for what the message says is one of the command's: a preset
    file's bad value keeps its key's name."""
    preset = tmp_path / "bad.toml"
    preset.write_text('[integration]\nt_end = 1e9\ndt = 1e-9\nmethod = "rk4"\n')
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["simulate", "--preset", str(preset), "--no-rrd"])
    assert result.exit_code == 2, (result.stdout, result.stderr)
    # simulate has --t-end and --dt, but the file said t_end and dt
    assert result.stderr.startswith("error: preset file"), result.stderr
    assert "t_end / dt is" in result.stderr and "--" not in result.stderr, result.stderr


# -- issue 48: tracebacks of 0.10.0 -------------------------------------------------------------
@pytest.mark.parametrize("args, words", [
    (["fractions", "--phi0", "pi/2:pi/0", "--samples", "100"], "--phi0: 'pi/0' divides by zero"),
    (["fractions", "--phi0", "-pi/0:pi", "--samples", "100"], "--phi0: '-pi/0' divides by zero"),
    (["basin", "S.zarr", "--vphi", "-pi/0:pi"], "--vphi: '-pi/0' divides by zero"),
    (["simulate", "--y0", "r/0", "--no-rrd"], "'r/0' divides by zero"),
    (["simulate", "--y0", "r/1e-400", "--no-rrd"], "'r/1e-400' divides by zero"),
    (["fractions", "--vphi", "normal(pi/0,1)", "--samples", "100"], "divides by zero"),
])
def test_a_division_by_zero_in_a_value_is_one_line(args, words, in_tmp, capsys):
    line = one_error_line(capsys, *args)
    assert words in line, line
    assert not (in_tmp / "S.zarr").exists()


def test_parse_quantity_refuses_a_division_by_zero():
    from coincli.quantities import parse_quantity, parse_span

    for text in ("pi/0", "-pi/0", "2pi/0.0", "pi/1e-400"):
        with pytest.raises(ParameterError, match="divides by zero"):
            parse_quantity("phi0", text)
    with pytest.raises(ParameterError, match="divides by zero"):
        parse_span("y0", "r:r/0")
    assert parse_quantity("phi0", "pi/2").value == pytest.approx(math.pi / 2)


@pytest.mark.parametrize("args, words", [
    (["stability", "--shock", "--diameter", "1e300"], "stiffest contact mode overflows"),
    (["stability", "--diameter", "1e160"], "--diameter 1e+160 m"),
    (["stability", "--shock", "--thickness", "1e-200"], "--thickness 1e-200 m is too thin"),
    (["simulate", "--diameter", "1e300", "--no-rrd"], "past what the model computes with"),
    (["fractions", "--thickness", "1e-170", "--samples", "100"], "too thin"),
])
def test_a_coin_past_floating_point_is_one_line(args, words, capsys):
    """Sizes whose squares overflow or vanish (a ZeroDivisionError or an OverflowError in
    0.10.0) are refused by the scene's checks, naming the options."""
    line = one_error_line(capsys, *args)
    assert words in line, line


def test_a_thin_coin_gets_its_stability_without_cancellation():
    """r - r_d of a coin with t/d = 5e-11 cancels to zero (0.10.0: a ZeroDivisionError): as
    r_t^2 / (r + r_d) it keeps its digits, k_cr = m g (r + r_d) / (2 r_t^2)."""
    import coincli

    for thickness in (1e-12, 1e-9, 1e-6):
        scene = coincli.load_preset("paper").with_overrides(thickness=thickness)
        report = coincli.stability(scene)
        coin = scene.coin
        exact = coin.mass * scene.g * (coin.r + coin.r_d) / (2 * coin.r_t ** 2)
        assert report.k_cr == pytest.approx(exact, rel=1e-12)
        assert report.k_stand_exact == pytest.approx(exact / 2, rel=1e-12)
