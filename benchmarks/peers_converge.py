#!/usr/bin/env python
"""Are the peers' wrong labels integration error? Re-run each peer, at tighter tolerances, on the
robust cells it labelled wrongly in a peers.json, and count how many it now gets right.
Then integrate the peers' model tightly (scipy DOP853, rtol 1e-12) on every cell any peer got
wrong. Accuracy only (nothing is timed); writes benchmarks/peers-converge.json and prints a
table.

    python benchmarks/peers_converge.py                      # reads benchmarks/peers.json
    python benchmarks/peers_converge.py --rtols 1e-8,1e-10
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import peers  # noqa: E402
from peer_models import Coin  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--input", default=str(HERE / "peers.json"))
    ap.add_argument("--out", default=str(HERE / "peers-converge.json"))
    ap.add_argument("--rtols", default="1e-8,1e-10")
    ap.add_argument("--tight-rtol", type=float, default=1e-12,
                    help="rtol of the final DOP853 check on every cell any peer got wrong")
    ap.add_argument("--timeout", type=float, default=60.0,
                    help="wall seconds per scipy trajectory")
    args = ap.parse_args(argv)
    rtols = [float(x) for x in args.rtols.split(",")]

    report = json.loads(Path(args.input).read_text())
    coin = Coin(**{k: report["coin"][k] for k in ("d", "t", "m", "inertia", "k", "c", "g")})
    vy = np.array(report["grid"]["vy0"])
    vphi = np.array(report["grid"]["vphi0"])
    vy_g, vphi_g = np.meshgrid(vy, vphi, indexing="ij")
    states = coin.initial_states(vy_g, vphi_g)
    reference = np.array(next(iter(report["references"].values()))["labels"])

    rows = []
    for result in report["results"]:
        lib, method = result["library"], result["method"]
        if lib == "coincli" or (lib == "diffrax" and not result.get("vmap", True)):
            continue  # the per-throw diffrax loop gives the same labels as the vmap one
        bad = np.array(result["agreement"]["disagreeing_cells"], int)
        row = {"method": method, "cells": bad.tolist(), "at": {}}
        for rtol in rtols:
            if bad.size == 0:
                break
            start = time.perf_counter()
            if lib == "scipy":
                name = method.split()[-1]
                out = peers.run_scipy(coin, states[bad], name, rtol, args.timeout)
            else:
                import jax
                jax.config.update("jax_enable_x64", True)
                name = method.split()[1]
                out = peers.run_diffrax(coin, states[bad], name, rtol, 10**6, 1)
            row["at"][f"{rtol:g}"] = {
                "now_agree": int(np.sum(out["labels"] == reference[bad])),
                "labels": out["labels"].tolist(),
                "status": peers.status_counts(out["status"]),
                "seconds": time.perf_counter() - start}
            print(f"{method} rtol={rtol:g}: {row['at'][f'{rtol:g}']['now_agree']}/{bad.size}",
                  file=sys.stderr, flush=True)
        rows.append(row)

    # the peers' own model, integrated tightly (scipy DOP853), on every cell any peer got wrong
    union = sorted({c for row in rows for c in row["cells"]})
    tight = None
    if union:
        start = time.perf_counter()
        out = peers.run_scipy(coin, states[union], "DOP853", args.tight_rtol, args.timeout)
        tight = {"method": f"scipy solve_ivp DOP853 rtol={args.tight_rtol:g}", "cells": union,
                 "now_agree": int(np.sum(out["labels"] == reference[union])),
                 "labels": out["labels"].tolist(), "status": peers.status_counts(out["status"]),
                 "seconds": time.perf_counter() - start}
    Path(args.out).write_text(json.dumps({"input": args.input, "rtols": rtols, "rows": rows,
                                          "tight_check": tight}, indent=1) + "\n")
    head = " | ".join(f"right at rtol {r:g}" for r in rtols)
    print(f"| method | wrong at rtol {report['rtol']:g} | {head} |")
    print("|---|---:|" + "---:|" * len(rtols))
    for row in rows:
        cells = " | ".join(str(row["at"].get(f"{r:g}", {}).get("now_agree", "-")) for r in rtols)
        print(f"| {row['method']} | {len(row['cells'])} | {cells} |")
    if tight:
        print(f"\n{tight['method']} (the peers' model integrated tightly) on the {len(union)} "
              f"cells any peer got wrong: {tight['now_agree']} labelled as the reference")
    return 0


if __name__ == "__main__":
    sys.exit(main())
