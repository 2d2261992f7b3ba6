#!/usr/bin/env python
"""Does the paper's frictionless coin hold? The measurements of docs/friction.md.

    python benchmarks/friction.py --cost            # what a verified throw costs with friction
    python benchmarks/friction.py --stick           # the upper rungs' driver in a stick
    python benchmarks/friction.py --sensitivity     # how far the throws amplify a nudge
    python benchmarks/friction.py --slip            # is v_s small enough: the map at 4 v_s
    python benchmarks/friction.py --maps            # the default map at mu = 0, 0.1, 0.3, 0.6
    python benchmarks/friction.py --curves          # P(standing) over the 5-D box against mu
    python benchmarks/friction.py --crossings       # t/d at P(standing) = 1/3 against mu
    python benchmarks/friction.py --all --out out/friction   # everything (hours on 2 cores)
    python benchmarks/friction.py --render          # the tables of friction.json into the page

Each part writes its results into benchmarks/friction.json (merged: a part run alone keeps the
others), its table into docs/friction.md (between the page's markers, with the version, the machine
and the date) and its picture into docs/; the stores of the maps and of the Monte Carlo runs go to
``--out`` (default out/friction), so that a run interrupted resumes, and a second run of a finished
part computes nothing. ``--quick`` runs every part small (a smoke test: minutes).

**The cost** (``--cost``): CPU time of one thread for a verified throw, with friction against
without, on the same throws, in interleaved rounds (the median of each round's ratio): the
paper's map (16 x 16 throws over its default ranges) and the 5-D box of docs/fractions.md (its
first 256 Sobol throws), for mu = 0.1, 0.3, 0.6 and 1 at v_s = 1e-3 m/s (and 1e-4 at 0.3 and
1). Rows: the friction scene's verified ladder (``event_rodas``: Dormand-Prince where friction is
not stiff, Rodas5P where a corner sticks, a decade a rung), its single pass, and the ladder of
the explicit pairs alone with friction (``event`` then ``event_dop853``, as without friction: the
drivers derived here with the explicit pairs, :func:`coincli.jit.derive`; this module's kernels
make its kernel cache a folder of its own, compiled at its first run).

**The upper rungs in a stick** (``--stick``): single runs of the map on the upper rungs'
driver (DOP853; with friction its switching pair), and that pair made to step implicitly
wherever a corner pushes (:data:`IMPLICIT8`), at rtol 1e-8, 1e-10 and 1e-12.

**The sensitivity** (``--sensitivity``): why the ladder climbs further with friction, whatever
the method: each throw of the paper's map (32 x 32) at the ladder's floor, from its initial state
and from vphi0 nudged, counted where the runs fail the ladder's own agreement rule, with a
control (the other pair at the floor) and the verified ladder's climb on the same throws.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from coincli.integrators import adaptive, batch, dop853, dopri, switching  # noqa: E402
from coincli.integrators.pairs import (  # noqa: E402
    PAIR_NAMES,
    integrate_adaptive_dop853_rodas,
    integrate_adaptive_rodas,
)
from coincli.jit import derive  # noqa: E402
from coincli.models import paper as paper_law  # noqa: E402

# the explicit pairs alone, with friction: the adaptive driver as written (Dormand-Prince) and
# with DOP853, neither taking Rosenbrock steps nor limiting a step that slides into a stick, and
# the ladder runner whose friction dispatch runs them in place of the switching drivers
_EXPLICIT5 = derive(adaptive, "_explicit5", step_limit=paper_law.step_limit).integrate_adaptive
_EXPLICIT8 = derive(adaptive, "_explicit8", step_limit=paper_law.step_limit,
                    **{name: getattr(dop853, name) for name in PAIR_NAMES}).integrate_adaptive
EXPLICIT_LADDER = derive(batch, "_explicit", integrate_adaptive_rodas=_EXPLICIT5,
                         integrate_adaptive_dop853_rodas=_EXPLICIT8).run_ladder
assert dopri.ORDER == 5
# the upper rungs' switching pair made to take Rodas5P wherever a corner pushes with friction
# (its switch at h lambda > 0 rather than past the explicit pair's stability): --stick
_ALWAYS_RODAS = derive(switching, "_always_rodas", STIFF8=0.0)
IMPLICIT8 = derive(adaptive, "_implicit8", ORDER=switching.ORDER8, FIRST_STEP=dop853.FIRST_STEP,
                   step=_ALWAYS_RODAS.step8, step_factor=dop853.step_factor,
                   controller_memory=dop853.controller_memory,
                   dense_coefficients=_ALWAYS_RODAS.dense_coefficients8,
                   dense_point=dop853.dense_point).integrate_adaptive

RESULTS = HERE / "friction.json"
DOCS = HERE.parent / "docs"
MUS = (0.1, 0.3, 0.6, 1.0)
BOX = dict(y0="r:5r", phi0="-pi:pi", vx="-0.5:0.5")  # vy, vphi: the default ranges


# -- throws ----------------------------------------------------------------------------------------
def map_throws(scene, side: int) -> np.ndarray:
    """A side x side grid of the paper's map: vy0 in [0.05, 2] m/s, vphi0 in [-20, 20] rad/s."""
    from coincli.defaults import DEFAULT_RANGES

    (vy0, vy1), (w0, w1) = DEFAULT_RANGES["vy"], DEFAULT_RANGES["vphi"]
    vy, vphi = np.meshgrid(np.linspace(vy0, vy1, side), np.linspace(w0, w1, side),
                           indexing="ij")
    states = np.zeros((side * side, 6))
    states[:, 1] = scene.y0
    states[:, 4] = vy.ravel()
    states[:, 5] = vphi.ravel()
    return states


def box_throws(scene, samples: int) -> np.ndarray:
    from fractions_labels import box_throws as first

    return first(scene, samples)


# -- the cost --------------------------------------------------------------------------------------
def _runner(scene, states, explicit: bool = False):
    """A function that labels ``states`` as ``scene`` says (``explicit``: on the explicit pairs
    alone, up the frictionless ladder), returning the labels; its kernels loaded first."""
    from coincli.integrators.batch import new_control, unrecorded
    from coincli.integrators.ladder import ladder_of
    from coincli.labeller import Labeller, VerifiedLabels

    labeller = Labeller.of(scene)
    labeller.load(states[0])
    if not explicit:
        return lambda: labeller.label(states)
    ladder = ladder_of(scene.integration, stiff=False)
    kernel = labeller.kernels[EXPLICIT_LADDER]
    settings = labeller.settings

    def run():
        n = states.shape[0]
        out = VerifiedLabels(np.empty(n, np.int16), np.empty(n, np.uint8),
                             np.empty(n, np.float32), np.empty(n, np.int64),
                             np.empty(n, np.uint8), np.empty(n, np.int8))
        kernel(labeller.params, settings, np.asarray(ladder.methods, dtype=np.int64),
               np.asarray(ladder.rtols), np.asarray(ladder.dts),
               np.asarray([ladder.budget(k, settings.max_steps) for k in range(len(ladder))],
                          dtype=np.int64), float(ladder.change_tolerance),
               float(ladder.settle_tolerance), np.ascontiguousarray(states), *unrecorded(),
               *out, new_control())
        return out

    run()
    return run


def cost(quick: bool = False, rounds: int = 3) -> dict:
    """The cost table (module docstring)."""
    import coincli
    from coincli.enums import Certainty

    rows = []
    paper = coincli.load_preset("paper")
    sets = {"map": map_throws(paper, 8 if quick else 16),
            "box": box_throws(paper, 128 if quick else 256)}
    cases = [(mu, 1e-3) for mu in MUS] + [(0.3, 1e-4), (1.0, 1e-4)]
    for set_name, states in sets.items():
        frictionless = _runner(paper, states)
        frictionless_single = _runner(paper.with_overrides(verify=False), states)
        for mu, vs in cases:
            scene = paper.with_overrides(mu=mu, slip_velocity=vs)
            runs = {"verified (event_rodas)": _runner(scene, states),
                    "single pass (event_rodas, rtol 1e-6)": _runner(
                        scene.with_overrides(verify=False), states),
                    "verified, explicit pairs (event, event_dop853)": _runner(
                        scene, states, explicit=True)}
            times = {name: [] for name in (*runs, "frictionless", "frictionless single")}
            last = {}
            for r in range(rounds):
                order = list(runs.items()) + [("frictionless", frictionless),
                                              ("frictionless single", frictionless_single)]
                for name, run in (order if r % 2 == 0 else order[::-1]):
                    start = time.thread_time()
                    last[name] = run()
                    times[name].append(time.thread_time() - start)
            n = len(states)
            for name in runs:
                against = "frictionless single" if name.startswith("single") else "frictionless"
                ratio = statistics.median(a / b for a, b in zip(times[name], times[against],
                                                                strict=True))
                out = last[name]
                rows.append({
                    "throws": set_name, "n": n, "mu": mu, "v_s": vs, "row": name,
                    "us_per_throw": 1e6 * statistics.median(times[name]) / n,
                    "frictionless_us": 1e6 * statistics.median(times[against]) / n,
                    "ratio": ratio, "steps": float(np.mean(out.steps)),
                    "certain": float(np.mean(out.certainty == Certainty.CERTAIN)),
                    "uncertain": float(np.mean((out.certainty == Certainty.UNCERTAIN)
                                               | (out.certainty == Certainty.UNDECIDED)))})
                print(f"{set_name:3s} mu {mu:<4g} v_s {vs:g}  {name:48s} "
                      f"{rows[-1]['us_per_throw']:9.1f} us  x{ratio:6.2f}  "
                      f"certain {rows[-1]['certain']:.1%}", flush=True)
    return {"cost": rows}


# -- v_s -------------------------------------------------------------------------------------------
def slip(out: Path, quick: bool = False) -> dict:
    """The paper's map at mu = 0.3 for v_s = 1e-2, 1e-3, 1e-4, 1e-5: how many certain labels
    change between neighbouring v_s."""
    import coincli
    from coincli.enums import Certainty

    res = 32 if quick else 128
    paper = coincli.load_preset("paper")
    maps, rows = {}, []
    for vs in (1e-2, 1e-3, 1e-4, 1e-5):
        store = out / f"slip-{vs:g}-{res}.zarr"
        start = time.perf_counter()
        ds = coincli.basin(paper.with_overrides(mu=0.3, slip_velocity=vs), res=res,
                           store=store, max_seconds=None)
        maps[vs] = (np.asarray(ds["quarter_turns"].values),
                    np.asarray(ds["certainty"].values) == Certainty.CERTAIN)
        rows.append({"v_s": vs, "seconds": time.perf_counter() - start,
                     "certain": float(maps[vs][1].mean()),
                     "standing": float(np.nanmean(np.mod(maps[vs][0], 2) == 1))})
    pairs = []
    values = sorted(maps, reverse=True)
    for a, b in zip(values, values[1:], strict=False):
        (na, ca), (nb, cb) = maps[a], maps[b]
        both = ca & cb
        pairs.append({"from": a, "to": b, "both_certain": int(both.sum()),
                      "differ": int((both & (na != nb)).sum()),
                      "parity_differs": int((both & (np.mod(na, 2) != np.mod(nb, 2))).sum())})
    return {"slip": {"res": res, "mu": 0.3, "maps": rows, "neighbours": pairs}}


# -- the upper rungs in a stick -----------------------------------------------------------------
STICK_RTOLS = (1e-8, 1e-10, 1e-12)


def stick(quick: bool = False, rounds: int = 3) -> dict:
    """Where the upper rungs spend their steps: single runs of the paper's map (16 x 16 throws)
    at rtol 1e-8, 1e-10 and 1e-12, without friction on the frictionless ladder's upper rungs
    (DOP853), with it on the friction ladder's (``event_rodas``: Dormand-Prince 5(4) where
    friction is not stiff, Rodas5P past the explicit pair's stability) and on the
    eighth-order switching pair (``event_dop853_rodas``), and on that pair made to take Rodas5P
    wherever a corner pushes (:data:`IMPLICIT8`): whether a higher order, or an implicit step
    of order 5, would let the rungs past the second step over a stick. CPU time of one thread
    (each batch repeated for 0.1 s at least), interleaved rounds, medians (of the rounds'
    ratios for the ratios)."""
    import coincli
    from coincli.enums import Method
    from coincli.integrators.batch import integrate, unrecorded
    from coincli.labeller import Labeller, new_control

    paper = coincli.load_preset("paper")
    states = map_throws(paper, 8 if quick else 16)
    rows = []
    for mu in (0.3, 1.0):
        frictionless = Labeller.of(paper)
        labeller = Labeller.of(paper.with_overrides(mu=mu))
        runs = {"frictionless": (frictionless, frictionless.kernels[integrate]),
                "rodas5": (labeller, labeller.kernels[integrate_adaptive_rodas]),
                "switching": (labeller, labeller.kernels[integrate_adaptive_dop853_rodas]),
                "implicit": (labeller, labeller.kernels[IMPLICIT8])}
        for rtol in STICK_RTOLS:
            times = {name: [] for name in runs}
            steps = {}
            for r in range(rounds):
                for name, (owner, kernel) in (list(runs.items())[::1 if r % 2 == 0 else -1]):
                    settings = owner.settings._replace(method=int(Method.EVENT_DOP853),
                                                       rtol=rtol)
                    start = time.thread_time()
                    batches = 0
                    while batches == 0 or time.thread_time() - start < 0.1:  # a readable clock
                        total = 0
                        for state in states:
                            no_samples, no_events, final = unrecorded()
                            total += kernel(owner.params, settings, np.ascontiguousarray(state),
                                            no_samples, no_events, final, new_control()).steps
                        batches += 1
                    times[name].append((time.thread_time() - start) / batches)
                    steps[name] = total / len(states)
            rows.append({"mu": mu, "rtol": rtol, "n": len(states),
                         **{f"{name}_steps": steps[name] for name in runs},
                         **{f"{name}_us": 1e6 * statistics.median(times[name]) / len(states)
                            for name in runs},
                         **{f"{name}_ratio": statistics.median(
                             a / b for a, b in zip(times[name], times["frictionless"],
                                                   strict=True)) for name in runs}})
            print(f"mu {mu:g} rtol {rtol:g}: {rows[-1]}", flush=True)
    return {"stick": {"rows": rows}}


# -- the sensitivity ------------------------------------------------------------------------------
NUDGES = (2e-9, 2e-7, 2e-5)  # rad/s added to vphi0: 1e-10, 1e-8, 1e-6 of the map's fastest
# spin (20 rad/s)
SENSITIVITY_CASES = ((0.0, 1e-3), (0.1, 1e-3), (0.3, 1e-3), (0.6, 1e-3), (1.0, 1e-3),
                     (0.3, 1e-4), (1.0, 1e-4))


def sensitivity(out: Path, quick: bool = False) -> dict:
    """How far the throws themselves amplify a difference, whatever integrates them: each throw
    of the paper's map (32 x 32) run at the ladder's floor (its last rung, rtol 1e-12) from its
    initial state and from vphi0 nudged by 2e-9, 2e-7 and 2e-5 rad/s, and counted where the two
    runs fail the ladder's own agreement rule (:func:`coincli.integrators.batch.rungs_agree`:
    the same n, entering its well and settling at the same moments). The control: the same
    throw by the other pair at rtol 1e-12 (DOP853 against Dormand-Prince 5(4), each with
    Rodas5P where friction is stiff), which must fail the rule far more rarely than the nudges
    do for the counts to be the throws' and not the integration's. Beside them, the verified
    ladder's climb on the same throws: how many need a rung past its second."""
    import coincli
    from coincli.enums import Method, Status
    from coincli.integrators.batch import integrate, outcome_label, rungs_agree, unrecorded
    from coincli.labeller import Labeller, new_control

    side = 8 if quick else 32
    paper = coincli.load_preset("paper")
    states = map_throws(paper, side)
    rows = []
    for mu, vs in SENSITIVITY_CASES:
        scene = paper.with_overrides(mu=mu, slip_velocity=vs)
        labeller = Labeller.of(scene)
        labeller.load(states[0], trajectory=True)
        run_kernel, agree = labeller.kernels[integrate], labeller.python[rungs_agree]
        floor = labeller.rung_settings(len(labeller.ladder) - 1)
        other = {Method.EVENT_DOP853: Method.EVENT, Method.EVENT_RODAS: Method.EVENT_DOP853_RODAS}
        control = floor._replace(method=int(other[Method(floor.method)]))

        def run(state, settings, labeller=labeller, run_kernel=run_kernel):
            no_samples, no_events, final = unrecorded()
            result = run_kernel(labeller.params, settings, np.ascontiguousarray(state),
                                no_samples, no_events, final, new_control())
            return outcome_label(result.status, result.n_well, final[2]), result

        def differ(a, b, agree=agree, ladder=labeller.ladder):
            return not agree(a[0], a[1], b[0], b[1], ladder.change_tolerance,
                             ladder.settle_tolerance)

        start = time.perf_counter()
        reference = [run(state, floor) for state in states]
        moved = {}
        for nudge in NUDGES:
            nudged = states.copy()
            nudged[:, 5] += nudge
            moved[nudge] = sum(differ(a, run(state, floor))
                               for a, state in zip(reference, nudged, strict=True))
        controls = sum(differ(a, run(state, control))
                       for a, state in zip(reference, states, strict=True))
        verified = labeller.label(states)
        rows.append({"mu": mu, "v_s": vs, "n": len(states),
                     "moved": {f"{nudge:g}": int(count) for nudge, count in moved.items()},
                     "control": int(controls),
                     "settled": int(sum(a[1].status == Status.SETTLED for a in reference)),
                     "past_second_rung": int((verified.rung > 1).sum()),
                     "steps_at_floor": float(np.mean([a[1].steps for a in reference])),
                     "seconds": time.perf_counter() - start})
        print(f"mu {mu:g} v_s {vs:g}: {rows[-1]}", flush=True)
    return {"sensitivity": {"side": side, "nudges": list(NUDGES), "rows": rows}}


# -- the maps --------------------------------------------------------------------------------------
def maps(out: Path, quick: bool = False) -> dict:
    """The default map at mu = 0, 0.1, 0.3, 0.6, side by side (docs/friction-maps.png)."""
    import matplotlib.pyplot as plt

    import coincli
    from coincli.enums import Certainty
    from coincli.files import save_figure

    res = 64 if quick else 512
    paper = coincli.load_preset("paper")
    sets, rows = {}, []
    for mu in (0.0, 0.1, 0.3, 0.6):
        store = out / f"map-mu{mu:g}-{res}.zarr"
        ds = coincli.basin(paper.with_overrides(mu=mu), res=res, store=store,
                           max_seconds=None)
        sets[mu] = ds
    n0 = np.asarray(sets[0.0]["quarter_turns"].values)
    c0 = np.asarray(sets[0.0]["certainty"].values) == Certainty.CERTAIN
    fig, axes = plt.subplots(1, 4, figsize=(20, 5), layout="constrained")
    for ax, (mu, ds) in zip(axes, sets.items(), strict=True):
        n = np.asarray(ds["quarter_turns"].values)
        certain = np.asarray(ds["certainty"].values) == Certainty.CERTAIN
        both = certain & c0
        differ = float((both & (n != n0)).sum() / both.sum()) if both.any() else math.nan
        standing = float(np.mean(np.mod(n[certain], 2) == 1)) if certain.any() else math.nan
        rows.append({"mu": mu, "res": res, "certain": float(certain.mean()),
                     "differ_from_mu0": differ, "standing": standing})
        coincli.render_basin(ds, ax=ax, title=(f"mu = {mu:g}: {standing:.1%} standing; "
                                               f"{differ:.1%} differ from mu = 0"))
    save_figure(fig, DOCS / "friction-maps.png", 110)
    plt.close(fig)
    return {"maps": rows}


# -- P(standing) against mu ------------------------------------------------------------------------
CURVE_MUS = (0.0, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0)
THICKNESSES = {0.1: 0.002, 0.6: 0.012, 0.8: 0.016}  # t/d -> t (d = 2 cm)


def curves(out: Path, quick: bool = False) -> dict:
    """P(standing) over the 5-D box against mu at t/d = 0.1, 0.6, 0.8
    (docs/friction-pstanding.png)."""
    import matplotlib.pyplot as plt

    import coincli
    from coincli.files import save_figure

    samples = 512 if quick else 4_000
    paper = coincli.load_preset("paper")
    over = coincli.fractions_over(paper, over={"thickness": list(THICKNESSES.values()),
                                               "mu": list(CURVE_MUS)},
                                  samples=samples, store=out / f"curves-{samples}.zarr",
                                  max_seconds=None, **BOX)
    est = over.estimate("certain")  # (thickness, mu, 3)
    decided = over.estimate("decided")
    rows = []
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    for i, (ratio, _) in enumerate(THICKNESSES.items()):
        p, lo, hi = est[i].T
        ax.plot(CURVE_MUS, p, "o-", label=f"t/d = {ratio:g}")
        ax.fill_between(CURVE_MUS, lo, hi, alpha=0.25)
        for j, mu in enumerate(CURVE_MUS):
            result = over.results[i * len(CURVE_MUS) + j]
            rows.append({"t_over_d": ratio, "mu": mu, "p": float(p[j]), "low": float(lo[j]),
                         "high": float(hi[j]), "p_decided": float(decided[i, j, 0]),
                         "samples": int(result.samples),
                         "uncertain": float(result.uncertain["probability"])})
    ax.axhline(1 / 3, color="grey", lw=0.8, ls=":")
    ax.set_xlabel("friction coefficient mu")
    ax.set_ylabel("P(standing) (certain labels), 95 % interval")
    ax.set_title(f"The 5-D box, {samples:,} throws a point, v_s = 1e-3 m/s, c = 0.5 N s/m")
    ax.legend()
    save_figure(fig, DOCS / "friction-pstanding.png", 130)
    plt.close(fig)
    return {"curves": {"samples": samples, "rows": rows, "cost": over.cost}}


# -- the crossings ---------------------------------------------------------------------------------
CROSSING_MUS = (0.0, 0.3, 0.6)
CROSSING_RATIOS = (0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
BASES = ("certain", "decided")  # P(standing) over the certain labels, over all decided ones


def crossings(out: Path, quick: bool = False) -> dict:
    """t/d at P(standing) = 1/3 against mu at c = 0.5 and 4 N s/m, over the 5-D box, over the
    certain labels and over all decided ones (docs/thickness-damping.md gives both without
    friction)."""
    import coincli

    samples = 256 if quick else 2_000
    paper = coincli.load_preset("paper")
    rows = []
    for c in (0.5, 4.0):
        over = coincli.fractions_over(
            paper.with_overrides(c=c),
            over={"thickness": [0.02 * r for r in CROSSING_RATIOS], "mu": list(CROSSING_MUS)},
            samples=samples, store=out / f"crossings-c{c:g}-{samples}.zarr", max_seconds=None,
            **BOX)
        found = {basis: over.crossing(1 / 3, along="thickness", basis=basis) for basis in BASES}
        for j, mu in enumerate(CROSSING_MUS):
            uncertain = [over.results[i * len(CROSSING_MUS) + j].uncertain["probability"]
                         for i in range(len(CROSSING_RATIOS))]
            row = {"c": c, "mu": mu, "uncertain_max": float(max(uncertain))}
            for basis, at in found.items():
                row[basis] = [float(at[key][j]) / 0.02 for key in ("at", "from", "to")]
            rows.append(row)
        rows[-1]["cost"] = over.cost
    return {"crossings": {"samples": samples, "ratios": list(CROSSING_RATIOS), "rows": rows}}


# -- the tables of docs/friction.md ----------------------------------------------------------------
PAGE = DOCS / "friction.md"


def _x(value: float) -> str:
    return f"{value:.2g}" if value < 10 else f"{value:.0f}"


VERIFIED = "verified (event_rodas)"
SINGLE = "single pass (event_rodas, rtol 1e-6)"
EXPLICIT = "verified, explicit pairs (event, event_dop853)"


def cost_table(found: dict) -> str:
    """The stiffness table: a verified throw with friction as a multiple of one without."""
    rows = ["| throws | mu | v_s (m/s) | frictionless verified, us a throw | **verified "
            "(event_rodas)** | its single pass | verified, explicit pairs alone | certain "
            "(event_rodas) | steps a throw (event_rodas) |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    table: dict = {}
    for r in found["cost"]:
        table.setdefault((r["throws"], r["n"], r["mu"], r["v_s"]), {})[r["row"]] = r
    names = {"map": "the paper's map", "box": "the 5-D box"}
    for (throws, n, mu, vs), row in table.items():
        verified = row[VERIFIED]
        rows.append(f"| {names[throws]} ({n:,}) | {mu:g} | {vs:g} | "
                    f"{verified['frictionless_us']:.0f} | **{_x(verified['ratio'])} x** | "
                    f"{_x(row[SINGLE]['ratio'])} x | {_x(row[EXPLICIT]['ratio'])} x | "
                    f"{100 * verified['certain']:.1f} % | {verified['steps']:.0f} |")
    return "\n".join(rows)


def slip_table(found: dict) -> str:
    """The v_s table: the map at mu = 0.3 at each slip velocity, and neighbours compared."""
    slip = found["slip"]
    rows = [f"| v_s (m/s) | certain labels | standing (certain) | seconds ({slip['res']} x "
            f"{slip['res']} map) | certain in both with the next v_s | of them, n differs | "
            "of them, lying/standing differs |",
            "|---:|---:|---:|---:|---:|---:|---:|"]
    after = {pair["from"]: pair for pair in slip["neighbours"]}
    for m in slip["maps"]:
        pair = after.get(m["v_s"])
        tail = (f"{pair['both_certain']:,} (with {pair['to']:g}) | {pair['differ']:,} "
                f"({100 * pair['differ'] / max(pair['both_certain'], 1):.1f} %) | "
                f"{pair['parity_differs']:,}" if pair else "- | - | -")
        rows.append(f"| {m['v_s']:g} | {100 * m['certain']:.1f} % | "
                    f"{100 * m['standing']:.2f} % | {m['seconds']:.0f} | {tail} |")
    return "\n".join(rows)


def maps_table(found: dict) -> str:
    rows = ["| mu | certain labels | standing (of the certain) | certain labels that differ "
            "from mu = 0 (certain in both) |", "|---:|---:|---:|---:|"]
    for m in found["maps"]:
        rows.append(f"| {m['mu']:g} | {100 * m['certain']:.1f} % | "
                    f"{100 * m['standing']:.2f} % | {100 * m['differ_from_mu0']:.1f} % |")
    return "\n".join(rows)


def curves_table(found: dict) -> str:
    curves = found["curves"]
    ratios = sorted({r["t_over_d"] for r in curves["rows"]})
    rows = ["| mu | " + " | ".join(f"t/d = {t:g}: P(standing), 95 % interval (uncertain)"
                                   for t in ratios) + " |",
            "|---:|" + "---:|" * len(ratios)]
    for mu in sorted({r["mu"] for r in curves["rows"]}):
        cells = []
        for t in ratios:
            r = next(r for r in curves["rows"] if r["t_over_d"] == t and r["mu"] == mu)
            cells.append(f"{100 * r['p']:.1f} % ({100 * r['low']:.1f} to "
                         f"{100 * r['high']:.1f}) ({100 * r['uncertain']:.0f} %)")
        rows.append(f"| {mu:g} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def _crossing(at: list[float]) -> str:
    value, low, high = at
    if not math.isfinite(value):
        return "does not cross"
    ends = [f"{v:.3f}" if math.isfinite(v) else "?" for v in (low, high)]
    return f"{value:.3f} ({ends[0]} to {ends[1]})"


def crossings_table(found: dict) -> str:
    crossing = found["crossings"]
    rows = ["| c (N s/m) | mu | t/d at P = 1/3, certain labels | t/d at P = 1/3, all decided "
            "labels | uncertain, at most |", "|---:|---:|---:|---:|---:|"]
    for r in crossing["rows"]:
        rows.append(f"| {r['c']:g} | {r['mu']:g} | {_crossing(r['certain'])} | "
                    f"{_crossing(r['decided'])} | {100 * r['uncertain_max']:.0f} % |")
    return "\n".join(rows)


def sensitivity_table(found: dict) -> str:
    """The throws' sensitivity: a nudge of vphi0 against the ladder's rule, at the floor."""
    found = found["sensitivity"]
    nudges = [f"{nudge:g}" for nudge in found["nudges"]]
    rows = ["| mu | v_s (m/s) | " + " | ".join(f"vphi0 + {nudge} rad/s" for nudge in nudges)
            + " | the other pair (control) | verified: past the second rung | steps a run at "
            "the floor |", "|---:|---:|" + "---:|" * (len(nudges) + 3)]
    for r in found["rows"]:
        cells = [f"{100 * r['moved'][nudge] / r['n']:.1f} %" for nudge in nudges]
        rows.append(f"| {r['mu']:g} | {r['v_s']:g} | " + " | ".join(cells)
                    + f" | {100 * r['control'] / r['n']:.1f} % | "
                    f"{100 * r['past_second_rung'] / r['n']:.1f} % | {r['steps_at_floor']:.0f} |")
    return "\n".join(rows)


def stick_table(found: dict) -> str:
    """The upper rungs' driver with and without friction, and made implicit wherever a corner
    pushes."""
    rows = ["| mu | rtol | without friction (event_dop853): steps, us a throw | with friction, "
            "event_rodas (its ladder): steps, us (x without) | event_dop853_rodas | "
            "event_dop853_rodas with Rodas5P wherever a corner pushes |",
            "|---:|---:|---:|---:|---:|---:|"]
    for r in found["stick"]["rows"]:
        rows.append(f"| {r['mu']:g} | {r['rtol']:g} | {r['frictionless_steps']:.0f}, "
                    f"{r['frictionless_us']:.0f} | {r['rodas5_steps']:.0f}, "
                    f"{r['rodas5_us']:.0f} ({_x(r['rodas5_ratio'])} x) | "
                    f"{r['switching_steps']:.0f}, "
                    f"{r['switching_us']:.0f} ({_x(r['switching_ratio'])} x) | "
                    f"{r['implicit_steps']:.0f}, {r['implicit_us']:.0f} "
                    f"({_x(r['implicit_ratio'])} x) |")
    return "\n".join(rows)


TABLES = {"friction-cost": ("cost", cost_table), "friction-stick": ("stick", stick_table),
          "friction-sensitivity": ("sensitivity", sensitivity_table),
          "friction-slip": ("slip", slip_table), "friction-maps": ("maps", maps_table),
          "friction-curves": ("curves", curves_table),
          "friction-crossings": ("crossings", crossings_table)}


def render(found: dict) -> None:
    """Each measured part's table into docs/friction.md, between its markers, under the line
    saying which version measured it where and when."""
    from docs_tables import provenance, replace_between

    for marker, (part, table) in TABLES.items():
        if part in found:
            measured = dict(found["measured"][part], command=f"python benchmarks/friction.py "
                                                             f"--{part}")
            replace_between(PAGE, marker, provenance(measured) + "\n\n" + table(found))


# each part of the study, run with the command's arguments: the timed parts (no stores) take
# the rounds, the others write their stores under --out
PARTS = {"cost": lambda args: cost(args.quick, args.rounds),
         "sensitivity": lambda args: sensitivity(args.out, args.quick),
         "stick": lambda args: stick(args.quick, args.rounds),
         "slip": lambda args: slip(args.out, args.quick),
         "maps": lambda args: maps(args.out, args.quick),
         "curves": lambda args: curves(args.out, args.quick),
         "crossings": lambda args: crossings(args.out, args.quick)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    for part in (*PARTS, "all"):
        parser.add_argument(f"--{part}", action="store_true")
    parser.add_argument("--render", action="store_true",
                        help="only write the tables of benchmarks/friction.json into "
                             "docs/friction.md")
    parser.add_argument("--quick", action="store_true", help="every part small: a smoke test")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", type=Path, default=Path("out/friction"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    found = json.loads(RESULTS.read_text()) if RESULTS.exists() and not args.quick else {}
    if args.render:
        render(found)
        return
    parts = [p for p in PARTS if getattr(args, p) or args.all]
    for part in parts:
        start = time.perf_counter()
        result = PARTS[part](args)
        print(f"{part}: {time.perf_counter() - start:.0f} s", flush=True)
        found.update(result)
        if not args.quick:
            from docs_tables import machine

            from coincli.version import __version__

            measured = found.get("measured", {})
            measured = measured if all(isinstance(v, dict) for v in measured.values()) else {}
            measured[part] = {"version": __version__, "machine": machine(),
                              "date": time.strftime("%Y-%m-%d")}
            found["measured"] = measured
            RESULTS.write_text(json.dumps(found, indent=1, default=float))
            render(found)
        else:
            print(json.dumps(result, indent=1, default=float)[:3000])


if __name__ == "__main__":
    main()
