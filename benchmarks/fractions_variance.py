"""Would quasi-random points or stratification make `coin fractions` cheaper? Measured: no.

P(standing) over the 5-D box of docs/fractions.md is about 0.27 %, and its 95 % interval of
+-0.005 percentage points takes 4.2 million verified throws with independent draws. Two
classical ways to need fewer:

1. Scrambled Sobol points (the default sampler). Their error shrinks faster than independent
   draws' for integrands that are smooth, or whose discontinuities are few and regular. This
   runs R independent scrambles (seeds) of N points each, and as many independent-draw runs,
   and compares the variance of P(standing) across the R runs with the binomial variance
   p (1 - p) / N. A ratio well below 1 would let a replicated-Sobol interval be narrower.
2. Stratification. With the optimal (Neyman) allocation, the variance over strata is
   (sum_h w_h sqrt(p_h (1 - p_h)))^2 / N against p (1 - p) / N: it gains only where the
   standing throws are concentrated in a few strata. Given a store of a finished run
   (``--store``), this computes that gain, with the strata's true frequencies taken from the
   store (the best any stratified design could do), for equal-width bins of every set of one,
   two and five of the initial conditions, also weighed by the strata's costs (steps).

    python benchmarks/fractions_variance.py --replicates 24 --samples 16384   # ~1 min
    python benchmarks/fractions_variance.py --store box.zarr   # after docs/fractions.md's box run

Writes benchmarks/fractions-variance.json (the replicates) and prints both studies.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

BOX = dict(y0="r:5r", phi0="-pi:pi", vx="-0.5:0.5")  # vy, vphi: coin basin's default ranges
NAMES = ("y0", "phi0", "vx", "vy", "vphi")


def replicates(count: int, samples: int) -> dict:
    """P(standing) of ``count`` runs of ``samples`` throws per sampler, and the ratio of its
    variance across runs to the binomial one, with a 95 % interval (chi-square, count - 1
    degrees of freedom)."""
    import coincli

    scene = coincli.load_preset("paper")
    out = {}
    for sampler in ("sobol", "random"):
        start = time.perf_counter()
        estimates, standing, labelled = [], [], []
        for k in range(count):
            result = coincli.fractions(scene, **BOX, samples=samples, seed=1000 + k,
                                       sampler=sampler)
            standing.append(result.standing["count"])
            labelled.append(result.standing["of"])
            estimates.append(standing[-1] / labelled[-1])
        p = sum(standing) / sum(labelled)
        binomial = p * (1 - p) / np.mean(labelled)
        ratio = float(np.var(estimates, ddof=1) / binomial)
        dof = count - 1
        low = ratio * dof / stats.chi2.ppf(0.975, dof)
        high = ratio * dof / stats.chi2.ppf(0.025, dof)
        out[sampler] = {"p_standing": p, "standing": standing, "labelled": labelled,
                        "variance_ratio": ratio, "ratio_low": low, "ratio_high": high,
                        "seconds": round(time.perf_counter() - start, 1)}
        print(f"{sampler:>6}: P(standing) {p:.4%}, variance across {count} runs / binomial "
              f"= {ratio:.2f} (95 % {low:.2f} to {high:.2f}), {out[sampler]['seconds']} s",
              flush=True)
    return out


def stratification(store: str, bins: int = 8) -> None:
    """The variance gain of the best stratified design over the initial conditions of a
    finished `coin fractions` store, by sets of coordinates."""
    import zarr

    from coincli.enums import Certainty

    group = zarr.open_group(store, mode="r")
    certain = group["certainty"][:] == Certainty.CERTAIN
    initial = group["initial"][:][certain]
    standing = (group["quarter_turns"][:][certain] % 2 != 0).astype(float)
    steps = group["steps"][:][certain].astype(float)
    p, cost = standing.mean(), steps.mean()
    lo, hi = initial.min(axis=0), initial.max(axis=0)
    print(f"store: {len(standing):,} certain throws, P(standing) {p:.4%}")

    def gains(dims, per_axis):
        stratum = np.zeros(len(standing), int)
        for d in dims:
            b = ((initial[:, d] - lo[d]) / (hi[d] - lo[d]) * per_axis).astype(int)
            stratum = stratum * per_axis + np.clip(b, 0, per_axis - 1)
        k = per_axis ** len(dims)
        size = np.bincount(stratum, minlength=k)
        w = size / len(standing)
        ph = np.bincount(stratum, standing, minlength=k) / np.maximum(size, 1)
        ch = np.bincount(stratum, steps, minlength=k) / np.maximum(size, 1)
        neyman = (w * np.sqrt(ph * (1 - ph))).sum() ** 2
        with_cost = (w * np.sqrt(ph * (1 - ph) * ch)).sum() ** 2
        return p * (1 - p) / neyman, p * (1 - p) * cost / with_cost

    print("variance gain of the best stratified design (and of variance x cost):")
    for r in (1, 2):
        for dims in itertools.combinations(range(5), r):
            g, gc = gains(dims, bins)
            print(f"  {' '.join(NAMES[d] for d in dims):<12} {bins}^{r} strata: "
                  f"{g:.2f} ({gc:.2f})")
    g, gc = gains(range(5), 4)
    print(f"  all five     4^5 strata: {g:.2f} ({gc:.2f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--replicates", type=int, default=24)
    parser.add_argument("--samples", type=int, default=16384)
    parser.add_argument("--store", help="a finished coin fractions store to stratify")
    args = parser.parse_args()
    if args.store:
        stratification(args.store)
        return
    result = replicates(args.replicates, args.samples)
    path = Path(__file__).with_name("fractions-variance.json")
    path.write_text(json.dumps({"box": BOX, "samples": args.samples,
                                "replicates": args.replicates, **result}, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
