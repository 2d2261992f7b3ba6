"""`coin fractions` and coincli.fractions: Monte Carlo outcome probabilities, checked against
answers known exactly (a square coin stands half the time, a soft foundation never holds a
standing coin, mirror symmetry, the basin's own fraction), and reproducible, resumable runs."""

from __future__ import annotations

import json
import math
import sys
import threading
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.montecarlo import (
    Dist,
    Draws,
    Goal,
    Progression,
    Tally,
    lamina_inertia,
    make_sampling,
    parse_dist,
    pender_uhrin,
    wilson_arrays,
)
from coincli.params import ParameterError, validate
from coincli.stats import wilson

PAPER = coincli.load_preset("paper")
SMALL = {"batch": 1024}  # small batches: the tests' sample counts stay whole batches


def covers(p: dict, value: float) -> bool:
    return p["low"] <= value <= p["high"]


# -- distributions, intervals, formulas (no simulation) -----------------------------------------
def test_distributions_are_parsed_with_pi_and_multiples_of_r():
    assert parse_dist("phi0", "0:2pi") == Dist("uniform", 0.0, 2 * math.pi)
    assert parse_dist("phi0", "-pi/2") == Dist("fixed", -math.pi / 2)
    assert parse_dist("y0", "r:5r") == Dist("uniform", 1.0, 5.0, per_r=True)
    assert parse_dist("vx", (-0.5, 0.5)) == Dist("uniform", -0.5, 0.5)
    assert parse_dist("vx", 0.25) == Dist("fixed", 0.25)
    d = parse_dist("y0", "normal(3r, 0.5r, r, 5r)")
    assert (d.kind, d.a, d.b, d.lo, d.hi, d.per_r) == ("normal", 3, 0.5, 1, 5, True)
    r = PAPER.coin.r
    assert d.scaled(r).support() == (r, 5 * r)
    for name, text, fragment in [("y0", "0.01:5r", "not a mix"), ("vx", "1r", "y0 only"),
                                 ("vy", "2:1", "empty range"), ("vy", "normal(0,-1)",
                                                                "positive"),
                                 ("vphi", "abc", "not a number"), ("vy", "beta(1,2)",
                                                                   "not a distribution")]:
        with pytest.raises(ParameterError, match=fragment):
            parse_dist(name, text)


def test_normal_draws_have_their_moments_and_truncation():
    u = (np.arange(20000) + 0.5) / 20000
    x = parse_dist("vx", "normal(0.1, 0.3)").ppf(u)
    assert abs(x.mean() - 0.1) < 1e-3 and abs(x.std() - 0.3) < 3e-3
    t = parse_dist("vx", "normal(0, 1, 0.5, 2)").ppf(u)
    assert t.min() >= 0.5 and t.max() <= 2.0
    from scipy.stats import truncnorm

    assert np.median(t) == pytest.approx(truncnorm(0.5, 2).median(), abs=1e-4)
    assert t.mean() == pytest.approx(truncnorm(0.5, 2).mean(), abs=1e-4)


def test_a_normal_whose_draws_overflow_is_refused_in_one_line():
    """`--vphi "normal(0,1e308)"` drew infinities, and numpy's "overflow encountered in
    multiply" leaked out of the command: refused before any draw, in our words, by the API
    (ParameterError naming vphi) and the command line (one line, exit 2, no warning)."""
    import subprocess

    with pytest.raises(ParameterError, match="past the largest float") as caught:
        coincli.fractions(PAPER, vphi="normal(0,1e308)", samples=256)
    assert caught.value.parameters == ("vphi",)
    widest = parse_dist("vphi", f"normal(-1e300, {sys.float_info.max / 8.4!r})")
    with np.errstate(all="raise"):  # the widest normal allowed draws finite numbers
        assert np.isfinite(widest.ppf(np.array([0.0, 0.5, 1.0]))).all()
    result = subprocess.run([sys.executable, "-m", "coincli", "fractions", "--vphi",
                             "normal(0,1e308)", "--samples", "256"], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 2 and result.stdout == "", result.stdout
    assert result.stderr.startswith("error: --vphi normal(0,1e308): draws of this normal reach "
                                     "past the largest float"), result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and "Warning" not in result.stderr


def test_vectorised_wilson_is_the_stats_module_interval():
    ks = [0, 1, 7, 500, 999, 1000, 13_000]
    ns = [1000, 1000, 1000, 1000, 1000, 1000, 4_600_000]
    lo, hi = wilson_arrays(ks, ns)
    for k, n, a, b in zip(ks, ns, lo, hi, strict=True):
        assert (a, b) == pytest.approx(wilson(k, n), rel=1e-12, abs=1e-15)


def test_pender_uhrin_planar_die():
    assert pender_uhrin(1.0) == pytest.approx(0.5, abs=1e-12)
    assert pender_uhrin(0.1) == pytest.approx(3.733e-4, rel=1e-3)  # "about 0.04 %"
    assert np.all(np.diff(pender_uhrin(np.linspace(0.05, 1, 20))) > 0)


def test_a_square_coin_is_valid_and_a_thicker_one_is_not():
    square = PAPER.with_overrides(thickness=0.02)
    assert validate(square).coin.phi_cr == pytest.approx(math.pi / 4)
    with pytest.raises(ParameterError, match="smaller than the diameter"):
        validate(PAPER.with_overrides(thickness=0.021))


def test_sample_i_depends_only_on_seed_and_i():
    s = make_sampling(PAPER, phi0="0:2pi", batch=256, seed=7)
    long = Draws(make_sampling(PAPER, phi0="0:2pi", batch=1024, seed=7)).batch(0)
    jumping = Draws(s)
    assert np.array_equal(jumping.batch(3), long[768:1024])  # fast-forwarded
    assert np.array_equal(jumping.batch(1), long[256:512])  # and back
    rnd = make_sampling(PAPER, sampler="random", batch=256, seed=7)
    assert np.array_equal(Draws(rnd).batch(2), Draws(rnd).batch(2))
    assert not np.array_equal(Draws(rnd).batch(2), Draws(rnd).batch(3))


def test_the_stop_rule_sees_batches_in_order_whatever_order_they_arrive_in():
    rng = np.random.default_rng(1)
    tallies = [Tally(samples=100, counted=Counter({0: 100 - k, 1: k}),
                     labelled=Counter({0: 100 - k, 1: k}))
               for k in rng.integers(0, 8, size=40)]
    goal = Goal(precision=0.02, of="standing", max_samples=4000)
    stops = set()
    for order in (range(40), reversed(range(40)), rng.permutation(40)):
        prog = Progression(goal, 100)
        for i in order:
            prog.add(int(i), tallies[int(i)])
        stops.add((prog.prefix, prog.reason, prog.tally.standing))
    assert len(stops) == 1, stops
    prefix, reason, _ = stops.pop()
    assert reason == "precision" and 1 < prefix < 40


def test_starts_inside_the_foundation_are_refused():
    with pytest.raises(ParameterError, match="deep in the foundation"):
        coincli.api.plan_fractions(PAPER, y0="0.005:0.05", phi0="0:2pi", samples=10)
    with pytest.raises(ParameterError, match="truncate it"):
        coincli.api.plan_fractions(PAPER, y0="normal(0.03, 0.01)", samples=10)
    coincli.api.plan_fractions(PAPER, y0="r:5r", phi0="0:2pi", samples=10)  # fine


def test_coincli_fractions_is_the_api_function_whatever_was_imported_first():
    import coincli.montecarlo  # noqa: F401  (the computation's package: no name clash)

    assert coincli.fractions is coincli.api.fractions
    assert coincli.fractions_over is coincli.api.fractions_over


# -- checks with exact answers ------------------------------------------------------------------
def test_a_square_coin_landing_at_random_stands_half_the_time():
    """t = d: a quarter turn maps the coin onto itself, so with phi0 uniform over a full turn
    every odd n has an even twin, equally likely: P(standing) = 1/2 exactly."""
    d = PAPER.coin.diameter
    square = PAPER.with_overrides(thickness=d, inertia=lamina_inertia(PAPER.coin.mass, d, d))
    r = coincli.fractions(square, phi0="0:2pi", samples=4096, **SMALL)
    assert r.counted > 3000  # a square rolls long: ~15 % of its labels are uncertain
    assert covers(r.standing, 0.5), r.standing
    assert r.standing["high"] - r.standing["low"] < 0.035


def test_a_foundation_softer_than_k_cr_over_2_never_holds_a_standing_coin():
    r = coincli.fractions(coincli.load_preset("soft"), phi0="-pi:pi", samples=4096, **SMALL)
    assert r.counted > 3500
    assert r.standing["count"] == 0 and r.all_labelled["standing"]["count"] == 0
    assert r.standing["probability"] == 0.0 and r.standing["high"] < 2e-3


def test_a_mirror_symmetric_distribution_gives_p_of_n_equal_to_p_of_minus_n():
    r = coincli.fractions(PAPER, phi0="-pi:pi", vx="normal(0, 0.2)", samples=8192, **SMALL)
    rows = {row["n"]: row for row in r.outcomes}
    assert any(n > 0 and rows[n]["count"] > 200 for n in rows)
    for n, row in rows.items():
        twin = r.probability(-n)
        assert row["low"] <= twin["high"] and twin["low"] <= row["high"], (n, row, twin)
    s = sum(row["probability"] for row in r.outcomes)
    assert s == pytest.approx(1.0)


def test_uniform_sampling_of_the_default_box_agrees_with_the_basin():
    ds = coincli.basin(PAPER, res=128, chunk=64)
    stats = coincli.basin_stats(ds)
    on_grid = stats["standing_certain"]  # itself an estimate: 16,384 cells, about 40 standing
    r = coincli.fractions(PAPER, samples=24576, batch=4096)
    assert r.sampling["distributions"]["vy"] == {"kind": "uniform", "low": 0.05, "high": 2.0}
    # the two 95 % intervals overlap (each estimate has its own error)
    assert r.standing["low"] <= on_grid["high"] and on_grid["low"] <= r.standing["high"], \
        (r.standing, on_grid)
    assert 0.001 < r.standing["probability"] < 0.006


# -- reproducible and resumable -----------------------------------------------------------------
def test_the_same_command_gives_the_same_samples_and_results_on_any_thread_count():
    kw = dict(phi0="-pi:pi", precision=0.01, of="all", batch=512)
    a = coincli.fractions(PAPER, threads=1, **kw)
    b = coincli.fractions(PAPER, threads=2, **kw)
    assert a.stopped == b.stopped == "precision" and a.achieved <= 0.01
    assert a.samples == b.samples and a.samples % 512 == 0
    assert a.outcomes == b.outcomes and a.uncertain == b.uncertain


def _files(path: Path) -> dict[str, bytes]:
    """The store's files but its records (runs.jsonl differs from run to run)."""
    from conftest import store_files

    return store_files(path)


def test_an_interrupted_store_resumes_to_the_same_store_and_results(tmp_path):
    kw = dict(phi0="-pi:pi", precision=0.013, batch=512)
    whole = coincli.fractions(PAPER, store=tmp_path / "whole.zarr", **kw)
    assert whole.stopped == "precision" and whole.samples >= 4096
    stop = threading.Event()
    part = coincli.fractions(PAPER, store=tmp_path / "part.zarr", stop=stop,
                             progress=lambda u: stop.set() if u.samples >= 2048 else None,
                             **kw)
    assert part.stopped == "interrupted" and 2048 <= part.samples < whole.samples
    resumed = coincli.fractions(PAPER, store=tmp_path / "part.zarr", threads=1, **kw)
    # the stored batches were not redone: what is left, and at most 2 batches in flight past
    # the stopping point (one thread keeps two in its window)
    assert resumed.cost["computed"] <= whole.samples - 2048 + 2 * 512
    assert resumed.samples == whole.samples and resumed.outcomes == whole.outcomes
    assert _files(tmp_path / "part.zarr") == _files(tmp_path / "whole.zarr")
    again = coincli.fractions(PAPER, store=tmp_path / "whole.zarr", **kw)
    assert again.cost["computed"] == 0 and again.outcomes == whole.outcomes
    with pytest.raises(ParameterError, match="seed = 0 in the store, 1 here"):
        coincli.fractions(PAPER, store=tmp_path / "whole.zarr", seed=1, **kw)


def test_asking_a_store_for_more_samples_extends_it(tmp_path):
    store = tmp_path / "grow.zarr"
    small = coincli.fractions(PAPER, samples=1024, batch=512, store=store)
    more = coincli.fractions(PAPER, samples=2560, batch=512, store=store)
    assert more.cost["computed"] == 1536 and more.samples == 2560
    assert coincli.api.open_fractions(store).sizes["sample"] == 2560
    fresh = coincli.fractions(PAPER, samples=2560, batch=512)
    assert more.outcomes == fresh.outcomes and small.samples == 1024


def _filled(path: Path) -> int:
    import zarr

    try:
        return int((np.asarray(zarr.open_group(str(path), mode="r")["filled"][:]) > 0).sum())
    except (FileNotFoundError, KeyError, ValueError):
        return 0


def test_a_run_killed_with_sigkill_resumes_to_the_same_store(tmp_path):
    import signal
    import subprocess
    import time

    args = ["--samples", "16384", "--batch", "256", "--phi0", "-pi:pi", "-q"]
    killed = tmp_path / "killed.zarr"
    proc = subprocess.Popen([sys.executable, "-m", "coincli", "fractions", *args, "--threads",
                             "1", "--store", str(killed)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, cwd=Path(__file__).parent.parent)
    end = time.monotonic() + 90
    while _filled(killed) < 4:
        assert proc.poll() is None, proc.communicate()[1].decode()[-2000:]
        assert time.monotonic() < end, "no batch was written in time"
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert 4 <= _filled(killed) < 64, "not killed mid-run"
    runner = CliRunner()
    resumed = runner.invoke(app, ["fractions", *args, "--store", str(killed), "--json"])
    assert resumed.exit_code == 0, resumed.stderr
    clean = tmp_path / "clean.zarr"
    whole = runner.invoke(app, ["fractions", *args, "--store", str(clean), "--json"])
    assert json.loads(resumed.stdout)["cost"]["computed"] < 16384
    for key in ("samples", "standing", "lying", "uncertain", "outcomes"):
        assert json.loads(resumed.stdout)[key] == json.loads(whole.stdout)[key], key
    assert _files(killed) == _files(clean)


def test_a_continuation_uses_the_same_samples_at_every_value(tmp_path):
    d = PAPER.coin.diameter
    store = tmp_path / "over.zarr"
    res = coincli.fractions_over(PAPER, "thickness", [0.002, 0.011, d], phi0="0:2pi",
                                 samples=2048, batch=1024, store=store)
    assert [r.value for r in res.results] == [0.002, 0.011, d]
    assert "solid disc" in res.note and "7.96e-08" in res.note
    coin = [r.scene["coin"] for r in res.results]
    assert coin[2]["mass"] == pytest.approx(10 * coin[0]["mass"])
    assert coin[0]["inertia"] == pytest.approx(coin[0]["mass"] * (3 * 0.01 ** 2 + 0.002 ** 2)
                                               / 12)  # a solid disc about a diameter
    assert covers(res.results[2].standing, 0.5)  # a square again, with a disc's inertia
    assert res.standing[0, 0] < res.standing[2, 0]
    ds = coincli.api.open_fractions(store)
    drawn = ds["initial"].values  # (thickness, sample, ic): phi0, vy, vphi shared
    assert np.array_equal(drawn[0, :, 1:], drawn[2, :, 1:])
    assert drawn[2, 0, 0] / drawn[0, 0, 0] == pytest.approx(
        math.hypot(d / 2, d / 2) / math.hypot(d / 2, 0.001))  # y0 = r follows the coin
    again = coincli.fractions_over(PAPER, "thickness", [0.002, 0.011, d], phi0="0:2pi",
                                   samples=2048, batch=1024, store=store)
    assert again.cost["computed"] == 0
    fig = coincli.render_fractions(res, tmp_path / "over.png")
    assert (tmp_path / "over.png").stat().st_size > 10_000 and len(fig.axes) >= 2


# -- the command line ---------------------------------------------------------------------------
def test_cli_json_has_the_probabilities_and_their_intervals(tmp_path):
    result = CliRunner().invoke(app, ["fractions", "--samples", "2048", "--batch", "1024",
                                      "--phi0", "-pi:pi", "--store", str(tmp_path / "s.zarr"),
                                      "--json"])
    assert result.exit_code == 0, (result.stdout, result.stderr)
    data = json.loads(result.stdout)
    assert data["samples"] == 2048
    for key in ("standing", "lying", "uncertain"):
        assert {"probability", "low", "high"} <= set(data[key]), key
        assert data[key]["low"] <= data[key]["probability"] <= data[key]["high"]
    assert all({"n", "probability", "low", "high"} <= set(row) for row in data["outcomes"])
    assert data["sampling"]["distributions"]["phi0"]["kind"] == "uniform"
    table = CliRunner().invoke(app, ["fractions", "--samples", "2048", "--batch", "1024",
                                     "--phi0", "-pi:pi", "--store", str(tmp_path / "s.zarr")])
    assert table.exit_code == 0 and "standing" in table.stdout
    assert "nothing computed" in table.stdout


@pytest.mark.parametrize("args,fragment", [
    (["--y0", "0.01:5r"], "not a mix"),
    (["--y0", "0.002:0.05", "--phi0", "0:2pi"], "deep in the foundation"),
    (["--samples", "100", "--precision", "0.01"], "not both"),
    (["--over", "colour=1:2:3"], "not a physical parameter"),
    (["--plot", "p.png"], "--over"),
    (["--sampler", "halton"], "--sampler"),
    (["--precision", "0.7"], "between 0 and 0.5"),
    (["--thickness", "0.03"], "smaller than the diameter"),
])
def test_cli_refuses_bad_input_in_one_line(args, fragment):
    result = CliRunner().invoke(app, ["fractions", *args])
    assert result.exit_code == 2, (result.stdout, result.stderr)
    err = result.stderr.strip()
    assert err.startswith("error:") and len(err.splitlines()) == 1 and fragment in err, err


def test_ctrl_c_raises_out_of_fractions_and_keeps_the_batches(tmp_path):
    """A notebook's interrupt must stop a cell that loops over runs, as in coincli.basin; the
    store keeps what was finished."""
    import signal

    from conftest import sigint_raises

    def interrupt(update):
        if update.samples >= 1024:
            signal.raise_signal(signal.SIGINT)

    with sigint_raises(), pytest.raises(KeyboardInterrupt, match="fractions interrupted after"):
        coincli.fractions(PAPER, samples=8192, batch=512, threads=1, progress=interrupt,
                          store=tmp_path / "f.zarr")
    kept = coincli.open_fractions(tmp_path / "f.zarr")
    assert int(kept["filled"].values.astype(bool).sum()) >= 2


def test_a_resumed_run_says_what_the_store_held(tmp_path):
    store = str(tmp_path / "f.zarr")
    args = ["fractions", "--store", store, "--batch", "1024", "--threads", "1"]
    first = CliRunner().invoke(app, [*args, "--samples", "2048"])
    assert first.exit_code == 0 and "were in the store already" not in first.output
    more = CliRunner().invoke(app, [*args, "--samples", "4096"])
    assert more.exit_code == 0, more.output
    assert "2,048 samples were in the store already" in " ".join(more.output.split())


# -- work refused for its cost before it starts, as a sweep is (issues 46, 48) ------------------
def test_a_continuation_of_weeks_is_refused_in_seconds_before_any_work(tmp_path):
    """coincli.fractions_over with 20,000 values: its pilot (a few hundred samples at three
    of them) estimates weeks, and the run is refused with WorkTooLong, the sweep's kind of
    refusal, before anything is created: in seconds, where it used to run for minutes."""
    import time

    values = np.linspace(0.0015, 0.0025, 20_000)
    start = time.perf_counter()
    with pytest.raises(coincli.WorkTooLong) as refused:  # months, on any machine
        coincli.fractions_over(PAPER, "thickness", values, precision=0.0005,
                               store=tmp_path / "f.zarr", threads=2)
    assert time.perf_counter() - start < 60
    est = refused.value.estimate
    assert est.seconds > 12 * 3600 and 0 < est.pilot_samples <= 3 * 512
    assert isinstance(refused.value, ParameterError)  # one line on the command line
    assert refused.value.parameters == ("max_seconds",)
    assert "would take about" in str(refused.value) and "max_seconds=None" in str(refused.value)
    assert not (tmp_path / "f.zarr").exists()
    assert issubclass(coincli.SweepTooLong, coincli.WorkTooLong)


def test_max_seconds_refuses_a_run_and_none_goes_ahead():
    """The keyword of coincli.sweep and coincli.basin: a run estimated over max_seconds is
    refused; max_seconds=None starts it without a pilot; a run no larger than its pilot is
    not piloted (the pilot would cost the run)."""
    with pytest.raises(coincli.WorkTooLong):
        coincli.fractions(PAPER, samples=2048, batch=512, threads=1, max_seconds=1e-6)
    seen = []
    plan = coincli.plan_fractions(PAPER, samples=2048, batch=512)
    r = coincli.run_fractions(plan, threads=1, max_seconds=None, on_start=seen.append)
    assert r.samples == 2048 and seen == [None]
    small = coincli.plan_fractions(PAPER, samples=512, batch=512)
    r = coincli.run_fractions(small, threads=1, max_seconds=1e-6, on_start=seen.append)
    assert r.samples == 512 and seen == [None, None]
    asked = coincli.run_fractions(small, threads=1, max_seconds=None, estimate=True,
                                  on_start=seen.append)
    assert asked.samples == 512 and seen[-1].pilot_samples == 512
    with pytest.raises(ParameterError, match="max_seconds must be a positive number"):
        coincli.fractions(PAPER, samples=512, batch=512, max_seconds=0)
    with pytest.raises(coincli.SweepTooLong):
        coincli.basin(PAPER, res=16, chunk=16, max_seconds=1e-9)


def test_the_command_line_refuses_a_long_run_in_one_line_unless_yes(monkeypatch):
    """--yes is the API's max_seconds=None: without it a run over the limit (lowered here from
    12 hours) is refused in one line, naming the way out."""
    from coincli.cli import fractions_cmd

    monkeypatch.setattr(fractions_cmd, "MAX_SECONDS", 1e-6)
    args = ["fractions", "--samples", "2048", "--batch", "512", "--threads", "1", "-q"]
    refused = CliRunner().invoke(app, args)
    err = refused.stderr.strip()
    assert refused.exit_code == 2 and len(err.splitlines()) == 1, refused.output
    assert err.startswith("error: this run would take about") and "--yes" in err, err
    assert CliRunner().invoke(app, [*args, "--yes"]).exit_code == 0
