"""Friction everywhere a scene's physical parameters go (issue 47): mu and slip_velocity in
presets, the API's calls and every command that takes physical parameters, checked in one line;
stores that record them (and a store without them reads as mu = 0); `coin simulate` saying what
friction took of a throw, or would take; Rerun's friction forces; the friction model's compile
notice. The physics of the friction law is tests/test_friction.py's."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.params import ParameterError

runner = CliRunner()
FIG2 = ("--vy", "1.197", "--vphi", "3.508")
RES, CHUNK = 8, 4


@pytest.fixture(autouse=True)
def in_tmp(tmp_path, monkeypatch):
    """Every command in a scratch directory (simulate writes coin.rrd by default)."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


def run(*args, env=None):
    return runner.invoke(app, [str(a) for a in args], env=env)


def one_line_error(result, *fragments) -> str:
    assert result.exit_code == 2, (result.exit_code, result.stdout, result.stderr)
    err = result.stderr.strip()
    assert len(err.splitlines()) == 1 and err.startswith("error:"), err
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    return err


@pytest.fixture(scope="module")
def base():
    return coincli.load_preset("paper")


# -- parameters: checked, in the API's words and the command line's ---------------------------

@pytest.mark.parametrize("values,fragment", [
    (dict(mu=-0.1), "mu must be a friction coefficient from 0"),
    (dict(mu=11.0), "to 10, got 11"),
    (dict(mu=float("nan")), "mu must be finite"),
    (dict(mu=0.3, slip_velocity=0.0), "slip_velocity must be a speed above 0"),
    (dict(mu=0.3, slip_velocity=-1e-3), "slip_velocity must be a speed above 0"),
    (dict(mu="0.3"), "mu must be a number"),
])
def test_bad_friction_is_one_line_in_the_apis_words(base, values, fragment):
    with pytest.raises(ParameterError) as error:
        coincli.simulate(base, **values)
    assert fragment in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize("command", [
    ("simulate", "--no-rrd"), ("basin", "s.zarr", "--res", "4"), ("fractions", "--samples", "64"),
    ("stability",), ("methods",), ("accuracy", "--quick")])
@pytest.mark.parametrize("option,value,fragment", [
    ("--mu", "-1", "--mu must be a friction coefficient from 0 (none: the paper's model) to 10"),
    ("--mu", "12", "--mu must be a friction coefficient"),
    ("--mu", "inf", "--mu must be finite"),
    ("--slip-velocity", "0", "--slip-velocity must be a speed above 0 m/s"),
])
def test_bad_friction_options_are_one_line_exit_2(command, option, value, fragment):
    extra = ("--mu", "0.3") if option == "--slip-velocity" else ()
    result = run(*command, *extra, option, value)
    one_line_error(result, fragment)
    assert not Path("s.zarr").exists()


@pytest.mark.parametrize("command", [("simulate",), ("basin", "sweep"), ("fractions",),
                                     ("stability",), ("methods",), ("accuracy",)])
def test_every_command_of_physical_parameters_takes_mu_and_slip_velocity(command):
    result = run(*command, "--help", env={"COLUMNS": "200"})
    assert result.exit_code == 0
    assert "--mu" in result.stdout and "--slip-velocity" in result.stdout, result.stdout


def test_a_preset_sets_friction_and_coin_presets_says_so(tmp_path, monkeypatch):
    import coincli.presets as presets

    folder = tmp_path / "presets"
    folder.mkdir()
    for shipped in presets.presets_dir().glob("*.toml"):
        (folder / shipped.name).write_text(shipped.read_text())
    (folder / "grippy.toml").write_text(
        'name = "grippy"\ndescription = "with friction"\n[foundation]\nk = 10000.0\n'
        'c = 0.5\nmu = 0.3\nslip_velocity = 0.0005\n')
    scene = coincli.load_preset(str(folder / "grippy.toml"))
    assert (scene.foundation.mu, scene.foundation.slip_velocity) == (0.3, 0.0005)
    monkeypatch.setattr(presets, "presets_dir", lambda: folder)
    result = run("presets")
    assert result.exit_code == 0, result.output
    text = " ".join(result.stdout.split())
    assert "capped (no t_end), friction mu = 0.3 at the corners, slip velocity 0.0005 m/s. " \
           "with friction" in text, text
    assert text.count("mu = 0.3") == 1, text  # said once, on the preset's own line
    data = json.loads(run("presets", "--json").stdout)
    assert data["grippy"]["foundation"]["mu"] == 0.3
    assert "mu" not in data["paper"]["foundation"]  # the paper's model records none
    bad = folder / "bad.toml"
    bad.write_text("[foundation]\nmu = -1\n")
    one_line_error(run("simulate", "--preset", bad, "--no-rrd"), "mu must be a friction")


# -- the API's calls ----------------------------------------------------------------------------

def test_coin_methods_names_the_stick_that_bounds_a_fixed_step():
    from coincli.models import stick_rate

    scene = coincli.load_preset("paper").with_overrides(mu=0.3)
    table = coincli.method_table(scene)
    assert table.stick_rate == pytest.approx(stick_rate(scene)) and table.stick_rate > 1e4
    assert coincli.method_table(coincli.load_preset("paper")).stick_rate == 0.0
    result = run("methods", "--mu", "0.3")
    text = " ".join(result.stdout.split())
    assert result.exit_code == 0 and "friction's stick at rest decays at 1.604e+04 /s" in text
    assert json.loads(run("methods", "--mu", "0.3", "--json").stdout)["stick_rate"] == \
        pytest.approx(table.stick_rate)


def test_the_apis_calls_take_mu(base):
    run_ = coincli.simulate(base, mu=0.3, vy=1.197, vphi=3.508)
    assert run_.scene.foundation.mu == 0.3 and run_.friction_work > 0
    assert coincli.classify(base, mu=0.3, vy=1.197, vphi=3.508).quarter_turns == \
        run_.quarter_turns
    ds = coincli.basin(base, mu=0.3, res=RES, chunk=CHUNK, threads=1)
    attrs = coincli.basin_attrs(ds)
    assert attrs["parameters"]["foundation"]["mu"] == 0.3
    assert attrs["method"]["model"] == "friction"
    assert coincli.fractions(base, mu=0.3, samples=64, batch=64, threads=1).samples == 64
    over = coincli.fractions_over(base, "mu", [0.0, 0.3], samples=64, batch=64, threads=1)
    assert over.parameters == ("mu",) and over.values == [0.0, 0.3]
    assert over.to_dataset()["mu"].attrs["units"] == "1"
    thick = coincli.fractions_over(base, "k", [5000, 10000], mu=0.3, samples=64, batch=64,
                                   threads=1)
    assert thick.values == [5000, 10000]
    found = coincli.minimal_shock(base, "standing", "vx", mu=0.3)
    assert found.value is not None
    with pytest.raises(TypeError, match="unexpected keyword argument 'muu'"):
        coincli.basin(base, muu=0.3, res=4)
    with pytest.raises(ParameterError, match="mu must be"):
        coincli.fractions(base, mu=-1, samples=64)


def test_stability_shock_says_its_friction():
    """The minimal shocks depend on mu (a standing coin's base grips: vx 1.20 -> 1.12 times the
    static kick at mu 0.3), so their table says the friction it ran with."""
    result = run("stability", "--shock", "--mu", "0.3", env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    text = " ".join(result.stdout.split())
    assert ("smallest kick to another well, with friction (mu = 0.3 at the corners, slip "
            "velocity 0.001 m/s)") in text, result.stdout
    assert "0.034725 m/s │ 0.031039 m/s │ 1.119" in text, result.stdout


def test_a_continuation_over_mu_and_its_store(tmp_path):
    store = tmp_path / "over.zarr"
    args = ("fractions", "--samples", "128", "--batch", "128", "--over", "mu=0,0.3",
            "--store", store, "--json", "-q")
    result = run(*args)
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["parameter"] == "mu" and data["units"] == "1"
    assert data["values"] == [0.0, 0.3] and len(data["results"]) == 2
    # the store records the slip velocity its values with friction ran at
    one_line_error(run(*args, "--slip-velocity", "1e-4"), "holds other samples",
                   "slip_velocity = 0.001 in the store, 0.0001 here")
    one_line_error(run("fractions", "--samples", "64", "--over", "slip_velocity=1e-4,1e-3"),
                   "the scene has no friction (--mu = 0)")
    text = run("fractions", "--samples", "128", "--batch", "128", "--over", "mu=0,0.3", "-q")
    assert "(with friction: event_rodas" in text.stdout, text.stdout
    # a dimensionless parameter is named without a unit ("1" only in the JSON, as CF writes it)
    header = next(line for line in text.stdout.splitlines() if "samples" in line and "P" in line)
    assert header.split()[0] == "mu" and "(1)" not in text.stdout, text.stdout
    over = coincli.fractions_over(coincli.load_preset("paper"), over={"mu": [0.0, 0.3]},
                                  samples=128, batch=128, store=store)  # done: read back
    assert repr(over).startswith("FractionsOver(mu, 2 values"), repr(over)


# -- stores --------------------------------------------------------------------------------------

def test_a_store_records_friction_and_one_of_another_mu_is_refused_in_one_line(tmp_path):
    paper, grippy = tmp_path / "paper.zarr", tmp_path / "grippy.zarr"
    sweep = ("basin", "--res", RES, "--chunk", CHUNK, "-q")
    assert run(*sweep[:1], paper, *sweep[1:]).exit_code == 0
    assert run(*sweep[:1], grippy, *sweep[1:], "--mu", "0.3").exit_code == 0
    attrs = coincli.basin_attrs(paper)
    assert "mu" not in attrs["parameters"]["foundation"]  # as a store written before friction
    assert coincli.api.basins.basin_scene(paper).foundation.mu == 0.0
    assert coincli.basin_attrs(grippy)["parameters"]["foundation"] == {
        "k": 10000.0, "c": 0.5, "mu": 0.3, "slip_velocity": 0.001}
    err = one_line_error(run(*sweep[:1], paper, *sweep[1:], "--mu", "0.3"),
                         "holds a different sweep: mu = 0 in the store, 0.3 here (the paper's "
                         "model in the store, the friction model here")
    assert "verification = " not in err and "slip_velocity" not in err  # said once, with mu
    one_line_error(run(*sweep[:1], grippy, *sweep[1:]), "mu = 0.3 in the store, 0 here")
    one_line_error(run(*sweep[:1], grippy, *sweep[1:], "--mu", "0.3", "--slip-velocity",
                       "0.01"), "slip_velocity = 0.001 in the store, 0.01 here")
    # the same parameters: resumed (complete), mu = 0 given or not
    for store, extra in ((paper, ()), (paper, ("--mu", "0")), (grippy, ("--mu", "0.3"))):
        result = run(*sweep[:1], store, *sweep[1:], *extra)
        assert result.exit_code == 0 and "every tile is done already" in result.stdout


def test_a_friction_store_renders_counts_exports_and_replays_with_its_friction(tmp_path):
    store = tmp_path / "grippy.zarr"
    ds = coincli.basin(coincli.load_preset("paper"), mu=0.3, res=RES, chunk=CHUNK,
                       store=store, threads=1)
    stats = run("basin", "stats", store)
    assert stats.exit_code == 0 and "friction mu = 0.3" in stats.stdout
    # the method the user chose, and the switching pair its ladder ran
    assert "event (run as event_rodas)" in " ".join(stats.stdout.split()), stats.stdout
    # and its JSON the parameters the store holds, friction among them
    as_json = json.loads(run("basin", "stats", store, "--json").stdout)
    assert as_json["parameters"]["foundation"]["mu"] == 0.3
    assert run("basin", "render", store, "-o", tmp_path / "m.png").exit_code == 0
    # the map says so too, its line of settings broken where it would be wider than the figure
    fig = coincli.render_basin(ds)
    subtitle = fig.axes[0].title
    assert "event (run as event_rodas)" in subtitle.get_text(), subtitle.get_text()
    assert ";\n" in subtitle.get_text()
    assert subtitle.get_window_extent().width <= fig.bbox.width
    # its analysis keeps the store's parameters and says its mu
    analysis = coincli.analyze(ds, points=0, bands=1, box=2, radius=2, balls=100)
    assert analysis.friction == 0.3
    assert analysis.to_dict()["parameters"]["foundation"]["mu"] == 0.3
    assert "$\\mu$ = 0.3" in coincli.render_analysis(analysis).get_suptitle()
    assert run("basin", "export", store, tmp_path / "m.nc").exit_code == 0
    assert coincli.basin_attrs(tmp_path / "m.nc")["parameters"]["foundation"]["mu"] == 0.3
    assert run("basin", "verify", store).exit_code == 0
    assert run("basin", "show", store, "--rrd", tmp_path / "m.rrd").exit_code == 0
    i, j = map(int, np.argwhere(ds.certainty.values == coincli.Certainty.CERTAIN)[5])
    result = run("basin", "inspect", store, "--cell", f"{i},{j}", "--json")
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["matches"] and out["parameters"]["foundation"]["mu"] == 0.3
    assert out["command"].startswith("coin simulate --mu 0.3 "), out["command"]
    # the command it prints reproduces the stored label
    words = out["command"].split()[1:]
    again = json.loads(run(*words, "--json", "--no-rrd").stdout)
    assert again["quarter_turns"] == out["stored"]["quarter_turns"]
    assert coincli.cell_scene(store, cell=(i, j)).foundation.mu == 0.3


# -- coin simulate: what friction took, or would take --------------------------------------------

def test_simulate_says_what_friction_would_take_of_a_frictionless_throw():
    result = run("simulate", *FIG2, "--no-rrd")
    assert result.exit_code == 0, result.output
    line = " ".join(next(line for line in result.stdout.splitlines()
                         if line.startswith("friction")).split())
    assert line.startswith("friction none (mu = 0, the paper's model); friction of coefficient "
                           "mu would take about mu x "), line
    assert "mJ of the throw's 2.5608 mJ" in line and line.endswith("try --mu 0.3"), line
    data = json.loads(run("simulate", *FIG2, "--no-rrd", "--json").stdout)
    assert data["mu"] == 0.0 and data["friction_work"] == 0.0
    assert 0.5 * data["energy_initial"] < data["sliding_work"] < 5 * data["energy_initial"]
    # a throw that never slides on the foundation: nothing to take
    still = run("simulate", "--vy", "1", "--no-rrd")
    assert "no corner slid along the foundation while pressed on it" in still.stdout


def test_simulate_with_friction_says_the_energy_it_took():
    result = run("simulate", *FIG2, "--mu", "0.3", "--no-rrd", "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["mu"] == 0.3 and data["slip_velocity"] == 0.001
    assert data["parameters"]["foundation"]["mu"] == 0.3
    assert 0 < data["friction_work"] < data["energy_dissipated"]
    assert data["method"] == "event"  # the scene's; its ladder climbs on event_rodas
    rungs = data["verification"]["rungs"]
    assert {r["method"] for r in rungs} == {"event_rodas"}
    assert rungs[-1]["rtol"] == pytest.approx(1e-12)
    frictionless = json.loads(run("simulate", *FIG2, "--no-rrd", "--json").stdout)
    assert [r["method"] for r in frictionless["verification"]["rungs"][:2]] == [
        "event", "event_dop853"]
    text = run("simulate", *FIG2, "--mu", "0.3", "--no-rrd").stdout
    line = " ".join(next(line for line in text.splitlines() if line.startswith("friction"))
                    .split())
    share = 100 * data["friction_work"] / data["energy_initial"]
    assert line == (f"friction took {data['friction_work'] * 1e3:.4g} mJ, {share:.3g} % of the "
                    f"throw's 2.5608 mJ (mu = 0.3, slip velocity 0.001 m/s)"), line


def test_simulate_says_why_its_ladder_climbed_past_a_rung_of_the_same_n():
    # a throw at mu = 0.6 whose first two rungs give n = -6 but settle 0.03 s apart: the
    # ladder's rule wants the same moments too, so it climbs to a third rung
    result = run("simulate", "--mu", "0.6", "--vy", "1.182258064516129", "--vphi",
                 "3.225806451612904", "--no-rrd")
    assert result.exit_code == 0, result.output
    text = " ".join(result.stdout.replace("\u00a0", " ").split())
    assert "certain: rtol = 1e-07 and rtol = 1e-08 agree" in text, text
    assert "rtol = 1e-07: n = -6 (settled 0.03" in text and "s apart from the rung before)" \
        in text, text


def test_the_ladders_gaps_follow_its_rule_of_agreement():
    from types import SimpleNamespace as Run

    from coincli.api.words import ladder_of

    ladder = ladder_of(coincli.load_preset("paper"))
    a = Run(settle_time=0.4, last_change=0.1)
    assert ladder.gaps(a, Run(settle_time=0.405, last_change=0.1005)) == []  # within both
    assert ladder.gaps(a, Run(settle_time=0.45, last_change=0.105)) == [
        "settled 0.05 s apart", "entered its well 5 ms apart"]
    assert ladder.gaps(Run(settle_time=0.4, last_change=math.nan), a) == [
        "only one of the two changed well"]
    assert ladder.gaps(Run(settle_time=0.4, last_change=math.nan),
                       Run(settle_time=0.4, last_change=math.nan)) == []


def test_the_work_is_the_same_recorded_or_not(base):
    """A throw that keeps no samples still integrates the work (it records its ends only), and
    the same as one that keeps them (the same steps: the samples are read off the steps)."""
    bare = coincli.simulate(base, mu=0.3, vy=1.197, vphi=3.508)
    kept = coincli.simulate(base, mu=0.3, vy=1.197, vphi=3.508, sample_dt=1e-3)
    assert bare.samples is None and bare.sample_dt is None and len(kept.samples) > 100
    assert bare.friction_work == pytest.approx(kept.friction_work, rel=1e-12)
    assert bare.sliding_work == pytest.approx(kept.sliding_work, rel=1e-12)
    assert bare.to_dict()["friction_work"] == bare.friction_work
    ds = kept.to_dataset()
    assert ds.attrs["foundation.mu"] == 0.3


# -- Rerun: the friction forces beside the normal forces -----------------------------------------

def test_the_recording_shows_each_corners_friction_beside_its_normal_force(tmp_path):
    pytest.importorskip("rerun")
    from test_rrd import Recording  # noqa: I001 - the suite's reader of a recording

    from coincli.recordings import rrd as rrd_io
    from coincli.recordings.frames import build_frames, friction_arrows

    run_ = coincli.simulate(coincli.load_preset("paper"), mu=0.3, vy=1.197, vphi=3.508,
                            sample_dt=1e-3, record_events=True)
    frames = build_frames(run_)
    assert np.abs(frames.tangential).max() > 0
    assert np.all(np.abs(frames.tangential) <= 0.3 * frames.normal + 1e-12)
    arrows = friction_arrows(frames, run_.scene.coin.mass * run_.scene.g, 0.02)
    assert np.all(arrows[..., 1] == 0) and np.all(np.sign(arrows[..., 0])
                                                 == np.sign(frames.tangential))
    path = tmp_path / "fric.rrd"
    rrd_io.write_recording(run_, rrd=path, log_every=1e-3)
    rec = Recording(path)
    for i in range(4):
        normal = rec.scalars(f"/{rrd_io.CONTACT_FORCES}/normal{i}")
        tangential = rec.scalars(f"/{rrd_io.CONTACT_FORCES}/tangential{i}")
        assert len(normal) == len(tangential) > 100
        assert np.all(np.abs(tangential) <= 0.3 * normal + 1e-9)
    assert f"/{rrd_io.FRICTION}" in rec.entities
    info = rec.static(f"/{rrd_io.INFO}").column("TextDocument:text").to_pylist()[0][0]
    assert "**Friction:** mu = 0.3, slip velocity 0.001 m/s" in info
    assert "teal arrows" in info
    # the paper's throw: no friction arrows or force plots, and what friction would take
    paper = coincli.simulate(coincli.load_preset("paper"), vy=1.197, vphi=3.508,
                             sample_dt=1e-3, record_events=True)
    rrd_io.write_recording(paper, rrd=tmp_path / "paper.rrd", log_every=1e-3)
    rec = Recording(tmp_path / "paper.rrd")
    assert f"/{rrd_io.FRICTION}" not in rec.entities
    assert not any(e.startswith(f"/{rrd_io.CONTACT_FORCES}") for e in rec.entities)
    info = rec.static(f"/{rrd_io.INFO}").column("TextDocument:text").to_pylist()[0][0]
    assert "**Friction:** none (mu = 0, the paper's model); a friction coefficient mu would " \
           "take about mu x" in info


def test_simulate_rrd_with_friction_writes_it(tmp_path):
    result = run("simulate", *FIG2, "--mu", "0.3", "--rrd", tmp_path / "f.rrd")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "f.rrd").stat().st_size > 10_000


def test_a_notebook_shows_a_friction_throw(monkeypatch):
    pytest.importorskip("rerun_notebook")
    from rerun.notebook import Viewer

    from coincli.recordings import stream

    shown = []
    monkeypatch.setattr(Viewer, "_flush_hook", lambda self, data: None)
    monkeypatch.setattr(stream, "in_notebook", lambda: True)
    monkeypatch.setattr(Viewer, "display", lambda self, **_: shown.append(self))
    coincli.simulate(coincli.load_preset("paper"), mu=0.3, vy=1.197, vphi=3.508).show()
    assert len(shown) == 1


# -- compiling the friction model's kernels ------------------------------------------------------

def test_the_compile_notice_names_the_friction_model(monkeypatch):
    import io

    from rich.console import Console

    import coincli.api as api
    import coincli.cli.common as common
    import coincli.jit as jit

    out = io.StringIO()
    asked = []
    monkeypatch.setattr(common, "err_console", Console(file=out, force_terminal=False, width=80))
    monkeypatch.setattr(jit, "kernels_cached", lambda model="paper": model != "friction")
    monkeypatch.setattr(api, "compile_kernels", lambda **model: (asked.append(model),
                                                                 time.sleep(0.2))[0])
    common.compile_first(scene=coincli.load_preset("paper").with_overrides(mu=0.3))
    lines = out.getvalue().strip().splitlines()
    seconds = coincli.api.throws.compile_seconds(model="friction")
    assert lines[0] == ("compiling the friction model's numerical kernels for this machine (a "
                        "scene with --mu > 0): once after installing or updating, about "
                        f"{round(seconds / 60)} min"), lines
    assert lines[-1].startswith("compiled the friction model's numerical kernels in 0 s")
    assert asked == [{"model": "friction"}]
    common.compile_first(scene=coincli.load_preset("paper"))  # the paper's: compiled
    assert asked == [{"model": "friction"}]


def test_coin_compile_friction_and_all(monkeypatch):
    import coincli.jit as jit

    monkeypatch.setattr(jit, "kernels_cached", lambda model="paper": True)
    result = run("compile", "--friction")
    assert result.exit_code == 0
    assert "the friction model's numerical kernels are compiled already" in result.stdout
    result = run("compile", "--all")
    assert "the numerical kernels are compiled already" in result.stdout
    assert "the friction model's numerical kernels are compiled already" in result.stdout
    one_line_error(run("compile", "--all", "--friction"), "give --friction or --all")


def test_the_compile_api_is_model_aware(base):
    from coincli.api import throws

    assert throws.kernel_model(base) == "paper"
    assert throws.kernel_model(base.with_overrides(mu=0.3)) == "friction"
    assert throws.model_names() == ("paper", "friction")
    assert throws.compile_seconds(model="paper") == coincli.api.throws.FIRST_COMPILE_SECONDS
    assert throws.compile_seconds(base.with_overrides(mu=0.3)) > 0
    with pytest.raises(ParameterError, match="model must be one of paper, friction"):
        throws.kernels_cached(model="coulomb")
    with pytest.raises(ParameterError, match="a scene or a model"):
        throws.compile_kernels(base, model="paper")
    # compiled already by the tests above (a friction throw ran compiled): nothing to do
    coincli.basin(base, mu=0.3, res=4, chunk=4, threads=1)
    assert throws.compile_kernels(base.with_overrides(mu=0.3)) is False


def test_a_throw_that_outgrows_python_says_so_before_compiling(monkeypatch, base):
    """The first run of a model's compiled kernels, where they are not compiled yet, calls
    before_compile first (`coin simulate` shows its compile notice there)."""
    import coincli.throw as throw

    called = []
    monkeypatch.setattr(throw, "kernels_cached", lambda model: False)
    coincli.simulate(base, mu=0.3, vy=1.197, vphi=3.508, engine="numba",
                     before_compile=lambda: called.append(1))
    assert called == [1]  # once: the ladder's later rungs find the kernels loaded
