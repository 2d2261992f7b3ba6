"""Can a cheap physical indicator replace the ladder's second run? Measured, and the answer is no.

Issue 11 suggests deciding from the first run alone which cells need a second one: how close
that run came to an edge. For every cell of a (vy0, vphi0) grid this runs the first rung
(event, rtol 1e-6) with dense samples every 1e-4 s and takes its *closest call*, in units of
m g r (r the half diagonal): at every passage over a well boundary (the diagonal vertical,
phi = k pi +- phi_cr) the kinetic energy of pivoting about the corner, (I + m r^2) vphi^2 / 2,
and at every turning point of phi the energy it lacked to reach the nearest boundary,
m g r (1 - cos(distance)). A run that never passed a boundary nor turned near one has a large
closest call. It then runs the second rung (rtol 1e-7) and marks the cells the ladder catches
(the two runs disagree by its rule), and prints, for thresholds of the closest call, the share
of cells the indicator would send on and how many of the caught cells it would wave through.

    python benchmarks/margin_indicator.py --preset paper --res 64   # about 10 s

Writes benchmarks/margin-<preset>-<res>.json.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

SAMPLE_DT = 1e-4  # s; a turning point is then found to ~ phi'' dt^2 / 2, ~ 1e-5 rad
THRESHOLDS = (1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.2, 0.3)
G = 9.81


def closest_call(p, samples) -> float:
    """The closest call of one run from its samples (t, x, y, phi, vx, vy, vphi rows), J."""
    phi, vphi = samples[:, 3], samples[:, 6]
    # distance of each sample from the nearest boundary k pi +- phi_cr
    to_edge = np.minimum(np.abs((phi - p.phi_cr + math.pi / 2) % math.pi - math.pi / 2),
                         np.abs((phi + p.phi_cr + math.pi / 2) % math.pi - math.pi / 2))
    calls = [math.inf]
    passed = ((np.diff(np.floor((phi - p.phi_cr) / math.pi)) != 0)
              | (np.diff(np.floor((phi + p.phi_cr) / math.pi)) != 0))
    if passed.any():
        i = np.nonzero(passed)[0]
        spin = np.minimum(np.abs(vphi[i]), np.abs(vphi[i + 1]))
        calls.append(float((0.5 * (p.inertia + p.mass * p.r ** 2) * spin ** 2).min()))
    turns = np.nonzero(np.sign(vphi[1:]) != np.sign(vphi[:-1]))[0]
    if len(turns):
        gap = np.minimum(to_edge[turns], to_edge[turns + 1])
        calls.append(float((p.mass * G * p.r * (1.0 - np.cos(gap))).min()))
    return min(calls)


def main() -> None:
    import coincli
    from coincli.accuracy import vy_vphi_grid
    from coincli.integrators import new_control
    from coincli.integrators.batch import integrate, outcome_label, rungs_agree
    from coincli.integrators.common import EVENT_COLUMNS
    from coincli.integrators.ladder import CHANGE_TOLERANCE, SETTLE_TOLERANCE
    from coincli.labeller import Labeller

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="paper")
    parser.add_argument("--res", type=int, default=64)
    args = parser.parse_args()
    scene = coincli.load_preset(args.preset)
    states = vy_vphi_grid(scene, res=(args.res, args.res)).states()
    labeller = Labeller.of(scene)
    p, base = labeller.params, labeller.settings
    first, second = base._replace(rtol=1e-6, sample_dt=SAMPLE_DT), base._replace(rtol=1e-7)
    kernel, control, final = labeller.kernels[integrate], new_control(), np.empty(6)
    outcome_label, rungs_agree = labeller.python[outcome_label], labeller.python[rungs_agree]
    samples = np.empty((int(base.t_end / SAMPLE_DT) + 2, 7))
    no_events = np.empty((0, EVENT_COLUMNS))
    started = time.time()
    call = np.empty(len(states))
    caught = np.zeros(len(states), bool)
    relabelled = np.zeros(len(states), bool)  # caught with a different n, not only later
    for i, state in enumerate(states):
        a = kernel(p, first, state, samples, no_events, final, control)
        label_a = outcome_label(a.status, a.n_well, final[2])
        call[i] = closest_call(p, samples[:a.n_samples]) if a.status == 0 else -math.inf
        b = kernel(p, second, state, samples[:0], no_events, final, control)
        label_b = outcome_label(b.status, b.n_well, final[2])
        caught[i] = not rungs_agree(label_a, a, label_b, b, CHANGE_TOLERANCE,
                                    SETTLE_TOLERANCE)
        relabelled[i] = label_a != label_b
    call /= p.mass * G * p.r
    rows = [{"threshold": t, "sent_on": float((call < t).mean()),
             "caught_missed": int((caught & ~(call < t)).sum()),
             "relabelled_missed": int((relabelled & ~(call < t)).sum())} for t in THRESHOLDS]
    result = {"preset": args.preset, "res": args.res, "cells": len(states),
              "caught": int(caught.sum()), "relabelled": int(relabelled.sum()),
              "largest_call_caught": float(call[caught].max()) if caught.any() else None,
              "rows": rows, "seconds": time.time() - started, "command": " ".join(sys.argv)}
    here = Path(__file__).resolve().parent
    (here / f"margin-{args.preset}-{args.res}.json").write_text(json.dumps(result, indent=2))
    print(f"{args.preset}, {args.res} x {args.res}: the ladder catches {caught.sum()} of "
          f"{len(states)} cells ({relabelled.sum()} with a different n); the largest closest "
          "call among them is "
          f"{result['largest_call_caught']:.3g} m g r")
    print("| closest call below (m g r) | cells sent to a second run | caught cells missed "
          "| of them with a different n |")
    print("|---|---|---|---|")
    for r in rows:
        print(f"| {r['threshold']:g} | {r['sent_on']:.1%} | {r['caught_missed']} "
              f"| {r['relabelled_missed']} |")


if __name__ == "__main__":
    main()
