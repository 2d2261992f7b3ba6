"""Decided, not timed out (issue 32): without a fixed horizon a run lasts until its outcome is
decided, within a cap that scales with the throw, and every label that is not certain says why:
undecided (a rung did not settle) or uncertain (decided, but the rungs disagree: chaotic)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import coincli
from coincli.charts.basin_render import UNCERTAIN, UNDECIDED, basin_rgba
from coincli.enums import Certainty, Status
from coincli.labeller import Labeller
from coincli.models import horizon_text, model_params, scene_horizon
from coincli.models.paper import CAP_FACTOR, decision_time
from coincli.params import ParameterError, validate
from coincli.stores.dataset import from_dataset

# the coin of the issue: d = 2 cm, t = 1 cm (t/d = 0.5), mass and inertia of a solid disc of the
# paper coin's density
HALF_MASS = 5 * math.pi * 1e-3
HALF = dict(thickness=0.01, mass=HALF_MASS, inertia=HALF_MASS * (3 * 0.01 ** 2 + 0.01 ** 2) / 12)


def test_no_horizon_by_default_and_the_cap_scales_with_the_throw():
    scene = coincli.load_preset("paper")
    assert scene.integration.t_end is None and not scene.fixed_horizon
    gentle = scene_horizon(scene.with_overrides(vy=0.1))
    hard = scene_horizon(scene.with_overrides(vy=2.0, vphi=20.0))
    assert gentle < hard  # more energy: longer flights to decide
    p = model_params(scene)
    state = (0.0, scene.y0, 0.0, 0.0, 2.0, 20.0)
    assert hard == pytest.approx(CAP_FACTOR * decision_time(p, state))
    # a fixed horizon is what it says, whatever the throw; paper-method keeps the paper's 2 s
    assert scene_horizon(scene.with_overrides(t_end=3.0, vy=2.0)) == 3.0
    assert scene_horizon(coincli.load_preset("paper-method")) == 2.0
    assert "until decided" in horizon_text(scene)
    assert horizon_text(scene.with_overrides(t_end=3.0)) == "t_end = 3 s"


def test_an_undamped_foundation_needs_a_fixed_horizon():
    with pytest.raises(ParameterError, match="c = 0.*give t_end"):
        validate(coincli.load_preset("paper").with_overrides(c=0.0))
    validate(coincli.load_preset("undamped"))  # its preset fixes t_end


def test_half_thick_coin_settles_everywhere_and_counts_uncertain_cells_by_cause():
    """The issue's coin, 32 x 32 default ranges: at t_end = 2 s 51 cells are still moving and
    their labels undecided; by default none is, and every uncertain cell is chaotic."""
    scene = coincli.load_preset("paper").with_overrides(**HALF)
    stats = coincli.basin_stats(coincli.basin(scene, res=32, threads=1))
    assert stats["status"]["unsettled"] == 0 and stats["status"]["settled"] == 1024
    uncertain = stats["uncertain"]
    assert uncertain["undecided"] == 0
    assert uncertain["chaotic"] == uncertain["count"] > 100  # honest: set below double precision
    assert stats["decided"]["count"] == 1024

    cut_map = coincli.basin(scene.with_overrides(t_end=2.0), res=32, threads=1)
    cut = coincli.basin_stats(cut_map)
    moving = cut["status"]["unsettled"]
    assert moving > 20
    assert cut["uncertain"]["undecided"] >= moving  # a cell still moving is never certain
    assert cut["uncertain"]["chaotic"] + cut["uncertain"]["undecided"] == \
        cut["uncertain"]["count"]
    assert cut["decided"]["count"] == 1024 - moving

    # the map draws the two causes apart: undecided cells darker than chaotic ones (those
    # still moving at the end in the colour of unsettled cells)
    rgba, classes = basin_rgba(from_dataset(cut_map))
    assert classes["uncertain"].sum() == cut["uncertain"]["chaotic"]
    assert classes["undecided"].sum() == cut["uncertain"]["undecided"] - moving > 0
    assert (rgba[classes["undecided"]] == UNDECIDED).all()
    assert (rgba[classes["uncertain"]] == UNCERTAIN).all()


def _ladder_certainty(scene, states):
    return Labeller.of(scene).label(np.asarray(states, dtype=np.float64))


def test_a_budget_too_small_makes_labels_undecided_not_chaotic():
    scene = coincli.load_preset("paper")
    state = [0.0, scene.y0, 0.0, 0.0, 1.5, 10.0]
    free = _ladder_certainty(scene, [state])
    assert free.certainty[0] == Certainty.CERTAIN and free.status[0] == Status.SETTLED
    starved = _ladder_certainty(scene.with_overrides(max_steps=5), [state])
    assert starved.status[0] == Status.BUDGET
    assert starved.certainty[0] == Certainty.UNDECIDED
    cut = _ladder_certainty(scene.with_overrides(t_end=0.01), [state])
    assert cut.status[0] == Status.UNSETTLED and cut.certainty[0] == Certainty.UNDECIDED


def test_simulate_says_why_a_label_is_not_certain():
    scene = coincli.load_preset("paper").with_overrides(vy=1.5, vphi=10.0)
    tr = coincli.simulate(scene.with_overrides(t_end=0.01))
    assert tr.certainty == Certainty.UNDECIDED
    out = tr.summary()
    assert out["certainty"] == "undecided" and "did not decide" in out["certainty_reason"]
    assert out["horizon"] == 0.01
    assert any("undecided" in note for note in tr.notes)
    free = coincli.simulate(scene)
    assert free.settled and free.summary()["horizon"] > free.settle_time


def test_fractions_report_the_decided_estimate_and_the_causes():
    scene = coincli.load_preset("paper").with_overrides(**HALF)
    r = coincli.fractions(scene, samples=512, vy=(0.05, 2.0), vphi=(-20.0, 20.0), threads=1)
    d = r.all_decided
    assert d["decided"] == r.status.get("settled", 0) == 512
    assert r.counted <= d["decided"]
    u = r.uncertain
    assert u["chaotic"] + u["undecided"] == u["count"] > 0
    assert "all_decided" in r.to_dict()


def test_an_old_store_is_refused_with_a_clear_message(tmp_path):
    import json

    from coincli.stores.basin_schema import FORMAT

    scene = coincli.load_preset("paper")
    store = tmp_path / "b.zarr"
    coincli.basin(scene, res=8, store=store, threads=1)
    meta = store / "zarr.json"
    data = json.loads(meta.read_text())
    data["attributes"]["coin_basin"]["format"] = FORMAT - 1
    meta.write_text(json.dumps(data))
    with pytest.raises(ParameterError, match=f"format {FORMAT - 1}.*reads format {FORMAT}"):
        coincli.basin_stats(store)
