"""One syntax for initial conditions everywhere (coincli.quantities): numbers, multiples of pi
for angles, of the half diagonal r for heights, LO:HI ranges; in the API and every command."""

from __future__ import annotations

import math

import numpy as np
import pytest
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.params import ParameterError
from coincli.quantities import Quantity, parse_quantity, parse_span

runner = CliRunner()
PAPER = coincli.load_preset("paper")
R = PAPER.coin.r


@pytest.mark.parametrize(("name", "text", "value"), [
    ("phi0", "pi", math.pi), ("phi0", "-pi", -math.pi), ("phi0", "2pi", 2 * math.pi),
    ("phi0", "pi/2", math.pi / 2), ("phi0", "-3pi/4", -0.75 * math.pi),
    ("phi0", "0.5*pi", 0.5 * math.pi), ("vphi", " 2 pi ", 2 * math.pi),
    ("vy", "1.197", 1.197), ("vy", "-2e-3", -2e-3), ("vx", "0", 0.0),
])
def test_values_read_as_written(name, text, value):
    q = parse_quantity(name, text)
    assert not q.per_r and q.value == pytest.approx(value, rel=1e-15)


def test_heights_in_multiples_of_the_half_diagonal():
    assert parse_quantity("y0", "r") == Quantity(1.0, per_r=True)
    assert parse_quantity("y0", "5r").resolve(R) == pytest.approx(5 * R)
    assert parse_quantity("y0", "r/2").resolve(R) == pytest.approx(R / 2)
    assert parse_quantity("y0", "0.02").resolve(R) == 0.02


@pytest.mark.parametrize(("name", "text", "says"), [
    ("vy", "pi", "pi is for the angles"), ("phi0", "2r", "are for y0 only"),
    ("vy", "abc", "is not a number"), ("phi0", "1.5x", "is not a number"),
    ("vy", "١.٥", "is not a number"),
])
def test_what_cannot_be_read_says_what_can(name, text, says):
    with pytest.raises(ParameterError, match=says) as info:
        parse_quantity(name, text)
    assert name in info.value.parameters


@pytest.mark.parametrize("text", ["1..2", "1,2", "1-2", "1 2", "1:2:3", ":2", "1:"])
def test_a_malformed_range_says_how_to_write_one(text):
    with pytest.raises(ParameterError, match="LO:HI, e.g. 0.05:2"):
        parse_span("vy", text)


def test_ranges():
    lo, hi = parse_span("phi0", "-pi:pi")
    assert (lo.value, hi.value) == (-math.pi, math.pi)
    lo, hi = parse_span("y0", "r:5r")
    assert lo.per_r and hi.per_r and (lo.value, hi.value) == (1.0, 5.0)
    assert parse_span("vy", (0.05, "2")) == (Quantity(0.05), Quantity(2.0))
    with pytest.raises(ParameterError, match="not a mix"):
        parse_span("y0", "r:0.05")
    with pytest.raises(ParameterError, match="empty range"):
        parse_span("phi0", "pi:-pi")


def test_the_api_takes_the_syntax_for_a_sweep_a_throw_and_a_draw():
    plan = coincli.plan_sweep(PAPER, phi0="-pi:pi", vx="-0.5:0.5", vy=1, vphi="pi", res=4)
    phi0, vx = plan.grid.axes
    assert (phi0.name, phi0.lo, phi0.hi) == ("phi0", -math.pi, math.pi)
    assert plan.scene.initial.vphi == math.pi and plan.scene.initial.vy == 1
    plan = coincli.plan_sweep(PAPER, y0="r:3r", vy=1, res=4)
    assert plan.grid.axes[0].lo == pytest.approx(R) and plan.grid.axes[0].hi == pytest.approx(3 * R)
    # a scene's overrides: r of the coin as overridden in the same call
    scene = PAPER.with_overrides(y0="2r", phi0="pi/2", diameter=0.03)
    assert scene.initial.y0 == pytest.approx(2 * math.hypot(0.015, PAPER.coin.r_t))
    assert scene.initial.phi0 == math.pi / 2
    plan = coincli.plan_fractions(PAPER, phi0="-pi:pi", y0="r:5r", samples=1024)
    assert "phi0 = -3.14159:3.14159 rad" in plan.sampling.describe()


def test_simulate_takes_the_scene_values_as_keywords():
    run = coincli.simulate(PAPER, vy=1.197, vphi=3.508)
    same = coincli.simulate(PAPER.with_overrides(vy=1.197, vphi=3.508))
    assert run.quarter_turns == same.quarter_turns == 6
    assert np.array_equal(run.final_state, same.final_state)
    assert coincli.classify(PAPER, vy=1.197, vphi=3.508).quarter_turns == 6
    assert coincli.simulate(PAPER, vy=1.0, phi0="pi/2", y0="2r").scene.initial.y0 == \
        pytest.approx(2 * R)
    with pytest.raises(TypeError, match="unexpected keyword argument 'vyy'"):
        coincli.simulate(PAPER, vyy=1.0)
    with pytest.raises(ParameterError, match="vy: 'fast' is not a number"):
        coincli.simulate(PAPER, vy="fast")


def test_every_command_reads_the_syntax(tmp_path):
    store = tmp_path / "s.zarr"
    result = runner.invoke(app, ["basin", str(store), "--phi0", "-pi:pi", "--vx", "-0.5:0.5",
                                 "--vy", "1", "--vphi", "3", "--res", "8", "--quiet"])
    assert result.exit_code == 0, result.output
    attrs = coincli.basin_attrs(store)
    assert [(a["name"], a["lo"]) for a in attrs["sweep"]["axes"]] == [("phi0", -math.pi),
                                                                      ("vx", -0.5)]
    result = runner.invoke(app, ["basin", "inspect", str(store), "--phi0", "pi/2", "--vx",
                                 "0.1"])
    assert result.exit_code == 0, result.output
    result = runner.invoke(app, ["basin", "render", str(store), "-o", str(tmp_path / "m.png"),
                                 "--mark", "pi/4,0.2"])
    assert result.exit_code == 0, result.output
    result = runner.invoke(app, ["simulate", "--phi0", "pi/2", "--y0", "2r", "--vy", "1",
                                 "--no-rrd"])
    assert result.exit_code == 0, result.output
    assert "phi0 = 1.5708" in result.output


@pytest.mark.parametrize("args", [["basin", "x.zarr", "--vy", "1..2"],
                                  ["fractions", "--vy", "1-2", "--samples", "8"],
                                  ["basin", "x.zarr", "--vphi", "1,2"]])
def test_a_malformed_range_is_one_line_naming_the_option(args, tmp_path):
    result = runner.invoke(app, args, catch_exceptions=False)
    assert result.exit_code == 2
    assert "LO:HI, e.g. 0.05:2" in result.output and "--v" in result.output
    assert "Traceback" not in result.output
