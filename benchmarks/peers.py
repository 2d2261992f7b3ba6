#!/usr/bin/env python
"""coincli against the tools a user would otherwise reach for: scipy's solve_ivp (RK45, LSODA,
Radau) with a terminal energy event, and diffrax (JAX on CPU, jit + vmap, Dopri5 and Tsit5 with
an Event), on the same throws of the paper's coin.

    python benchmarks/peers.py                 # 256 throws (16 x 16 grid), several minutes
    python benchmarks/peers.py --quick         # 16 of those throws, a smoke run
    python benchmarks/peers.py --peers scipy   # only some peers (scipy, diffrax)

Measured per peer: wall time per trajectory (median over repeats, one process), the process CPU
time beside it (so multi-threading shows), and the fraction of *robust* cells labelled as the
reference does (robust = two independent converged references from coincli agree and both
settled). Writes every number to --out (JSON) and prints a markdown table.

coincli is used in two places only, both in the section "coincli side" below: ``ours`` (our
integrator, timed) and ``references`` (the two reference labellings). The peers' model lives in
peer_models.py and imports nothing from coincli.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO))  # coincli from this checkout, without installing it
sys.path.insert(0, str(HERE))

from peer_models import (  # noqa: E402
    NO_LABEL,
    STATUS_FAILED,
    STATUS_NAMES,
    STATUS_SETTLED,
    STATUS_TIMEOUT,
    STATUS_UNSETTLED,
    Coin,
    Timeout,
    scipy_functions,
    well_index,
)

T_END = 2.0
RTOL = 1e-6
GRID_RES = 16
VY_RANGE = (0.05, 2.0)
VPHI_RANGE = (-20.0, 20.0)
QUICK_INDEX = [0, 5, 10, 15]  # --quick: a 4 x 4 subset of the 16 x 16 grid (same throws)
SCIPY_METHODS = ("RK45", "LSODA", "Radau")
DIFFRAX_SOLVERS = ("Dopri5", "Tsit5")


# == coincli side: the only two functions that call our package ================================
def load_scene():
    from coincli.presets import load
    return load("paper").scene


def coin_of(scene) -> Coin:
    """The scene's parameters as the peers' plain Coin."""
    return Coin(d=scene.coin.diameter, t=scene.coin.thickness, m=scene.coin.mass,
                inertia=scene.coin.inertia, k=scene.foundation.k, c=scene.foundation.c,
                g=scene.g)


def ours(scene, states, rtol):
    """Our integrator on every row of ``states`` (one pass of the event method at ``rtol``, as
    the peers make one): (labels, seconds per trajectory). Labels are the settled well index,
    NO_LABEL for a run that did not settle by T_END."""
    from coincli.labeller import Labeller

    run = scene.with_overrides(method="event", rtol=rtol, t_end=T_END, stop_on_settle=True,
                               verify=False)
    labeller = Labeller.of(run)  # a single pass
    states = np.ascontiguousarray(states, dtype=np.float64)
    labeller.load(states[0])  # load the compiled kernels before the clock starts
    start = time.perf_counter()
    out = labeller.label(states)
    seconds = (time.perf_counter() - start) / len(states)
    labels = np.where(out.status == 0, out.quarter_turns.astype(np.int64), NO_LABEL)
    return labels, seconds


def references(scene, vy, vphi):
    """The two references of coincli's accuracy study on the grid vy x vphi (indexing "ij",
    flattened like the states): {name: (labels, status)}."""
    from coincli.accuracy import REFERENCE_A, REFERENCE_B, run_grid, vy_vphi_grid

    vy, vphi = np.asarray(vy, float), np.asarray(vphi, float)
    grid = vy_vphi_grid(scene, (vy[0], vy[-1]), (vphi[0], vphi[-1]), (vy.size, vphi.size))
    assert np.allclose(grid.axes[0].coords, vy) and np.allclose(grid.axes[1].coords, vphi)
    out = {}
    for name, setting in (("A: event rtol=1e-12", REFERENCE_A), ("B: rk4 h=2.5e-7", REFERENCE_B)):
        run = run_grid(scene, setting, grid)
        out[name] = (run.quarter_turns.ravel().astype(np.int64), run.status.ravel().astype(int))
    return out


def ours_state_at(scene, state0, t, rtol=1e-12):
    """Our state at time t from state0 (no early stop): used only to check the peers' model."""
    from coincli.labeller import Labeller

    run = scene.with_overrides(method="event", rtol=rtol, t_end=t, stop_on_settle=False,
                               verify=False)
    return Labeller.of(run).final_state(np.asarray(state0, float))[0]


def ours_well_index(scene, phi):
    from coincli.models import model_of, model_params

    return model_of(scene).kernels("python").well_index(model_params(scene), phi)
# ===============================================================================================


# (vy0, vphi0, t): a few impacts in, before chaos amplifies differences (coincli's accuracy
# study compares trajectories at the same points)
CHECK_THROWS = [(0.4, 6.0, 0.15), (0.6, -9.0, 0.18), (0.75, 3.0, 0.21)]


def model_check(scene, coin: Coin, with_jax: bool) -> dict:
    """Is the peers' model ours? (1) their label rule and E_crit; (2) scipy DOP853 at
    rtol = 1e-11 on the peers' RHS against our method at rtol = 1e-12, state error in the
    coin's natural units; (3) the JAX vector field against the scipy RHS at random states."""
    from scipy.integrate import solve_ivp

    for phi in np.linspace(-12.0, 12.0, 2001):
        assert well_index(coin, phi) == ours_well_index(scene, phi), phi
    assert math.isclose(coin.e_crit, scene.e_crit, rel_tol=1e-14)
    rhs, _ = scipy_functions(coin, [math.inf])
    scale = coin.atol(1.0)
    errors = []
    for vy, vphi, t in CHECK_THROWS:
        y0 = coin.initial_states([vy], [vphi])[0]
        sol = solve_ivp(rhs, (0.0, t), y0, method="DOP853", rtol=1e-11, atol=coin.atol(1e-11))
        errors.append(float(np.max(np.abs(sol.y[:, -1] - ours_state_at(scene, y0, t)) / scale)))
    out = {"label_rule_and_e_crit": "identical",
           "trajectory_error_natural_units": errors, "throws": CHECK_THROWS}
    if with_jax:
        import jax.numpy as jnp
        from peer_models import jax_functions

        vector_field, _ = jax_functions(coin)
        rng = np.random.default_rng(1)
        worst = 0.0
        for _ in range(200):  # centroid within reach of the ground, so corners penetrate
            s = np.array([0.0, rng.uniform(-0.2, 1.2) * coin.r, rng.uniform(-4, 4),
                          *rng.normal(0.0, 1.0, 2), rng.normal(0.0, 20.0)])
            a = np.asarray(rhs(0.0, s))
            b = np.asarray(vector_field(0.0, jnp.asarray(s), None))
            worst = max(worst, float(np.max(np.abs(a - b) / (np.abs(a) + 1e-9))))
        out["jax_vs_scipy_rhs_max_relative_difference"] = worst
    return out


def timed_repeats(fn, repeats):
    """Run fn() `repeats` times; (last result, wall seconds list, cpu seconds list)."""
    walls, cpus, result = [], [], None
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        result = fn()
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    return result, walls, cpus


# -- scipy ------------------------------------------------------------------------------------
def run_scipy(coin: Coin, states: np.ndarray, method: str, rtol: float, timeout: float):
    """solve_ivp on every throw, one after the other. Returns a dict of per-throw arrays."""
    from scipy.integrate import solve_ivp

    deadline = [math.inf]
    rhs, energy_event = scipy_functions(coin, deadline)
    atol = coin.atol(rtol)
    n = len(states)
    labels = np.full(n, NO_LABEL, np.int64)
    status = np.zeros(n, int)
    nfev = np.zeros(n, int)
    steps = np.zeros(n, int)
    seconds = np.zeros(n)
    messages = {}
    for i, y0 in enumerate(states):
        start = time.perf_counter()
        deadline[0] = start + timeout
        try:
            sol = solve_ivp(rhs, (0.0, T_END), y0, method=method, rtol=rtol, atol=atol,
                            events=[energy_event])
        except Timeout:
            status[i] = STATUS_TIMEOUT
            seconds[i] = time.perf_counter() - start
            continue
        seconds[i] = time.perf_counter() - start
        nfev[i] = sol.nfev
        steps[i] = sol.t.size - 1
        if sol.status == 1:  # the terminal event fired: E fell below E_crit
            labels[i] = well_index(coin, float(sol.y_events[0][0][2]))
            status[i] = STATUS_SETTLED
        elif sol.status == 0:
            status[i] = STATUS_UNSETTLED
        else:
            status[i] = STATUS_FAILED
            messages[str(i)] = sol.message
    return {"labels": labels, "status": status, "nfev": nfev, "steps": steps,
            "seconds": seconds, "messages": messages}


# -- diffrax ----------------------------------------------------------------------------------
def diffrax_solve_one(coin: Coin, solver_name: str, rtol: float, max_steps: int):
    """solve one throw: y0 -> (final state, event fired, ok, max_steps reached, accepted steps,
    rejected steps)."""
    import diffrax
    import jax.numpy as jnp
    import optimistix as optx
    from peer_models import jax_functions

    vector_field, cond_fn = jax_functions(coin)
    term = diffrax.ODETerm(vector_field)
    solver = getattr(diffrax, solver_name)()
    controller = diffrax.PIDController(rtol=rtol, atol=jnp.asarray(coin.atol(rtol)))
    event = diffrax.Event(cond_fn, root_finder=optx.Newton(rtol=1e-10, atol=1e-12),
                          direction=False)  # downcrossing: E falls below E_crit

    def one(y0):
        sol = diffrax.diffeqsolve(term, solver, t0=0.0, t1=T_END, dt0=None, y0=y0,
                                  stepsize_controller=controller, event=event,
                                  saveat=diffrax.SaveAt(t1=True), max_steps=max_steps,
                                  throw=False)
        ok = ((sol.result == diffrax.RESULTS.successful)
              | (sol.result == diffrax.RESULTS.event_occurred))
        return (sol.ys[-1], sol.event_mask, ok,
                sol.result == diffrax.RESULTS.max_steps_reached,
                sol.stats["num_accepted_steps"], sol.stats["num_rejected_steps"])

    return one


def run_diffrax(coin: Coin, states: np.ndarray, solver_name: str, rtol: float, max_steps: int,
                repeats: int, vmap: bool = True):
    """jax.jit(jax.vmap(one)) on the whole batch at once (the JAX idiom), or, with vmap=False,
    jax.jit(one) called once per throw from Python."""
    import jax
    import jax.numpy as jnp

    one = diffrax_solve_one(coin, solver_name, rtol, max_steps)
    if vmap:
        y0 = jnp.asarray(states)
        batch = jax.jit(jax.vmap(one))

        def run():
            return jax.block_until_ready(batch(y0))
    else:
        single = jax.jit(one)

        def run():
            outs = [jax.block_until_ready(single(row)) for row in states]  # numpy rows
            return tuple(np.stack([np.asarray(o[j]) for o in outs]) for j in range(6))

    w0, c0 = time.perf_counter(), time.process_time()
    if vmap:
        run()  # trace + compile + one run of the batch
    else:
        jax.block_until_ready(single(states[0]))  # trace + compile + one throw
    first_wall, first_cpu = time.perf_counter() - w0, time.process_time() - c0
    out, walls, cpus = timed_repeats(run, repeats)
    final, fired, ok, max_steps_hit, steps, rejected = (np.asarray(a) for a in out)
    n = len(states)
    labels = np.full(n, NO_LABEL, np.int64)
    status = np.full(n, STATUS_UNSETTLED, int)
    for i in range(n):
        if not ok[i]:
            status[i] = STATUS_FAILED  # max_steps reached, or another solver failure
        elif fired[i]:
            status[i] = STATUS_SETTLED
            labels[i] = well_index(coin, float(final[i, 2]))
    run_one = statistics.median(walls) / (1 if vmap else n)
    compile_wall = max(first_wall - run_one, 0.0)
    return {"labels": labels, "status": status, "steps": steps.astype(int),
            "rejected": rejected.astype(int), "max_steps_reached": int(max_steps_hit.sum()),
            "walls": walls, "cpus": cpus, "first_call_wall": first_wall,
            "first_call_cpu": first_cpu, "compile_wall": compile_wall}


# -- bookkeeping ------------------------------------------------------------------------------
def versions() -> dict:
    out = {"python": platform.python_version()}
    for name in ("numpy", "scipy", "numba", "jax", "jaxlib", "diffrax", "equinox",
                 "optimistix", "lineax"):
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = None
    try:
        import coincli
        out["coincli"] = coincli.__version__
    except Exception as exc:  # noqa: BLE001
        out["coincli"] = f"not importable: {exc}"
    try:
        out["coincli_git"] = subprocess.run(
            ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True,
            check=True).stdout.strip()
    except Exception:  # noqa: BLE001
        out["coincli_git"] = None
    return out


def machine() -> dict:
    info = {"cpu_count": os.cpu_count(), "platform": platform.platform(),
            "processor": platform.processor() or platform.machine()}
    if hasattr(os, "sched_getaffinity"):
        info["cpus_usable"] = len(os.sched_getaffinity(0))
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    info["cpu_model"] = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    if hasattr(os, "getloadavg"):
        info["loadavg_1_5_15min"] = list(os.getloadavg())
    info["env"] = {k: os.environ.get(k) for k in ("XLA_FLAGS", "OMP_NUM_THREADS",
                                                  "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                                  "OPENBLAS_CORETYPE")}
    return info


def agreement(labels: np.ndarray, reference: np.ndarray, robust: np.ndarray) -> dict:
    hit = labels == reference
    n = int(robust.sum())
    return {"robust_cells": n, "agree": int(hit[robust].sum()),
            "fraction": float(hit[robust].mean()) if n else math.nan,
            "disagreeing_cells": [int(i) for i in np.flatnonzero(robust & ~hit)]}


def status_counts(status: np.ndarray) -> dict:
    return {STATUS_NAMES[s]: int(np.sum(status == s)) for s in STATUS_NAMES if np.any(status == s)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true",
                    help="16 throws (a 4 x 4 subset of the grid) and one repeat: a smoke run")
    ap.add_argument("--peers", default="scipy,diffrax",
                    help="comma-separated: scipy, diffrax, or single methods such as "
                         "scipy:RK45, diffrax:Tsit5 (default: scipy,diffrax)")
    ap.add_argument("--out", default=None,
                    help="JSON output file (default benchmarks/peers.json, or "
                         "benchmarks/peers-quick.json with --quick)")
    ap.add_argument("--repeats", type=int, default=3,
                    help="timed repeats of each peer's batch (median reported); ours gets "
                         "max(5, this)")
    ap.add_argument("--rtol", type=float, default=RTOL)
    ap.add_argument("--timeout", type=float, default=10.0,
                    help="wall seconds allowed per scipy trajectory before it is abandoned")
    ap.add_argument("--radau-every", type=int, default=1,
                    help="scipy Radau (always one repeat) runs every N-th throw only")
    ap.add_argument("--max-steps", type=int, default=200_000, help="diffrax max_steps")
    args = ap.parse_args(argv)

    wanted = []
    for item in args.peers.split(","):
        item = item.strip()
        if not item:
            continue
        lib, _, meth = item.partition(":")
        if lib == "scipy":
            wanted += [("scipy", m, False) for m in SCIPY_METHODS if not meth or m == meth]
        elif lib == "diffrax":
            wanted += [("diffrax", m, vm) for vm in (True, False) for m in DIFFRAX_SOLVERS
                       if not meth or m == meth]
        else:
            ap.error(f"unknown peer {item!r}: use scipy, diffrax, scipy:RK45, diffrax:Tsit5, ...")

    if any(w[0] == "diffrax" for w in wanted):
        import jax
        jax.config.update("jax_enable_x64", True)

    machine_start = machine()
    scene = load_scene()
    coin = coin_of(scene)
    vy_all = np.linspace(*VY_RANGE, GRID_RES)
    vphi_all = np.linspace(*VPHI_RANGE, GRID_RES)
    idx = QUICK_INDEX if args.quick else list(range(GRID_RES))
    vy, vphi = vy_all[idx], vphi_all[idx]
    vy_g, vphi_g = np.meshgrid(vy, vphi, indexing="ij")
    states = coin.initial_states(vy_g, vphi_g)
    n = len(states)
    repeats = 1 if args.quick else args.repeats
    log = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731

    log(f"{n} throws: vy0 in {VY_RANGE} m/s, vphi0 in {VPHI_RANGE} rad/s; rtol = {args.rtol:g}")
    log("references (coincli: event rtol=1e-12 and rk4 h=2.5e-7) ...")
    t0 = time.perf_counter()
    refs = references(scene, vy, vphi)
    ref_seconds = time.perf_counter() - t0
    (ref_a, st_a), (ref_b, st_b) = refs.values()
    robust = (st_a == 0) & (st_b == 0) & (ref_a == ref_b)
    log(f"  {int(robust.sum())} of {n} cells robust ({ref_seconds:.1f} s)")

    check = model_check(scene, coin, any(w[0] == "diffrax" for w in wanted))
    worst = max(check["trajectory_error_natural_units"])
    log(f"model check: peers' model vs ours, state error {worst:.1e}"
        " (natural units)")

    results = []

    # ours
    log("ours (coincli event method) ...")
    ours_runs, ours_cpu = [], []
    for _ in range(max(5, repeats)):
        c0 = time.process_time()  # around the whole call: includes its one-throw warm-up
        ours_runs.append(ours(scene, states, args.rtol))
        ours_cpu.append((time.process_time() - c0) / n)
    ours_labels = ours_runs[-1][0]
    ours_s = statistics.median(r[1] for r in ours_runs)
    results.append({
        "method": "coincli event", "library": "coincli", "throws": n,
        "seconds_per_trajectory": ours_s,
        "seconds_per_trajectory_repeats": [r[1] for r in ours_runs],
        "cpu_seconds_per_trajectory": statistics.median(ours_cpu),
        "threads": 1, "labels": ours_labels.tolist(),
        "status": status_counts(np.where(ours_labels == NO_LABEL, STATUS_UNSETTLED,
                                         STATUS_SETTLED)),
        "agreement": agreement(ours_labels, ref_a, robust),
        "notes": ["numba, 1 thread, warmed up"],
    })
    log(f"  {ours_s * 1e3:.3f} ms/trajectory")

    for lib, meth, vmap in wanted:
        if lib == "scipy":
            sub = np.arange(n)
            reps = repeats
            notes = ["Python RHS, 1 thread"]
            if meth == "Radau":  # slow: one repeat, optionally a subset of the throws
                reps = 1
                if args.radau_every > 1:
                    sub = np.arange(0, n, args.radau_every)
                    notes.append(f"every {args.radau_every}th throw only ({sub.size} of {n})")
                notes.append("finite-difference Jacobian; 1 repeat")
            log(f"scipy solve_ivp {meth} on {sub.size} throws x {reps} ...")
            res, walls, cpus = timed_repeats(
                lambda sub=sub, meth=meth: run_scipy(coin, states[sub], meth, args.rtol,
                                                     args.timeout), reps)
            per = statistics.median(walls) / sub.size
            labels = np.full(n, NO_LABEL, np.int64)
            labels[sub] = res["labels"]
            status = res["status"]
            rob = np.zeros(n, bool)
            rob[sub] = robust[sub]
            counts = status_counts(status)
            if counts.get("timeout"):
                notes.append(f"{counts['timeout']} timed out after {args.timeout:g} s "
                             "(counted at the timeout, labelled wrong)")
            if counts.get("failed"):
                notes.append(f"{counts['failed']} failed: "
                             + "; ".join(sorted(set(res["messages"].values()))))
            if counts.get("unsettled"):
                notes.append(f"{counts['unsettled']} not settled by t = {T_END:g} s")
            results.append({
                "method": f"scipy solve_ivp {meth}", "library": "scipy", "throws": int(sub.size),
                "subset": sub.tolist() if sub.size < n else None,
                "seconds_per_trajectory": per,
                "cpu_seconds_per_trajectory": statistics.median(cpus) / sub.size,
                "batch_wall_seconds": walls, "batch_cpu_seconds": cpus,
                "cpu_per_wall": sum(cpus) / sum(walls), "threads": 1,
                "labels": labels.tolist(), "status": counts,
                "per_trajectory_seconds": res["seconds"].tolist(),
                "nfev_median": float(np.median(res["nfev"])),
                "steps_median": float(np.median(res["steps"])),
                "steps_max": int(res["steps"].max()),
                "agreement": agreement(labels, ref_a, rob), "notes": notes,
            })
            log(f"  {per * 1e3:.2f} ms/trajectory, {counts}")
        else:
            import jax
            how = "jit+vmap" if vmap else "jit, loop"
            log(f"diffrax {meth} ({how}, {n} throws) x {repeats} ...")
            res = run_diffrax(coin, states, meth, args.rtol, args.max_steps, repeats, vmap)
            per = statistics.median(res["walls"]) / n
            counts = status_counts(res["status"])
            notes = [f"compile {res['compile_wall']:.1f} s (excluded)"]
            if counts.get("failed"):
                notes.append(f"{counts['failed']} failed ({res['max_steps_reached']} reached "
                             f"max_steps = {args.max_steps})")
            if counts.get("unsettled"):
                notes.append(f"{counts['unsettled']} not settled by t = {T_END:g} s")
            cpu_per_wall = sum(res["cpus"]) / sum(res["walls"])
            results.append({
                "method": f"diffrax {meth} ({how})", "library": "diffrax", "throws": n,
                "vmap": vmap,
                "seconds_per_trajectory": per,
                "cpu_seconds_per_trajectory": statistics.median(res["cpus"]) / n,
                "batch_wall_seconds": res["walls"], "batch_cpu_seconds": res["cpus"],
                "cpu_per_wall": cpu_per_wall,
                "first_call_wall_seconds": res["first_call_wall"],
                "first_call_cpu_seconds": res["first_call_cpu"],
                "compile_seconds": res["compile_wall"],
                "jax_devices": [str(d) for d in jax.devices()],
                "process_threads": len(os.listdir("/proc/self/task"))
                if os.path.isdir("/proc/self/task") else None,
                "labels": res["labels"].tolist(), "status": counts,
                "steps_median": float(np.median(res["steps"])),
                "steps_max": int(res["steps"].max()),
                "rejected_steps_median": float(np.median(res["rejected"])),
                "agreement": agreement(res["labels"], ref_a, robust), "notes": notes,
            })
            log(f"  {per * 1e3:.2f} ms/trajectory (CPU/wall {cpu_per_wall:.2f}), {counts}, "
                f"compile {res['compile_wall']:.1f} s")

    for r in results:
        r["x_slower_than_ours"] = r["seconds_per_trajectory"] / ours_s

    report = {
        "command": " ".join([sys.executable] + sys.argv),
        "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "quick": args.quick,
        "grid": {"vy0": vy.tolist(), "vphi0": vphi.tolist(), "indexing": "ij (vy0 major)",
                 "full_grid": f"{GRID_RES} x {GRID_RES} np.linspace over {VY_RANGE} x "
                              f"{VPHI_RANGE}"},
        "throws": n, "t_end": T_END, "rtol": args.rtol, "atol": coin.atol(args.rtol).tolist(),
        "atol_rule": "rtol x (r, r, 1 rad, sqrt(2 g r), sqrt(2 g r), sqrt(2 g r) / r)",
        "repeats": repeats, "timeout_per_scipy_trajectory": args.timeout,
        "diffrax_max_steps": args.max_steps,
        "coin": {k: getattr(coin, k) for k in ("d", "t", "m", "inertia", "k", "c", "g")}
        | {"r": coin.r, "e_crit": coin.e_crit},
        "references": {name: {"labels": lab.tolist(), "status": st.tolist()}
                       for name, (lab, st) in refs.items()},
        "references_seconds": ref_seconds,
        "model_check": check,
        "robust_cells": int(robust.sum()), "robust_mask": robust.astype(int).tolist(),
        "versions": versions(), "machine_at_start": machine_start, "machine": machine(),
        "results": results,
    }
    out = Path(args.out or HERE / ("peers-quick.json" if args.quick else "peers.json"))
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=1, allow_nan=False, default=float) + "\n")
    print(markdown_table(report))
    log(f"wrote {out}")
    return 0


def markdown_table(report: dict) -> str:
    load = report["machine_at_start"].get("loadavg_1_5_15min", [math.nan])[0]
    lines = [f"{report['throws']} throws, rtol = {report['rtol']:g}, "
             f"{report['robust_cells']} robust cells (references agree and settled); "
             f"wall ms per trajectory, median of {report['repeats']} repeats, one process; "
             f"{report['machine']['cpu_count']} cores, load average {load:.2f} at start",
             "",
             "| method | ms/trajectory | x slower than ours | CPU ms/trajectory "
             "| label agreement on robust cells | notes |",
             "|---|---:|---:|---:|---:|---|"]
    for r in report["results"]:
        a = r["agreement"]
        notes = list(r["notes"])
        if "cpu_per_wall" in r and r["library"] == "diffrax":
            notes.append(f"CPU/wall {r['cpu_per_wall']:.2f}")
        if r.get("steps_median") is not None:
            notes.append(f"median {r['steps_median']:.0f} accepted steps")
        lines.append(
            f"| {r['method']} | {r['seconds_per_trajectory'] * 1e3:.3g} | "
            f"{r['x_slower_than_ours']:.0f} | {r['cpu_seconds_per_trajectory'] * 1e3:.3g} | "
            f"{a['agree']}/{a['robust_cells']} "
            f"({100 * a['fraction']:.1f} %) | {'; '.join(notes)} |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
