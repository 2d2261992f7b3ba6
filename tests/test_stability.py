"""`coin stability` reproduces the paper's section 3 figures (eqs. 7-13, NOTES.md)."""

from __future__ import annotations

import json
import math

import pytest
from typer.testing import CliRunner

from coincli import simulate
from coincli.cli import app
from coincli.enums import Status
from coincli.presets import load
from coincli.statics import analyse

runner = CliRunner()


def invoke(*args):
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, (result.stdout, result.stderr, result.exception)
    return result


def words(text: str) -> str:
    """The text with every run of whitespace (rich's line wrapping included) made one space."""
    return " ".join(text.split())


def test_paper_figures_from_analyse():
    rep = analyse(load("paper").scene.with_overrides(verify=False))
    assert f"{rep.rigid.ratio:.1f}" == "181.4"
    assert f"{rep.elastic.ratio:.1f}" == "187.2"
    assert f"{rep.k_min:.1f}" == "154.9"
    assert f"{rep.k_cr:.2f}" == "308.96"
    assert math.degrees(rep.phi_cr) == pytest.approx(84.289, abs=1e-3)
    assert rep.lying_static and rep.standing_static and rep.single_corner_contact


def test_formulas_independently():
    """Eqs. 8-13 recomputed from the raw numbers (eq. 13 with the denominator 2 (r - r_d))."""
    m, g, k = math.pi * 1e-3, 9.81, 1.0e4
    r_d, r_t = 0.01, 0.001
    r = math.hypot(r_d, r_t)
    w = m * g
    rep = analyse(load("paper").scene.with_overrides(verify=False))
    assert rep.rigid.v_max == pytest.approx(w * r, rel=1e-14)
    assert rep.rigid.v_min1 == pytest.approx(w * r_t, rel=1e-14)
    assert rep.rigid.v_min2 == pytest.approx(w * r_d, rel=1e-14)
    assert rep.rigid.ratio == pytest.approx((r - r_t) / (r - r_d), rel=1e-12)
    sink = w / (2 * k)
    assert rep.elastic.v_max == pytest.approx(w * (r - w / k), rel=1e-14)
    assert rep.elastic.v_min1 == pytest.approx(w * (r_t - sink), rel=1e-14)
    assert rep.elastic.v_min2 == pytest.approx(w * (r_d - sink), rel=1e-14)
    assert rep.elastic.ratio == pytest.approx((r - w / k - r_t + sink) / (r - w / k - r_d + sink),
                                              rel=1e-12)
    assert rep.k_min == pytest.approx(w * r / (2 * r_t ** 2), rel=1e-14)
    assert rep.k_cr == pytest.approx(w / (2 * (r - r_d)), rel=1e-14)
    assert rep.k_cr > 0
    assert rep.e_crit == pytest.approx(w * (r - w / (2 * k)), rel=1e-14)


def test_paper_figures_from_cli_json():
    data = json.loads(invoke("stability", "--json").stdout)
    assert round(data["rigid"]["ratio"], 1) == 181.4
    assert round(data["elastic"]["ratio"], 1) == 187.2
    assert round(data["k_min"], 1) == 154.9
    assert round(data["k_cr"], 2) == 308.96
    assert data["standing_static"] is True and data["lying_static"] is True
    assert data["e_crit"] == pytest.approx(load("paper").scene.e_crit, rel=1e-14)
    assert data["parameters"]["coin"]["mass"] == pytest.approx(math.pi * 1e-3)


def test_paper_figures_in_the_table():
    out = words(invoke("stability").stdout)
    for figure in ("181.4", "187.2", "154.9 N/m", "308.96 N/m"):
        assert figure in out
    assert "cannot be at rest" not in out


def test_soft_foundation_says_no_coin_can_stand():
    scene = load("soft").scene.with_overrides(verify=False)
    assert scene.foundation.k < analyse(scene).k_cr
    rep = analyse(scene)
    assert not rep.standing_static and rep.lying_static
    out = words(invoke("stability", "--preset", "soft").stdout)
    assert "a standing coin cannot be at rest" in out
    assert "standing (phi = pi/2): static" not in out
    data = json.loads(invoke("stability", "--preset", "soft", "--json").stdout)
    assert data["standing_static"] is False


def test_k_override_below_k_cr():
    out = words(invoke("stability", "--k", "300").stdout)
    assert "a standing coin cannot be at rest" in out
    out = words(invoke("stability", "--k", "320").stdout)
    assert "cannot be at rest" not in out


def test_mass_of_3_14_grams():
    """NOTES.md: the text's 3.14 g gives k_min 154.8 and k_cr 308.8; the ratios do not change."""
    data = json.loads(invoke("stability", "--mass", "3.14e-3", "--json").stdout)
    assert round(data["k_min"], 1) == 154.8
    assert round(data["k_cr"], 1) == 308.8
    assert round(data["rigid"]["ratio"], 1) == 181.4
    assert round(data["elastic"]["ratio"], 1) == 187.2
    out = words(invoke("stability", "--mass", "3.14e-3").stdout)
    assert "154.8 N/m" in out


@pytest.mark.parametrize("k,stays", [(250.0, True), (170.0, True), (140.0, False)])
def test_standing_rest_below_k_cr_follows_the_exact_energies(k, stays):
    """The paper's k_cr = 309 N/m compares centroid heights only. With the springs' energy
    counted, a standing coin keeps a well for k > k_cr / 2 = 154.5 N/m: a standing coin nudged
    at k = 250 or 170 N/m stays standing, at 140 N/m it falls."""
    scene = load("paper").scene.with_overrides(verify=False).with_overrides(k=k)
    rep = analyse(scene)
    assert (rep.standing_well_depth > 0) is stays
    assert rep.k_stand_exact == pytest.approx(rep.k_cr / 2)
    weight = scene.coin.mass * scene.g
    run = scene.with_overrides(y0=scene.coin.r_d - weight / (2 * k), phi0=math.pi / 2,
                               vphi=0.01, t_end=1.0, stop_on_settle=False)
    tr = simulate(run)
    assert tr.status == Status.SETTLED
    assert (tr.quarter_turns == 1) is stays
    out = words(invoke("stability", "--k", str(k)).stdout)
    assert "a standing coin cannot be at rest" in out
    assert ("shallow standing well" in out) is stays


def test_k_cr_is_labelled_as_the_papers_and_the_models():
    """docs/model.md, section 9: the paper's printed k_cr (eq. 13) is twice the threshold the
    model uses. Both are printed, each labelled, in the table, the JSON and the report."""
    out = words(invoke("stability").stdout)
    assert "k_cr (paper, eq. 13) │ 308.96 N/m" in out and "twice too high" in out
    assert "k_cr / 2 (model) │ 154.48 N/m" in out
    data = json.loads(invoke("stability", "--k", "250", "--json").stdout)
    assert data["k_cr"] == data["k_cr_paper"] == pytest.approx(308.96, abs=0.005)
    assert data["k_cr_model"] == data["k_stand_exact"] == pytest.approx(data["k_cr"] / 2)
    assert data["standing_static"] is False and data["standing_static_model"] is True
    assert "twice too high" in data["k_cr_note"] and "k_cr_model" in data["k_cr_note"]
    out = words(invoke("stability", "--k", "250").stdout)
    assert "standing (phi = pi/2): static in the model (k > k_cr / 2), not by the paper's" in out
    assert "below the paper's k_cr = 308.96 N/m" in out
    report = analyse(load("paper").scene.with_overrides(verify=False, k=250.0))
    assert "standing (k > k_cr / 2; not by the paper's k_cr)" in repr(report)
    assert "k_cr / 2 (model)" in repr(report) and "k_cr (paper, eq. 13)" in repr(report)
