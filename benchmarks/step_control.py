"""What DOP853's step-size control saves: steps accepted and rejected, and right-hand sides, a
throw of the README's five-dimensional box, with the PI control the driver has (err^(-1/8)
times the previous accepted step's err^(1/32)) and without it (the last error only).

    python benchmarks/step_control.py                                   # paper, rtol 1e-8
    python benchmarks/step_control.py --preset thick --rtol 1e-9 --samples 100

The kernels run as plain Python (the model's kernel set for CPython), so that the driver's
calls can be counted: about a minute a hundred throws. Stages: 12 a step tried, 3 more for each
continuous extension (the steps that locate an event).
"""

from __future__ import annotations

import argparse
import collections
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", default="paper")
    parser.add_argument("--rtol", type=float, default=1e-8)
    parser.add_argument("--samples", type=int, default=200)
    args = parser.parse_args()

    import numpy as np
    from fractions_labels import box_throws

    import coincli
    from coincli.enums import Method
    from coincli.integrators import pairs
    from coincli.integrators.batch import integrate, unrecorded
    from coincli.labeller import Labeller

    scene = coincli.load_preset(args.preset)
    labeller = Labeller.of(scene, backend="python")
    kernels = labeller.kernels  # plain Python functions
    # the set's DOP853 copy of the driver looks its pair's names up in its globals, a namespace
    # of its own (coincli.jit.derive, then the kernel set's copy of it)
    namespace = kernels[pairs.integrate_adaptive_dop853].__globals__
    shipped = {name: namespace[name] for name in ("step", "dense_coefficients",
                                                  "controller_memory")}
    counts = collections.Counter()

    def step(p, mode, h, *rest):
        out = shipped["step"](p, mode, h, *rest)
        counts["accepted" if out[4] <= 1.0 else "rejected"] += 1
        return out

    def dense_coefficients(*a):
        counts["extensions"] += 1
        return shipped["dense_coefficients"](*a)

    namespace["step"] = step
    namespace["dense_coefficients"] = dense_coefficients
    states = box_throws(scene, args.samples)
    p = labeller.params
    settings = labeller.settings._replace(
        method=int(Method.EVENT_DOP853), rtol=args.rtol, stop_on_settle=True)
    labels = {}
    print(f"{args.preset}, DOP853 at rtol {args.rtol:g}, {len(states)} box throws, a throw:")
    for name, memory in (("PI (the driver's)", shipped["controller_memory"]),
                         ("I (last error only)", lambda err: 1.0)):
        namespace["controller_memory"] = memory
        counts.clear()
        labels[name] = np.array([
            kernels[integrate](p, settings, s.copy(), *unrecorded(),
                               np.zeros(1, np.int64)).n_well
            for s in states])
        stages = 12 * (counts["accepted"] + counts["rejected"]) + 3 * counts["extensions"]
        print(f"  {name:20s} accepted {counts['accepted'] / len(states):6.2f}  rejected "
              f"{counts['rejected'] / len(states):6.2f}  stages {stages / len(states):7.1f}")
    a, b = labels.values()
    print(f"  throws whose settled well differs: {int((a != b).sum())} of {len(states)}")


if __name__ == "__main__":
    main()
