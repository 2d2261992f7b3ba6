"""What bounds a Dormand-Prince 5(4) contact step, compiled: the latency of its chains of
dependent operations, or the number of instructions? Times a chain of steps of one coin rocking
on its two lower corners, and two such chains in one loop (independent work the CPU could
overlap where the step waits on latency), and counts the instructions of the compiled function.
The same for a branch-free step written for that one contact mode (its corners fixed, the turn's
cosine and sine from one short series), in case the general step's branches kept the two chains
apart. Also times a variant that keeps fewer stages live (the error estimate and the continuous
extension's sum accumulated as the stages come), the same arithmetic but for its order.

    python benchmarks/step_throughput.py [--steps 200000] [--rounds 9]

Thread time, medians of interleaved rounds.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--rounds", type=int, default=9)
    args = parser.parse_args()

    import numba
    import numpy as np

    import coincli
    from coincli.integrators import dopri
    from coincli.models import PAPER, model_params

    kernels = PAPER.kernels()  # the paper model's compiled kernels (numba dispatchers)
    combine, derivative, stage, step = (kernels[dopri.combine], kernels[dopri.derivative],
                                        kernels[dopri.stage], kernels[dopri.step])
    error_scales, rotate = kernels[dopri.error_scales], kernels.rotate
    A2, A3, A4, A5, A6, B, E, D = (dopri.A2, dopri.A3, dopri.A4, dopri.A5, dopri.A6, dopri.B,
                                   dopri.E, dopri.D)

    @numba.njit(fastmath={"contract"}, inline="always")
    def axpy(acc, w, k):
        return (acc[0] + w * k[0], acc[1] + w * k[1], acc[2] + w * k[2], acc[3] + w * k[3],
                acc[4] + w * k[4], acc[5] + w * k[5])

    @numba.njit(fastmath={"contract"}, inline="always")
    def step_accumulating(p, mode, h, start, k1, c, s, scales, rtol):
        k2 = stage(p, mode, start, h, A2, (k1,), c, s)
        k3 = stage(p, mode, start, h, A3, (k1, k2), c, s)
        k4 = stage(p, mode, start, h, A4, (k1, k2, k3), c, s)
        k5 = stage(p, mode, start, h, A5, (k1, k2, k3, k4), c, s)
        k6 = stage(p, mode, start, h, A6, (k1, k2, k3, k4, k5), c, s)
        end = combine(start, h, B, (k1, k2, k3, k4, k5, k6))
        e = axpy((0.0, 0.0, 0.0, 0.0, 0.0, 0.0), E[0], k1)
        d = axpy((0.0, 0.0, 0.0, 0.0, 0.0, 0.0), D[0], k1)
        for w_e, w_d, k in ((E[2], D[2], k3), (E[3], D[3], k4), (E[4], D[4], k5),
                            (E[5], D[5], k6)):
            e = axpy(e, w_e, k)
            d = axpy(d, w_d, k)
        c7, s7 = rotate(c, s, end[2] - start[2])
        k7 = derivative(p, mode, end, c7, s7)
        e = axpy(e, E[6], k7)
        d = axpy(d, D[6], k7)
        total = 0.0
        for j in range(6):
            tol = scales[j] + rtol * max(abs(start[j]), abs(end[j]))
            total += (h * e[j] / tol) ** 2
        return end, k7, c7, s7, math.sqrt(total / 6.0), (k1, k7, d)

    @numba.njit(fastmath={"contract"}, inline="always")
    def turn(c, s, d):  # the series of coincli.models.rotation.rotate for small turns, no branches
        d2 = d * d
        d4 = d2 * d2
        cd = (1.0 - d2 * (1.0 / 2)) + d4 * (1.0 / 24 - d2 * (1.0 / 720))
        sd = d * ((1.0 - d2 * (1.0 / 6)) + d4 * (1.0 / 120 - d2 * (1.0 / 5040)))
        return c * cd - s * sd, s * cd + c * sd

    @numba.njit(fastmath={"contract"}, inline="always")
    def rocking(p, point, c, s):  # the derivative with corners 0 and 1 in contact, unrolled
        y, vx, vy, vphi = point[1], point[3], point[4], point[5]
        fx = fy = moment = 0.0
        for side in (1.0, -1.0):
            dx = side * p.r_d * c + p.r_t * s
            dy = side * p.r_d * s - p.r_t * c
            fxi = -p.c * (vx - vphi * dy)
            fyi = -p.k * (y + dy) - p.c * (vy + vphi * dx)
            fx += fxi
            fy += fyi
            moment += dx * fyi - dy * fxi
        return (vx, vy, vphi, fx * p.inv_mass, fy * p.inv_mass - p.g, moment * p.inv_inertia)

    @numba.njit(fastmath={"contract"}, inline="always")
    def rocking_stage(p, start, h, weights, stages, c, s):
        point = combine(start, h, weights, stages)
        cp, sp = turn(c, s, point[2] - start[2])
        return rocking(p, point, cp, sp)

    @numba.njit(fastmath={"contract"}, inline="always")
    def step_branch_free(p, mode, h, start, k1, c, s, scales, rtol):
        k2 = rocking_stage(p, start, h, A2, (k1,), c, s)
        k3 = rocking_stage(p, start, h, A3, (k1, k2), c, s)
        k4 = rocking_stage(p, start, h, A4, (k1, k2, k3), c, s)
        k5 = rocking_stage(p, start, h, A5, (k1, k2, k3, k4), c, s)
        k6 = rocking_stage(p, start, h, A6, (k1, k2, k3, k4, k5), c, s)
        end = combine(start, h, B, (k1, k2, k3, k4, k5, k6))
        c7, s7 = turn(c, s, end[2] - start[2])
        k7 = rocking(p, end, c7, s7)
        stages = (k1, k2, k3, k4, k5, k6, k7)
        error = combine((0.0, 0.0, 0.0, 0.0, 0.0, 0.0), h, E, stages)
        total = 0.0
        for j in range(6):
            tol = scales[j] + rtol * max(abs(start[j]), abs(end[j]))
            total += (error[j] / tol) ** 2
        return end, k7, c7, s7, math.sqrt(total / 6.0), stages

    def chain(stepper):
        @numba.njit(fastmath={"contract"}, nogil=True)
        def run(p, mode, h, st, n):
            rtol = 1e-6
            scales = error_scales(p, rtol)
            c, s = math.cos(st[2]), math.sin(st[2])
            k1 = derivative(p, mode, st, c, s)
            total = 0.0
            for _ in range(n):
                end, k7, c7, s7, err, stages = stepper(p, mode, h, st, k1, c, s, scales, rtol)
                if err > 1e9:  # the stages kept for a rare continuous extension, as the driver
                    total += stages[0][0] + stages[-1][1]
                st, k1, c, s = end, k7, c7, s7
                total += err
            return total + st[1]
        return run

    def two_chains(stepper):
        @numba.njit(fastmath={"contract"}, nogil=True)
        def run(p, mode, h, sa, sb, n):
            rtol = 1e-6
            scales = error_scales(p, rtol)
            ca, sna = math.cos(sa[2]), math.sin(sa[2])
            cb, snb = math.cos(sb[2]), math.sin(sb[2])
            ka, kb = derivative(p, mode, sa, ca, sna), derivative(p, mode, sb, cb, snb)
            total = 0.0
            for _ in range(n):
                ea, k7a, c7a, s7a, erra, _a = stepper(p, mode, h, sa, ka, ca, sna, scales, rtol)
                eb, k7b, c7b, s7b, errb, _b = stepper(p, mode, h, sb, kb, cb, snb, scales, rtol)
                sa, ka, ca, sna = ea, k7a, c7a, s7a
                sb, kb, cb, snb = eb, k7b, c7b, s7b
                total += erra + errb
            return total + sa[1] + sb[1]
        return run

    p = model_params(coincli.load_preset("paper"))
    rest = p.r_t - 0.5 * p.mass * p.g / p.k  # resting on the two lower corners (mode 3)
    a = (0.0, rest - 1e-5, 0.01, 0.1, 0.0, 1.0)
    b = (0.0, rest - 2e-5, -0.01, -0.1, 0.01, -1.5)
    h, n = 2e-5, args.steps
    one, accumulating, free = chain(step), chain(step_accumulating), chain(step_branch_free)
    two, two_free = two_chains(step), two_chains(step_branch_free)
    runs = {"one chain": lambda: one(p, 3, h, a, n),
            "two chains": lambda: two(p, 3, h, a, b, n),
            "accumulating": lambda: accumulating(p, 3, h, a, n),
            "branch-free": lambda: free(p, 3, h, a, n),
            "bf two chains": lambda: two_free(p, 3, h, a, b, n)}
    for run in runs.values():
        run()
    seconds = {name: [] for name in runs}
    for _ in range(args.rounds):
        for name, run in runs.items():
            start = time.thread_time()
            run()
            seconds[name].append(time.thread_time() - start)
    per_step = {name: np.array(values) / n * 1e9 for name, values in seconds.items()}
    per_step["two chains"] /= 2
    per_step["bf two chains"] /= 2
    for name, dispatcher in (("one chain", one), ("accumulating", accumulating),
                             ("branch-free", free)):
        body = dispatcher.inspect_asm(dispatcher.signatures[0]).split("_ZN7cpython")[0]
        count = sum(1 for line in body.splitlines()
                    if line.startswith("\t") and not line.startswith("\t."))
        print(f"{name:13s} compiled function: {count} instructions, "
              f"{body.count('(%rsp)')} of them on the stack")
    base = per_step["one chain"]
    for name, values in per_step.items():
        print(f"{name:13s} {np.median(values):6.1f} ns a step, "
              f"{np.median(values / base):.3f} x one chain (median of the rounds' ratios)")


if __name__ == "__main__":
    main()
