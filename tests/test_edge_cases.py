"""Edge cases found in review: simultaneous touch-downs, degenerate parameters, strict JSON."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from coincli import simulate
from coincli.cli import app
from coincli.presets import load


def invoke(*args):
    return CliRunner().invoke(app, list(args))


def strict_json(text: str):
    def refuse(constant):
        raise ValueError(f"{constant} is not JSON")

    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("method", ["event", "dopri5"])
@pytest.mark.parametrize("vy", [0.5, 2.0, 2.2403])
def test_flat_landing_touches_with_both_corners_at_once(method, vy):
    """A coin thrown straight up lands flat on two corners at the same instant: no torque may
    appear, so phi stays exactly 0 (the event method once added the corners one by one)."""
    scene = load("paper").scene.with_overrides(verify=False, vy=vy, vphi=0.0, method=method,
                                               t_end=3.0)
    tr = simulate(scene, record_events=True)
    assert tr.final_state[2] == 0.0 and tr.final_state[5] == 0.0
    assert tr.quarter_turns == 0
    first_two = tr.events[:2]
    assert first_two[0, 0] == first_two[1, 0]  # same time
    assert sorted(first_two[:, 1].astype(int)) == [0, 1]


@pytest.mark.parametrize("args,message", [
    (["--thickness", "0.03"], "smaller than the diameter"),
    (["--g", "0"], "g must be positive"),
    (["--rtol", "1e-30"], "rtol must be between"),
    (["--method", "symplectic_euler", "--t-end", "1e13"], "at most 1e12"),
])
def test_degenerate_parameters_are_refused(args, message):
    result = invoke("simulate", "--no-rrd", *args)
    assert result.exit_code == 2
    assert message in result.output and "Traceback" not in result.output


def test_preset_file_that_is_not_utf8(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"\xff\xfe")
    result = invoke("simulate", "--no-rrd", "--preset", str(bad))
    assert result.exit_code == 2 and "malformed preset file" in result.output


def test_json_never_prints_nan_or_infinity():
    out = invoke("simulate", "--no-rrd", "--k", "1e300", "--json")
    data = strict_json(out.stdout)
    assert data["status"] == "non-finite" and data["quarter_turns"] is None
    assert data["energy_final"] is None
    assert out.exit_code == 1  # a non-finite run is reported, not labelled


def test_render_to_a_missing_folder_is_a_one_line_error(tmp_path):
    path = tmp_path / "s.zarr"
    assert invoke("basin", str(path), "--res", "4", "--vy", "0.2:0.4", "--quiet").exit_code == 0
    result = invoke("basin", "render", str(path), "-o", str(tmp_path / "b.png"), "--rrd",
                    str(tmp_path / "nowhere" / "x.rrd"))
    assert result.exit_code == 2 and "does not exist" in result.output
    result = invoke("basin", "render", str(path), "-o", str(tmp_path / "nowhere" / "b.png"))
    assert result.exit_code == 2 and "does not exist" in result.output


@pytest.mark.parametrize("args", [["--threads", "0"], ["--repeats", "0"], ["--basin-res", "1"]])
def test_bench_validates_its_options(args):
    result = invoke("bench", *args)
    assert result.exit_code == 2 and "error:" in result.output
