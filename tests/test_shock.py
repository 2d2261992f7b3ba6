"""The minimal shock (coincli.minimal_shock, `coin stability --shock`): the rest states come from
the model's forces, each reported value is checked on both sides against fixed-step RK4 at a
fine step (no event location), and the symmetries, the physics' limits and the JSON keys."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

import coincli
from coincli import ParameterError
from coincli.cli import app, stability_cmd
from coincli.enums import Certainty, Status
from coincli.models import PAPER, model_params
from coincli.shock import PRECISION, Kick, minimal_shock
from coincli.statics import analyse, rest

REFERENCE_DT = 2.5e-7  # s: the step of the RK4 reference (docs/verified-labels.md uses it too)
SIDE = 3e-4  # the reference runs kicks this far (relative) below and above each value


@pytest.fixture(scope="module")
def paper():
    return coincli.load_preset("paper")


@pytest.fixture(scope="module")
def shocks(paper):
    """Every state and kind on the paper's coin (the fast path: verified labels)."""
    return {(state, kind): minimal_shock(paper, state, kind)
            for state in ("standing", "lying") for kind in Kick}


@pytest.mark.parametrize("pose", ["lying", "standing"])
def test_the_rest_state_is_at_rest_in_the_model(paper, pose):
    """Two corners in contact carry m g between them: the model's accelerations vanish there
    (to rounding of g) and its energy is the one statics gives; the depth is E_crit minus it."""
    at_rest = rest(paper, pose)
    p = model_params(paper)
    python = PAPER.kernels("python")
    ax, ay, aphi = python.accelerations_auto(p, (0.0, at_rest.y, at_rest.phi, 0.0, 0.0, 0.0))
    assert abs(ax) < 1e-12 and abs(ay) < 1e-12 * paper.g
    assert abs(aphi) < 1e-9  # rad/s^2: cos(pi/2) is 6e-17, not 0
    energy = python.total_energy(p, (0.0, at_rest.y, at_rest.phi, 0.0, 0.0, 0.0))
    assert energy == pytest.approx(at_rest.energy, rel=1e-12)
    assert at_rest.depth == pytest.approx(paper.e_crit - energy, rel=1e-9)
    assert at_rest.quarter_turns == (1 if pose == "standing" else 0)
    if pose == "standing":
        assert at_rest.depth == pytest.approx(analyse(paper).standing_well_depth, rel=1e-12)


def reference_label(paper, found, factor: float, sign: int) -> int:
    """The count of quarter turns after the kick ``sign * factor * value``, by fixed-step RK4
    at REFERENCE_DT (the contact set taken at every stage: no event location), one pass."""
    run = coincli.simulate(paper.with_overrides(
        method="rk4", dt=REFERENCE_DT, verify=False, y0=found.rest.y, phi0=found.rest.phi,
        **{str(found.kick): sign * factor * found.value}))
    assert run.status == Status.SETTLED
    return run.quarter_turns


@pytest.mark.parametrize("state,kind", [("standing", "vphi"), ("lying", "vx")])
def test_each_value_against_rk4_on_both_sides(paper, shocks, state, kind):
    """A kick 0.03 % below the value keeps the coin in its well, 0.03 % above takes it to
    another, by RK4 at 2.5e-7 s, both signs."""
    found = shocks[state, kind]
    own = found.rest.quarter_turns
    for sign in (1, -1):
        assert reference_label(paper, found, 1 - SIDE, sign) == own
        assert reference_label(paper, found, 1 + SIDE, sign) != own


@pytest.mark.parametrize("state,kind", [("standing", "vphi"), ("standing", "vx"),
                                        ("lying", "vphi"), ("lying", "vx")])
def test_a_value_is_a_converged_bracket_of_certain_labels(paper, shocks, state, kind):
    found = shocks[state, kind]
    own = found.rest.quarter_turns
    low, high = found.bracket
    assert high == found.value and high - low <= PRECISION * high
    assert found.below.quarter_turns == own and found.below.certainty == Certainty.CERTAIN
    assert found.above.quarter_turns != own and found.above.certainty == Certainty.CERTAIN
    assert abs(found.below.kick) == low and abs(found.above.kick) == high
    # never below the static kick: with less energy the coin is below E_crit in its well
    assert found.static_kick < found.value and found.ratio == found.value / found.static_kick
    mass = paper.coin.inertia if kind == "vphi" else paper.coin.mass
    assert found.static_kick == pytest.approx(math.sqrt(2 * found.depth / mass), rel=1e-12)
    assert found.throws > 0 and found.steps > 0 and found.seconds > 0
    assert found.unit == ("rad/s" if kind == "vphi" else "m/s")


@pytest.mark.parametrize("state,kind", [("standing", "vphi"), ("standing", "vx"),
                                        ("lying", "vphi"), ("lying", "vx")])
def test_both_signs_agree_by_the_mirror_symmetry(shocks, state, kind):
    """x -> -x, phi -> -phi maps a kick of one sign on a coin at rest to the other's."""
    found = shocks[state, kind]
    plus, minus = found.searches
    assert (plus.sign, minus.sign) == (1, -1)
    assert found.signs_agree is True
    assert plus.value == pytest.approx(minus.value, rel=2 * PRECISION)
    # the mirror image of the well n is -n; a standing coin's n = 1 is also -1 + 2
    own = found.rest.quarter_turns
    assert plus.above.quarter_turns - own == -(minus.above.quarter_turns - own)


def test_the_paper_coin_values(shocks):
    """The values the docs print (docs/stability.md), to the bisection's precision."""
    expected = {("standing", "vphi"): 14.336, ("standing", "vx"): 0.037386,
                ("lying", "vphi"): 119.69, ("lying", "vx"): 3.3476}
    for key, value in expected.items():
        assert shocks[key].value == pytest.approx(value, rel=2e-4), key


@pytest.mark.parametrize("state", ["standing", "lying"])
def test_a_vertical_kick_never_tips_the_coin(shocks, state):
    """vy keeps the mirror symmetry of the rest pose: no value, and the reason says so; the
    scan up to the limit (1000 times the barrier's energy) finds no change of well."""
    found = shocks[state, "vy"]
    assert found.value is None and found.ratio is None and found.bracket is None
    assert "mirror symmetry" in found.reason and "no vertical kick up to" in found.note
    assert found.limit == pytest.approx(found.static_kick * math.sqrt(1000))
    for search in found.searches:
        assert search.value is None and not search.unsure
        assert search.scanned_to == pytest.approx(found.limit)
        assert search.below.quarter_turns == found.rest.quarter_turns
    assert {s.direction for s in found.searches} == {"up, off the foundation",
                                                    "down, into it"}


def test_a_label_not_certain_is_reported_not_bisected_through(paper):
    """With weak damping (c = 0.05) a lying coin rocks over several times near the threshold;
    in 2 % steps the bisection meets a kick whose label is uncertain and stops there: the
    value is the bracket's top, a certain leave, and the note names the kick."""
    found = minimal_shock(paper.with_overrides(c=0.05), "lying", "vphi", scan_step=1.02)
    for search in found.searches:
        (unsure,) = search.unsure
        low, high = search.bracket
        assert not search.converged and low < abs(unsure.kick) < high
        assert unsure.certainty == Certainty.UNCERTAIN and unsure.leaves is None
        assert search.above.certainty == Certainty.CERTAIN and search.value == high
    assert found.value == found.bracket[1]
    assert "uncertain, where the search stopped" in found.note


def test_a_vertical_kick_on_a_stiff_lightly_damped_foundation(paper):
    """There the symmetric bouncing is unstable and rounding errors grow into rocking: labels
    that are not certain stop the vertical scan, and no value is given."""
    found = minimal_shock(paper.with_overrides(k=1e5, c=0.1), "standing", "vy")
    assert found.value is None and "mirror symmetry" in found.reason
    for search in found.searches:
        assert search.unsure and search.unsure[0].certainty != Certainty.CERTAIN
        assert search.scanned_to < found.limit / 10
    assert "where the search stopped" in found.note


def test_no_standing_well_below_half_k_cr(paper):
    """Below k_cr / 2 a standing coin at rest is above E_crit: no label from it is certain."""
    soft = paper.with_overrides(k=150.0)
    found = minimal_shock(soft, "standing", "vphi")
    assert found.value is None and found.throws == 0
    assert "k <= k_cr / 2" in found.reason and found.depth < 0


def test_without_damping_no_kick_is_decided(paper):
    """With c = 0 nothing acts horizontally, and the energy of a kick above the static one
    never falls below E_crit: no value, no throw run."""
    undamped = paper.with_overrides(c=0.0, t_end=0.1)
    found = minimal_shock(undamped, "standing", "vx")
    assert found.value is None and found.throws == 0
    assert "no force acts horizontally" in found.reason
    found = minimal_shock(undamped, "lying", "vphi")
    assert found.value is None and found.throws == 0 and "energy is conserved" in found.reason


def test_options_are_checked(paper):
    with pytest.raises(ParameterError, match="state must be one of lying, standing"):
        minimal_shock(paper, "flying")
    with pytest.raises(ParameterError, match="kick must be one of vphi, vx, vy"):
        minimal_shock(paper, "lying", "vz")
    with pytest.raises(ParameterError, match="precision"):
        minimal_shock(paper, "lying", precision=0)
    with pytest.raises(TypeError, match="coincli.Scene"):
        minimal_shock("paper")


@pytest.mark.parametrize("options, words", [
    # issue 48: a list of states was `TypeError: unhashable type: 'list'`
    ({"state": ["standing"]}, "state must be one of lying, standing, got list ['standing']; "
                              "one a call"),
    ({"state": ("standing", "lying")}, "got tuple ('standing', 'lying'); one a call"),
    ({"state": {"standing": 1}}, "state must be one of lying, standing, got dict"),
    ({"state": None}, "state must be one of lying, standing, got None"),
    ({"state": 1}, "state must be one of lying, standing, got 1"),
    ({"kick": ["vphi", "vx"]}, "kick must be one of vphi, vx, vy, got list ['vphi', 'vx']; "
                               "one a call"),
    ({"kick": {"vphi"}}, "kick must be one of vphi, vx, vy, got set"),
    ({"kick": 2}, "kick must be one of vphi, vx, vy, got 2"),
    ({"precision": "0.01"}, "precision must be a number above 0, got '0.01'"),
    ({"scan_step": [2]}, "scan_step must be a number above 1, got list [2]"),
    ({"energy_limit": None}, "energy_limit must be a number above 1, got None"),
])
def test_options_of_a_wrong_type_are_a_parameter_error_in_api_words(paper, options, words):
    with pytest.raises(ParameterError) as caught:
        coincli.minimal_shock(paper, **options)
    assert words in str(caught.value) and "--" not in str(caught.value), str(caught.value)


def test_a_numpy_number_is_a_number(paper):
    found = minimal_shock(paper, "standing", "vx", precision=np.float32(0.01))
    assert found.value is not None and found.precision == pytest.approx(0.01)


def test_public_api_and_plain_result(shocks):
    found = shocks["standing", "vphi"]
    assert coincli.minimal_shock is minimal_shock and isinstance(found, coincli.MinimalShock)
    data = json.loads(json.dumps(found.to_dict(), allow_nan=False))
    assert data["kick"] == "vphi" and data["unit"] == "rad/s" and data["value"] == found.value
    assert data["below"]["certainty"] == "certain" and len(data["searches"]) == 2
    assert data["rest"]["pose"] == "standing" and "14.336 rad/s" in repr(found)


def test_cli_json_keys():
    result = CliRunner().invoke(app, ["stability", "--shock", "--json", "--k", "1e3",
                                      "--c", "5"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert set(data["shocks"]) == {"standing", "lying"}
    for state in ("standing", "lying"):
        assert set(data["shocks"][state]) == {"vphi", "vx", "vy"}
        assert data["shocks"][state]["vy"] is None
        for kind in ("vphi", "vx"):
            value = data["shocks"][state][kind]
            details = data["shock_details"][state][kind]
            assert value == details["value"] and value > details["static_kick"]
            assert details["signs_agree"] is True
    assert data["shock_units"] == {"vphi": "rad/s", "vx": "m/s", "vy": "m/s"}
    assert stability_cmd.KICKS == tuple(Kick)  # named there without importing the kernels
    assert data["parameters"]["foundation"] == {"k": 1e3, "c": 5.0}
    assert data["k_cr"] == data["k_cr_paper"] == pytest.approx(308.96, abs=0.01)


def test_cli_table_fits_80_columns():
    """The tables fit 80 columns, no cell cut short (the paragraphs are broken at a
    terminal's width only: tests/test_terminal.py)."""
    result = CliRunner().invoke(app, ["stability", "--shock"], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "…" not in out
    assert max(len(line) for line in out.splitlines() if line[:1] in "┏┃┡│└") <= 80
    for phrase in ("14.336 rad/s", "6.5477 rad/s", "2.189", "3.3476 m/s", "none (1)",
                   "mirror symmetry"):
        assert phrase in out, phrase
    assert "friction" not in out  # the paper's law: no friction to name
    # issue 48: the documentation site, not a path under docs/ that an installed package lacks
    from coincli.version import documentation

    assert "docs/" not in out and ".md" not in out, out
    assert f"The table explained: {documentation('stability', 'coin stability')}." in out
