"""How the verification ladder was chosen: certain-and-wrong and uncertain cells of candidate
ladders, on the robust cells of a grid (where two independent converged references agree).

For every cell of a (vy0, vphi0) grid it runs the event method once at each tolerance of a
long ladder, and DOP853 (``event_dop853``) at each from 1e-6 down, and keeps each run's label,
status, steps and the time of its last change of well; then it replays candidate designs (first
rung, floor, agreement rule, the pair of the rungs past the first) on those runs, so that every
design is judged on the same trajectories. The default ladder's cost is then measured through
the real kernel against the same ladder on Dormand-Prince 5(4) alone, interleaved, one thread
(steps of the two pairs cost different amounts). The references are the event method at rtol
1e-12 and fixed-step RK4 at h = 2.5e-7 (no shared stepping code); "wrong" is judged against
RK4. RK4 is slow (about a second a cell on the thick coin): its labels are saved beside the
output and reused when the same grid is asked again.

    python benchmarks/ladder_design.py --preset paper --res 64     # about 30 min on 2 cores
    python benchmarks/ladder_design.py --preset thick --res 32     # about an hour
    python benchmarks/ladder_design.py --preset paper --box 1024   # throws of the 5-D box

``--box N`` replaces the grid by N seeded random throws over the 5-D box of docs/fractions.md
of ``coin fractions`` (y0 r:5r, phi0 over a full turn, vx within 0.5 m/s, the default vy0 and
vphi0 ranges): throws no design was chosen on.

Prints the table docs/verified-labels.md quotes, and writes it to
benchmarks/ladder-<preset>-<res>.json.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from coincli.enums import Method  # noqa: E402  (light: no numpy, no numba)

RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
DOP853_RTOLS = RTOLS[1:]
EVENT, DOP853 = Method.EVENT, Method.EVENT_DOP853
DESIGNS = [  # (first rung, floor, change tolerance, settle tolerance in s (inf: not compared),
    # the method of the rungs past the first, and their first rtol (None: a decade down))
    (1e-6, 1e-10, np.inf, np.inf, EVENT, None), (1e-6, 1e-10, 1e-3, np.inf, EVENT, None),
    (1e-6, 1e-12, np.inf, np.inf, EVENT, None), (1e-6, 1e-12, 1e-2, np.inf, EVENT, None),
    (1e-6, 1e-12, 1e-3, np.inf, EVENT, None), (1e-6, 1e-12, 1e-4, np.inf, EVENT, None),
    (1e-5, 1e-12, 1e-3, np.inf, EVENT, None), (1e-6, 1e-12, 1e-3, 1e-2, EVENT, None),
    (1e-6, 1e-12, 1e-3, 1e-3, EVENT, None), (1e-6, 1e-12, np.inf, 1e-3, EVENT, None),
    (1e-6, 1e-12, 1e-3, 1e-2, DOP853, None), (1e-6, 1e-12, 1e-3, 1e-2, DOP853, 1e-8),
    (1e-6, 1e-12, 1e-3, 1e-2, DOP853, 1e-9), (1e-5, 1e-12, 1e-3, 1e-2, DOP853, 1e-8)]
BOX = {"y0": "r:5r", "phi0": "-pi:pi", "vx": "-0.5:0.5"}  # the 5-D box of docs/fractions.md


def runs(scene, states, rtols=RTOLS):
    """Per rtol and cell: label, status, steps, last change of well, settle time (one compiled
    call each), with the scene's method."""
    from coincli.integrators import new_control
    from coincli.integrators.batch import integrate, outcome_label, unrecorded
    from coincli.labeller import Labeller

    labeller = Labeller.of(scene)
    p, base = labeller.params, labeller.settings
    kernel = labeller.kernels[integrate]
    no_samples, no_events, final = unrecorded()
    control = new_control()
    out = {name: np.empty((len(rtols), len(states))) for name in ("q", "st", "steps", "tc", "ts")}
    for k, rtol in enumerate(rtols):
        settings = base._replace(rtol=rtol)
        for i, state in enumerate(states):
            r = kernel(p, settings, state, no_samples, no_events, final, control)
            out["q"][k, i] = outcome_label(r.status, r.n_well, final[2])
            out["st"][k, i], out["steps"][k, i], out["tc"][k, i] = r.status, r.steps, r.last_change
            out["ts"][k, i] = r.settle_time
    return out


def rung_runs(data, data8, first, floor, upper, upper_start):
    """The saved runs of a design's rungs, coarse to fine: (label, status, steps, last change,
    settle time) per rung; the first on the event method, the others on ``upper``'s runs, from
    ``upper_start`` (or a decade below the first) to the floor."""
    def run(table, rtols, rtol):
        k = rtols.index(rtol)
        return tuple(table[name][k] for name in ("q", "st", "steps", "tc", "ts"))

    rungs = [run(data, RTOLS, first)]
    start = RTOLS.index(upper_start) if upper_start else RTOLS.index(first) + 1
    for k in range(start, RTOLS.index(floor) + 1):
        rungs.append(run(data, RTOLS, RTOLS[k]) if upper == EVENT
                     else run(data8, DOP853_RTOLS, RTOLS[k]))
    return rungs


def replay(data, data8, robust, rk4, first, floor, tolerance, settle_tolerance, upper,
           upper_start):
    """A design replayed on the saved runs: its verdicts and cost."""
    rungs = rung_runs(data, data8, first, floor, upper, upper_start)
    q0 = rungs[0][0]
    n = q0.shape[0]
    certain, open_ = np.zeros(n, bool), np.ones(n, bool)
    label, cost = q0.copy(), rungs[0][2].copy()
    successive = zip(rungs[:-1], rungs[1:], strict=True)
    for (q_a, st_a, _, tc_a, ts_a), (q_b, st_b, steps_b, tc_b, ts_b) in successive:
        cost += np.where(open_, steps_b, 0)
        gap = np.abs(tc_b - tc_a)
        gap[np.isnan(tc_b) & np.isnan(tc_a)] = 0.0  # neither ever changed well
        agree = ((q_b == q_a) & (st_b == 0) & (st_a == 0) & (gap <= tolerance)
                 & (np.abs(ts_b - ts_a) <= settle_tolerance))
        label = np.where(open_, q_b, label)
        certain |= open_ & agree
        open_ &= ~agree
    return {"first": first, "floor": floor, "change_tolerance": tolerance,
            "settle_tolerance": settle_tolerance, "upper_rungs": upper.label,
            "upper_start": upper_start or RTOLS[RTOLS.index(first) + 1],
            "certain_and_wrong_robust": float((certain & (label != rk4) & robust).sum()
                                              / robust.sum()),
            "uncertain_robust": float((~certain & robust).sum() / robust.sum()),
            "uncertain_all": float((~certain).mean()), "steps_per_cell": float(cost.mean()),
            "single_pass_steps": float(rungs[0][2].mean())}


def measured_cost(scene, states, rounds=3):
    """Seconds a throw of the default ladder (DOP853 past its first rung) and of the former one
    (Dormand-Prince 5(4) alone, rtol 1e-6, 1e-7, ... 1e-12), through the real kernel on one
    thread, thread time, interleaved rounds (medians)."""
    from coincli.labeller import Labeller

    labeller = Labeller.of(scene)
    default = labeller.ladder
    rtols = tuple(r for r in RTOLS if r <= default.rtols[0])
    dp5_only = replace(default, methods=(default.methods[0],) * len(rtols), rtols=rtols,
                       dts=default.dts[:1] * len(rtols),
                       budgets=default.budgets[:1] * len(rtols) if default.budgets else ())
    seconds = {"default": [], "dp5_only": []}
    for _ in range(rounds):
        for name, ladder in (("default", default), ("dp5_only", dp5_only)):
            started = time.thread_time()
            replace(labeller, ladder=ladder).label(states)
            seconds[name].append((time.thread_time() - started) / len(states))
    return {name: float(np.median(values)) for name, values in seconds.items()}


def box_states(scene, n):
    """n seeded random throws over the 5-D box BOX (the default vy0 and vphi0 ranges)."""
    from coincli.montecarlo.sampling import initial_states, make_sampling

    sampling = make_sampling(scene, sampler="random", **BOX)
    u = np.random.default_rng(20261122).random((n, len(sampling.random_names)))
    return initial_states(scene, sampling, u)


def reference_labels(scene, states, threads):
    """RK4 at h = 2.5e-7 (REFERENCE_B), on ``threads`` threads: (labels, statuses)."""
    from concurrent.futures import ThreadPoolExecutor

    from coincli.accuracy import REFERENCE_B
    from coincli.labeller import Labeller

    run_scene = REFERENCE_B.apply(scene, stop_on_settle=True, t_end=None)
    single = Labeller.of(run_scene)  # a single pass (REFERENCE_B does not verify)
    parts = [np.arange(i, len(states), threads) for i in range(threads)]
    q, st = np.empty(len(states), np.int16), np.empty(len(states), np.uint8)
    with ThreadPoolExecutor(threads) as pool:
        for idx, out in zip(parts, pool.map(lambda i: single.label(states[i]), parts),
                            strict=True):
            q[idx], st[idx] = out.quarter_turns, out.status
    return q, st


def main() -> None:
    import coincli
    from coincli.accuracy import REFERENCE_B, run_grid, vy_vphi_grid

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="paper", help="a preset name or TOML file")
    parser.add_argument("--res", type=int, default=64)
    parser.add_argument("--box", type=int, default=0, metavar="N",
                        help="N random throws of the 5-D box instead of the grid")
    parser.add_argument("--threads", type=int, default=2, help="for the RK4 reference")
    args = parser.parse_args()
    here = Path(__file__).resolve().parent
    scene = coincli.load_preset(args.preset)
    preset = Path(args.preset).stem  # a preset's name, or a TOML file's
    name = f"{preset}-box{args.box}" if args.box else f"{preset}-{args.res}"
    if args.box:
        states = box_states(scene, args.box)
    else:
        grid = vy_vphi_grid(scene, res=(args.res, args.res))
        states = grid.states()
    started = time.time()
    data = runs(scene, states)
    data8 = runs(scene.with_overrides(method=DOP853), states, DOP853_RTOLS)
    cache = here / f"rk4-{name}.npz"
    if cache.exists():
        saved = np.load(cache)
        rk4_q, rk4_st = saved["q"], saved["st"]
    elif args.box:
        rk4_q, rk4_st = reference_labels(scene, states, args.threads)
        np.savez(cache, q=rk4_q, st=rk4_st)
    else:
        ref = run_grid(scene, REFERENCE_B, grid, args.threads)
        rk4_q, rk4_st = ref.quarter_turns.ravel(), ref.status.ravel()
        np.savez(cache, q=rk4_q, st=rk4_st)
    tight = RTOLS.index(1e-12)
    robust = ((data["st"][tight] == 0) & (rk4_st == 0) & (data["q"][tight] == rk4_q))
    rows = [replay(data, data8, robust, rk4_q, *design) for design in DESIGNS]
    cost = measured_cost(scene, states)
    single = {f"{r:g}": float(((data["q"][k] != rk4_q) & robust).sum() / robust.sum())
              for k, r in enumerate(RTOLS)}
    result = {"preset": args.preset, "res": args.res, "box": dict(BOX, n=args.box) if args.box
              else None, "robust_cells": int(robust.sum()),
              "cells": int(robust.size), "single_pass_wrong_robust": single, "designs": rows,
              "default_seconds_per_throw": cost["default"],
              "dp5_only_seconds_per_throw": cost["dp5_only"],
              "seconds": time.time() - started, "command": " ".join(sys.argv)}
    (here / f"ladder-{name}.json").write_text(json.dumps(result, indent=2))
    where = (f"{args.box} throws of the 5-D box" if args.box
             else f"{args.res} x {args.res} over the default ranges")
    print(f"{args.preset}, {where}: {robust.sum()} robust cells of {robust.size}")
    print("single pass, wrong on robust cells: "
          + ", ".join(f"rtol {k} {v:.2%}" for k, v in single.items()))
    print("| first rung | floor | upper rungs | last change within | settled within "
          "| certain and wrong | uncertain (robust) | uncertain (all) | steps a cell |")
    print("|---|---|---|---|---|---|---|---|---|")

    def within(seconds):
        return f"{seconds * 1e3:g} ms" if np.isfinite(seconds) else "-"

    for r in rows:
        print(f"| {r['first']:g} | {r['floor']:g} | {r['upper_rungs']} from {r['upper_start']:g} "
              f"| {within(r['change_tolerance'])} "
              f"| {within(r['settle_tolerance'])} | {r['certain_and_wrong_robust']:.2%} "
              f"| {r['uncertain_robust']:.2%} | {r['uncertain_all']:.1%} "
              f"| {r['steps_per_cell']:.0f} |")
    print(f"default ladder (DOP853 from 1e-8): {cost['default'] * 1e6:.1f} us a throw, "
          f"Dormand-Prince 5(4) alone from 1e-7 {cost['dp5_only'] * 1e6:.1f} us "
          f"({cost['dp5_only'] / cost['default']:.2f}x; one thread, median of 3 interleaved)")


if __name__ == "__main__":
    main()
