"""`coincli.analyze` and `coin basin analyze`: the boundary measures of a coin basin, whole and
by band, with the perturbation method run on the simulator's verified labels. (The estimators'
known answers are in test_boundary.py; here: the coin-specific plumbing, on small maps.)"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import coincli
from coincli.analysis import (
    AnalysisOptions,
    VerifiedClassifier,
    base_state_of,
    evidence_mask,
    scene_of,
)
from coincli.boundary import LOG2
from coincli.cli import app
from coincli.enums import Certainty, Status
from coincli.labeller import Labeller
from coincli.params import ParameterError

# A chaotic corner of the default map (vy0 1.2-2 m/s): every measure has something to measure.
REGION = dict(vy=(1.2, 2.0), vphi=(4.0, 12.0), res=40)
FAST = dict(box=4, bands=2, points=400, eps=(1e-6, 1e-5, 1e-4, 1e-3), balls=200, radius=3,
            threads=2)
KEYS = ("basin_entropy", "boundary_basin_entropy", "box", "fractal_boundary", "fractal_test",
        "uncertainty_exponent", "uncertainty_exponent_interval", "boundary_dimension", "wada",
        "uncertain_fraction")


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    path = tmp_path_factory.mktemp("analyze") / "chaotic.zarr"
    coincli.basin(coincli.load_preset("paper"), store=path, **REGION)
    return path


@pytest.fixture(scope="module")
def result(store):
    return coincli.analyze(store, **FAST)


def test_whole_and_bands_with_every_measure(result):
    assert len(result.bands) == 2 and result.verified
    w = result.whole
    # 40 rows in boxes of 4: 10 box rows, 5 per band
    assert [b.rows for b in result.bands] == [(0, 20), (20, 40)]
    assert result.bands[0].span[0] == 1.2 and result.bands[-1].span[1] == 2.0
    assert result.bands[0].span[1] == pytest.approx(result.bands[1].span[0])
    assert w.entropy.boxes == sum(b.entropy.boxes for b in result.bands)
    assert w.entropy.boundary_basin_entropy > LOG2 and w.entropy.fractal_boundary
    assert w.fractal_test is not None and w.fractal_test.verdict in ("fractal", "smooth")
    assert w.wada.n_classes >= 3
    # the perturbation points are split between the bands and pooled for the whole map
    pw = w.perturbation
    assert pw.n_points == FAST["points"] == sum(b.perturbation.n_points for b in result.bands)
    np.testing.assert_array_equal(pw.uncertain, sum(b.perturbation.uncertain
                                                    for b in result.bands))
    assert np.all(pw.evidence + pw.excluded == FAST["points"])
    assert np.all(np.diff(pw.fraction) > 0)  # more points change outcome at larger eps
    assert 0.0 < w.alpha < 1.2 and w.exponent.boundary_dimension == pytest.approx(2 - w.alpha)
    assert 0.0 <= w.uncertain_fraction < 0.2
    assert result.trajectories == FAST["points"] * (1 + 2 * len(FAST["eps"]))
    assert set(result.seconds) == {"map", "perturbation", "total"}


def test_json_has_the_issue_keys_whole_and_per_band(result):
    data = json.loads(json.dumps(coincli_jsonable(result.to_dict()), allow_nan=False))
    for region in (data, *data["bands"]):
        for key in KEYS:
            assert key in region, key
        assert region["box"] == [4, 4]
        assert isinstance(region["fractal_boundary"], bool) and isinstance(region["wada"], bool)
        assert isinstance(region["fractal_test"]["fractal"], bool)
        lo, hi = region["uncertainty_exponent_interval"]
        assert lo <= region["uncertainty_exponent"] <= hi
        assert region["boundary_dimension"] == pytest.approx(2 - region["uncertainty_exponent"])
        assert len(region["perturbation"]["fraction"]) == 4
        assert len(region["perturbation"]["local_exponents"]) == 3
    assert data["band_axis"] == "vy" and data["verified"] is True
    assert data["settings"]["eps"] == list(FAST["eps"])


def coincli_jsonable(value):
    from coincli.jsonable import jsonable

    return jsonable(value)


def test_classifier_gives_the_verified_labels_on_any_thread_count(store):
    ds = coincli.open_basin(store)
    scene = scene_of(coincli.basin_attrs(ds))
    labeller = Labeller.of(scene)
    base = base_state_of(coincli.basin_attrs(ds))
    assert base[0] == 0.0 and base[2] == 0.0 and base[1] == pytest.approx(scene.coin.r)
    # the store's own cells: the classifier at cell centres reproduces the stored labels
    vy, vphi = ds["vy"].values, ds["vphi"].values
    pts = np.column_stack([np.repeat(vy[:5], 40), np.tile(vphi, 5)])
    with VerifiedClassifier(labeller, base, [4, 5], threads=2) as classify:
        lab2, cert2 = classify(pts)
    with VerifiedClassifier(labeller, base, [4, 5], threads=1) as classify:
        lab1, cert1 = classify(pts)
    np.testing.assert_array_equal(lab1, lab2)
    np.testing.assert_array_equal(cert1, cert2)
    stored = ds["quarter_turns"].values[:5].ravel()
    np.testing.assert_array_equal(lab2, stored)
    np.testing.assert_array_equal(cert2, ds["certainty"].values[:5].ravel() == Certainty.CERTAIN)
    direct = labeller.label(VerifiedClassifier(labeller, base, [4, 5]).states(pts))
    np.testing.assert_array_equal(direct.quarter_turns, lab2)


def test_only_certain_cells_are_evidence():
    q = np.array([[0, 2], [4, -2]], dtype=np.int16)
    status = np.array([[Status.SETTLED, Status.SETTLED], [Status.UNSETTLED,
                                                          Status.NOT_COMPUTED]], dtype=np.uint8)
    cert = np.array([[Certainty.CERTAIN, Certainty.UNCERTAIN], [Certainty.CERTAIN,
                                                                Certainty.NOT_COMPUTED]],
                    dtype=np.uint8)
    np.testing.assert_array_equal(evidence_mask(q, status, cert, True),
                                  [[True, False], [True, False]])
    single = np.array([[Certainty.UNVERIFIED] * 2, [Certainty.UNVERIFIED,
                                                    Certainty.NOT_COMPUTED]], dtype=np.uint8)
    np.testing.assert_array_equal(evidence_mask(q, status, single, False),
                                  [[True, True], [False, False]])


def test_uncertain_and_missing_cells_are_left_out(store):
    ds = coincli.open_basin(store).copy(deep=True)
    ds["certainty"].values[:8, :] = Certainty.UNCERTAIN
    ds["status"].values[-4:, :] = Status.NOT_COMPUTED
    ds["certainty"].values[-4:, :] = Certainty.NOT_COMPUTED
    r = coincli.analyze(ds, box=4, bands=2, points=0, balls=100, radius=3)
    certain = int((coincli.open_basin(store)["certainty"].values[8:-4]
                   == Certainty.CERTAIN).sum())
    assert r.whole.evidence_cells == certain
    assert r.whole.entropy.excluded_boxes >= 10 * 3  # 3 rows of boxes out of 10 are excluded
    assert r.whole.perturbation is None and r.whole.exponent is None
    assert r.whole.to_dict("vy")["uncertainty_exponent"] is None


def test_a_single_outcome_has_no_boundary(tmp_path):
    ds = coincli.basin(coincli.load_preset("paper"), vy=(0.05, 0.3), vphi=(-2.0, 2.0), res=24)
    assert np.unique(ds["quarter_turns"].values).tolist() == [0]
    r = coincli.analyze(ds, box=4, bands=1, points=100, eps=(1e-6, 1e-3), balls=100, radius=3)
    w = r.whole
    assert w.entropy.basin_entropy == 0 and math.isnan(w.entropy.boundary_basin_entropy)
    assert not w.entropy.fractal_boundary and w.fractal_test.verdict == "undetermined"
    assert math.isnan(w.alpha) and w.exponent.reason and not w.wada.is_wada
    assert np.all(w.perturbation.uncertain == 0)


def test_unverified_store_uses_settled_labels():
    scene = coincli.load_preset("paper").with_overrides(verify=False)
    ds = coincli.basin(scene, vy=(1.2, 2.0), vphi=(4.0, 12.0), res=24)
    r = coincli.analyze(ds, box=4, bands=1, points=100, eps=(1e-5, 1e-3), balls=100, radius=3)
    assert not r.verified and r.to_dict()["verified"] is False
    assert r.whole.evidence_cells == int((ds["status"].values == Status.SETTLED).sum())
    assert r.whole.perturbation.evidence.sum() > 0


def test_options_are_checked():
    with pytest.raises(ParameterError, match="^bands must be between"):
        AnalysisOptions(box=5, bands=20).check((40, 40))
    with pytest.raises(ParameterError, match="^box must be between"):
        AnalysisOptions(box=50).check((40, 40))
    with pytest.raises(ParameterError, match="eps"):
        AnalysisOptions(eps=(1e-3,)).check((40, 40))


# -- the command line --------------------------------------------------------------------------
def run(*args):
    return CliRunner().invoke(app, [str(a) for a in args])


CLI_FAST = ("--box", "4", "--bands", "2", "--points", "200", "--eps", "1e-6:1e-3",
            "--eps-values", "3", "--balls", "200", "--radius", "3", "-q")


def test_cli_json_and_figures(store, tmp_path):
    png, svg = tmp_path / "a.png", tmp_path / "a.svg"
    res = run("basin", "analyze", store, *CLI_FAST, "--json", "-o", png)
    assert res.exit_code == 0, (res.stdout, res.stderr)
    data = json.loads(res.stdout)
    for key in KEYS:
        assert key in data and all(key in band for band in data["bands"])
    assert data["figure"] == str(png) and png.stat().st_size > 10_000
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    res = run("basin", "analyze", store, *CLI_FAST, "-o", svg)
    assert res.exit_code == 0, (res.stdout, res.stderr)
    assert svg.read_text().lstrip().startswith("<?xml") and "Basin entropy" in res.stdout
    assert "log-2 criterion" in res.stdout and "ball test" in res.stdout
    assert "Uncertainty exponent" in res.stdout and "took" in res.stdout


@pytest.mark.parametrize("args, fragment", [
    (("--eps", "1e-3:1e-6"), "empty range"),
    (("--eps", "0:1e-3"), "0 < LO < HI"),
    (("--eps-values", "1"), "--eps-values"),
    (("-o", "fig.jpg"), ".png, .svg or .pdf"),
    (("--bands", "999"), "--bands"),
])
def test_cli_bad_options_are_one_line_errors(store, tmp_path, args, fragment):
    res = run("basin", "analyze", store, "--points", "0", "-q", *args)
    assert res.exit_code == 2, (res.stdout, res.stderr)
    err = res.stderr.strip()
    assert err.startswith("error:") and len(err.splitlines()) == 1 and fragment in err, err


def test_cli_missing_store(tmp_path):
    res = run("basin", "analyze", tmp_path / "nothing.zarr", "-q")
    assert res.exit_code == 2 and res.stderr.startswith("error:")
