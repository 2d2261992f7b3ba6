"""How far can the labels behind `coin fractions` move its probabilities? Measured on the
five-dimensional box of docs/fractions.md.

The 95 % interval `coin fractions` prints is a sampling interval: it assumes every counted label
is the label of the true throw. A label that is certain and wrong biases the estimate instead,
and no number of samples averages that out; so the interval is only worth its width if such
labels are rarer still. This recomputes the first N throws of the run of docs/fractions.md (the same
scrambled Sobol points: seed 0, batches of 8,192) with the default, verified labels, and again
with the event method at rtol 1e-11 and at 1e-12 (the reference: both settled, with the same
count). It counts the certain labels whose count n differs from the reference, and those whose
parity differs (lying against standing), the only ones that can move P(standing). With none
of the latter among C certain labels, their rate is below 3 / C at 95 % (the rule of three).

    python benchmarks/fractions_labels.py              # 262,144 throws, about 2 min on 2 cores
    python benchmarks/fractions_labels.py --preset thick --samples 65536 --rk4 600  # 6 min

The reference shares its stepping code with the default method; `ladder_design.py --box` judges
the same kind of throws against fixed-step RK4, which shares none. Writes
benchmarks/fractions-labels.json (fractions-labels-PRESET.json for another preset) and prints a
summary.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

BOX = dict(y0="r:5r", phi0="-pi:pi", vx="-0.5:0.5")  # vy, vphi: coin basin's default ranges
REFERENCE_RTOLS = (1e-11, 1e-12)


def box_throws(scene, samples: int) -> np.ndarray:
    """The first ``samples`` initial states of the run of docs/fractions.md (whole batches)."""
    from coincli.montecarlo.sampling import Draws, initial_states, make_sampling

    sampling = make_sampling(scene, sampler="sobol", seed=0, **BOX)
    draws = Draws(sampling)
    batches = -(-samples // sampling.batch)
    states = np.concatenate([initial_states(scene, sampling, draws.batch(b))
                             for b in range(batches)])
    return states[:samples]


def on_threads(run, states: np.ndarray, threads: int) -> list:
    """``run`` on 64 slices of ``states`` (the kernels release the GIL), in order."""
    parts = np.array_split(np.arange(len(states)), 64)
    with ThreadPoolExecutor(threads) as pool:
        return list(pool.map(lambda idx: run(states[idx]), parts))


def against_rk4(scene, states, n, n_ref, judged, differs, sampled: int, threads: int) -> dict:
    """The independent reference on the throws where the default and the event reference
    differ, and on ``sampled`` judged throws drawn at random (how many of them are robust:
    RK4 settled with the event reference's n), so that the certain-and-wrong rate over the
    robust throws can be estimated, as the ladder study defines it."""
    from ladder_design import reference_labels

    picked = np.flatnonzero(differs)
    q, st = reference_labels(scene, states[picked], threads)
    q = q.astype(int)
    settled = st == 0
    robust_wrong = settled & (q == n_ref[picked])
    draw = np.sort(np.random.default_rng(7).choice(np.flatnonzero(judged),
                                                   min(sampled, int(judged.sum())),
                                                   replace=False))
    qs, sts = reference_labels(scene, states[draw], threads)
    robust_fraction = float(((sts == 0) & (qs.astype(int) == n_ref[draw])).mean())
    robust = robust_fraction * int(judged.sum())
    return {"differing_reference": int(robust_wrong.sum()),
            "differing_default": int((settled & (q == n[picked])).sum()),
            "differing_neither": int((~robust_wrong & ~(settled & (q == n[picked]))).sum()),
            "differing_reference_parity": int((robust_wrong & (n[picked] % 2 != n_ref[picked]
                                                               % 2)).sum()),
            "sampled": int(draw.size), "robust_fraction": robust_fraction,
            "wrong_robust_rate": float(robust_wrong.sum() / robust) if robust else None}


def main() -> None:
    import coincli
    from coincli.enums import Certainty, Status
    from coincli.labeller import Labeller
    from coincli.montecarlo.batch import BatchTask, compute_batch, make_fraction_spec

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="paper", help="a preset name or TOML file")
    parser.add_argument("--samples", type=int, default=262_144)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--rk4", type=int, default=0, metavar="N",
                        help="also judge the differing throws, and N certain ones drawn at "
                             "random, against fixed-step RK4 (the ladder study's independent "
                             "reference, about a second a throw on the thick coin)")
    args = parser.parse_args()
    scene = coincli.load_preset(args.preset)
    states = box_throws(scene, args.samples)
    started = time.time()

    spec = make_fraction_spec(scene)
    results = on_threads(lambda s: compute_batch(spec, BatchTask(0, 0, len(s), s)), states,
                         args.threads)
    n = np.concatenate([r.labels["quarter_turns"] for r in results]).astype(int)
    certain = np.concatenate([r.labels["certainty"] for r in results]) == Certainty.CERTAIN
    rung = np.concatenate([r.labels["rung"] for r in results]).astype(int)
    default_seconds = time.time() - started

    refs = []
    for rtol in REFERENCE_RTOLS:  # single passes of the event method
        at = Labeller.of(scene.with_overrides(method="event", rtol=rtol, stop_on_settle=True,
                                              verify=False))
        outs = on_threads(lambda s, at=at: at.label(s), states, args.threads)
        refs.append((np.concatenate([o.quarter_turns for o in outs]).astype(int),
                     np.concatenate([o.status for o in outs])))
    (n11, st11), (n12, st12) = refs
    reference = (st11 == Status.SETTLED) & (st12 == Status.SETTLED) & (n11 == n12)

    judged = certain & reference
    if not judged.any():
        sys.exit("no certain label to judge (a single-pass preset?)")
    n_differs = judged & (n != n12)
    parity_differs = judged & (n % 2 != n12 % 2)
    count = int(judged.sum())
    flips = int(parity_differs.sum())
    standing = int((judged & (n % 2 == 1)).sum())
    standing_ref = int((judged & (n12 % 2 == 1)).sum())
    result = {
        "preset": args.preset, "box": BOX, "sampler": "sobol", "seed": 0,
        "samples": int(len(states)),
        "reference": f"event method at rtol {REFERENCE_RTOLS[0]:g} and {REFERENCE_RTOLS[1]:g},"
                     " both settled with the same n",
        "certain": int(certain.sum()), "uncertain": int((~certain).sum()),
        "reference_undecided": int((~reference).sum()),
        "judged": count,
        "n_differs": int(n_differs.sum()),
        "parity_differs": flips,
        "standing_default": standing, "standing_reference": standing_ref,
        "parity_rate_bound_95": 3.0 / count if flips == 0 else None,  # else: the count says
        "differing": [{"sample": int(i), "n": int(n[i]), "n_reference": int(n12[i]),
                       "rung": int(rung[i])} for i in np.flatnonzero(n_differs)],
        "default_seconds": default_seconds,
    }
    if args.rk4:
        result["rk4"] = against_rk4(scene, states, n, n12, judged, n_differs, args.rk4,
                                    args.threads)
    result.update(seconds=time.time() - started, command=" ".join(sys.argv))
    here = Path(__file__).resolve().parent
    name = "" if args.preset == "paper" else f"-{Path(args.preset).stem}"
    (here / f"fractions-labels{name}.json").write_text(json.dumps(result, indent=2) + "\n")
    print(f"{len(states):,} throws of the box: {result['certain']:,} certain, "
          f"{result['uncertain']:,} uncertain; reference undecided on "
          f"{result['reference_undecided']:,}")
    print(f"of the {count:,} certain labels the reference decides, {result['n_differs']} "
          f"({result['n_differs'] / count:.4%}) differ in n,\n{flips} lying against standing")
    print(f"standing: {standing:,} by the default, {standing_ref:,} by the reference")
    if flips == 0:
        print(f"rate of lying/standing errors below {3 / count:.2e} "
              f"({100 * 3 / count:.4f} percentage points) at 95 %")
    if args.rk4:
        r = result["rk4"]
        print(f"RK4 on the {result['n_differs']} that differ: {r['differing_reference']} as the "
              f"reference (robust: the default is wrong), {r['differing_default']} as the "
              f"default, {r['differing_neither']} neither; on {r['sampled']} certain throws "
              f"drawn at random, {r['robust_fraction']:.1%} robust: the default is certain and "
              f"wrong on about {r['wrong_robust_rate']:.3%} of the robust throws "
              f"({r['differing_reference_parity']} of them lying for standing)")
    print(f"{result['seconds']:.0f} s ({default_seconds:.0f} s the default labels)")


if __name__ == "__main__":
    main()
