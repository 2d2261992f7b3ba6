"""The tables and the second figure of docs/thickness-damping.md, from the store of its run.

The run (docs/thickness-damping.md; 2,698 CPU s, an hour on one thread):

    coin fractions --y0 r:5r --phi0 -pi:pi --vx -0.5:0.5 --over thickness=... --over c=... \\
        --samples 16k --threads 1 --store thickness-damping.zarr --plot docs/thickness-damping.png

then, reading that store (the same run: nothing is computed when it is complete):

    python benchmarks/thickness_damping.py thickness-damping.zarr

prints the page's tables (markdown), draws docs/thickness-damping-crossing.png and writes
benchmarks/thickness-damping.json (every point's estimates, so the tables can be checked
without the store). With ``--landing N`` it also follows N throws of the same box one by one at
a few dampings (single passes, with their contact events): the well the coin first lands in
(the well of its angle at its first contact) against the one it ends in, and how it left the
first: after leaving the foundation again (a bounce), or rolling over a corner without leaving
it; and over more dampings, how many of the throws that land in a standing well, and in a
lying one, stay there (about 6 minutes for N = 2000).

For each c: the t/d at which P(standing) = 1/3, over the certain labels and over all decided
ones, each with the interval where the 95 % intervals of the grid cross 1/3
(FractionsOver.crossing); the corner's coefficient of restitution at that thickness
(coincli.montecarlo.corner_restitution): the corner under the centroid (the whole mass behind
it) and the corner of a coin landing flat (lever d/2).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import coincli  # noqa: E402
from coincli.files import save_figure  # noqa: E402
from coincli.montecarlo import corner_restitution, pender_uhrin, point_scene  # noqa: E402

D = 0.02  # m, the paper coin's diameter
T_D = [0.05 * i for i in range(1, 10)] + [0.5 + 0.025 * i for i in range(21)]
THICKNESS = [round(D * q, 6) for q in T_D]
C = [0.05, 0.1, 0.2, 0.5, 1, 2, 4, 8, 16, 32, 64, 128]
BOX = dict(y0="r:5r", phi0="-pi:pi", vx="-0.5:0.5")  # vy, vphi: coin basin's default ranges
SAMPLES = 16_000
GEOMETRIC = 1 / math.sqrt(3)  # (2/pi) arctan(t/d) = 1/3
SLICES = (0.5, 0.6, 0.7, 0.8, 0.9, 1.0)  # t/d of the table of P(standing)


def run(store: str):
    return coincli.fractions_over(coincli.load_preset("paper"),
                                  over={"thickness": THICKNESS, "c": C}, samples=SAMPLES,
                                  store=store, threads=1, **BOX)


def pender_uhrin_third() -> float:
    from scipy.optimize import brentq

    return brentq(lambda q: pender_uhrin(q) - 1 / 3, 0.1, 1.0)


def restitutions(base, t_d: float, c: float) -> tuple[float, float]:
    """e of the corner under the centroid and of a corner of a coin landing flat, at t/d."""
    scene = point_scene(base, {"thickness": D * t_d, "c": c})
    return corner_restitution(scene), corner_restitution(scene, lever=scene.coin.r_d)


def interval(at: float, lo: float, hi: float) -> str:
    def show(v: float) -> str:
        return "-" if math.isnan(v) else f"{v:.3f}"
    return f"{show(at)} ({show(lo)} to {show(hi)})"


def crossing_table(result, base) -> tuple[str, list[dict]]:
    certain = result.crossing(basis="certain")
    decided = result.crossing(basis="decided")
    rows = []
    lines = ["| c (N s/m) | e, corner under the centroid | e, corner of a coin landing flat "
             "| t/d at P = 1/3, certain labels (95 %) | t/d at P = 1/3, all decided labels "
             "(95 %) |", "|---|---|---|---|---|"]
    for j, c in enumerate(C):
        cert = tuple(float(certain[k][j]) / D for k in ("at", "from", "to"))
        dec = tuple(float(decided[k][j]) / D for k in ("at", "from", "to"))
        e0, e_flat = restitutions(base, dec[0], c)
        rows.append({"c": c, "e_under_centroid": e0, "e_flat": e_flat,
                     "t_d_certain": cert, "t_d_decided": dec})
        lines.append(f"| {c:g} | {e0:.3g} | {e_flat:.3g} | {interval(*cert)} | "
                     f"{interval(*dec)} |")
    return "\n".join(lines), rows


def slice_table(result) -> str:
    """P(standing) over the certain and over all decided labels, and the uncertain share, at
    the SLICES of t/d, one row per c."""
    head = " | ".join(f"t/d = {q:g}" for q in SLICES)
    lines = [f"| c (N s/m) | {head} |", "|---|" + "---|" * len(SLICES)]
    index = {round(q, 4): i for i, q in enumerate(T_D)}
    for j, c in enumerate(C):
        cells = []
        for q in SLICES:
            r = result.results[index[round(q, 4)] * len(C) + j]
            cells.append(f"{100 * r.standing['probability']:.1f} / "
                         f"{100 * r.all_decided['standing']['probability']:.1f} / "
                         f"{100 * r.uncertain['probability']:.0f}")
        lines.append(f"| {c:g} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def draw(result, rows: list[dict], out: Path) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.3), layout="constrained")
    left, right = fig.subplots(1, 2)
    e = np.array([row["e_under_centroid"] for row in rows])
    c = np.array(C, dtype=float)
    for key, colour, label, shift in (("t_d_certain", "#000000", "certain labels", 0.97),
                                      ("t_d_decided", "#1f77b4", "all decided labels", 1.03)):
        at, lo, hi = np.array([row[key] for row in rows]).T
        left.errorbar(c * shift, at, yerr=[at - lo, hi - at], fmt="o-", ms=4, lw=1.2,
                      color=colour, capsize=3, label=f"P(standing) = 1/3, {label} (95 %)")
    pu = pender_uhrin_third()
    left.axhline(pu, color="#d62728", ls="-.", lw=1.2,
                 label=f"Pender & Uhrin, bouncy planar die: {pu:.3f}")
    left.axhline(GEOMETRIC, color="#ff7f0e", ls=":", lw=1.5,
                 label=f"no bounce, (2/pi) arctan(t/d) = 1/3: {GEOMETRIC:.3f}")
    left.set_xscale("log")
    left.set_xlabel("c (N s/m), damping of each corner")
    left.set_ylabel("t / d at which P(standing) = 1/3")
    top = left.secondary_xaxis("top", functions=(lambda x: x, lambda x: x))
    top.set_ticks(c[::2], labels=[f"{v:.3g}" for v in e[::2]])
    top.set_xlabel("e, the corner's restitution at that thickness (corner under the centroid)")
    left.set_ylim(0.5, 0.9)
    left.legend(fontsize=7, loc="lower left")
    left.grid(True, alpha=0.3)

    ratio = np.array(T_D)
    fine = np.linspace(ratio.min(), ratio.max(), 400)
    standing = result.estimate("decided")
    from matplotlib import colormaps

    colours = colormaps["viridis"]
    for j, cj in enumerate(C):
        if cj not in (0.05, 0.5, 4, 32, 128):
            continue
        p, lo, hi = standing[:, j].T
        colour = colours(j / (len(C) - 1))
        right.fill_between(ratio, lo, hi, color=colour, alpha=0.3, lw=0)
        right.plot(ratio, p, "o-", ms=2.5, lw=1, color=colour,
                   label=f"c = {cj:g} N s/m (e = {e[j]:.3g})")
    right.plot(fine, pender_uhrin(fine), "-.", color="#d62728", lw=1.2,
               label="Pender & Uhrin, bouncy planar die")
    right.plot(fine, 2 / np.pi * np.arctan(fine), ":", color="#ff7f0e", lw=1.5,
               label="no bounce, (2/pi) arctan(t/d)")
    right.axhline(1 / 3, color="grey", lw=0.8)
    right.set_xlabel("t / d")
    right.set_ylabel("P(standing), all decided labels (95 % bands)")
    right.legend(fontsize=7, loc="upper left")
    right.grid(True, alpha=0.3)
    fig.suptitle(f"P(standing) = 1/3 against the damping: {SAMPLES:,} throws a point, the same "
                 "throws at every point", fontsize=9)
    save_figure(fig, out, 150)  # with the version that made it in its metadata


LANDING = [(t_d, c) for t_d in (0.6, 0.8) for c in (0.5, 8, 32, 128)]  # the landing table's
WELLS = [(t_d, c) for t_d in (0.5, 0.8) for c in (0.5, 1, 2, 4, 8, 16, 32, 128)]  # the wells'


def landing(n: int, points) -> dict[tuple[float, float], dict]:
    """Where N throws of the box first land and where they end, at each (t/d, c) of
    ``points``: how many end where they landed, how many leave it after a bounce or rolling,
    and how many of those that land in a standing well, and in a lying one, end in it."""
    from coincli.models import model_of, model_params
    from coincli.montecarlo import Draws, initial_states, make_sampling

    base = coincli.load_preset("paper")
    out = {}
    for t_d, c in points:
        scene = point_scene(base, {"thickness": D * t_d, "c": c})
        p = model_params(scene)
        well_index = model_of(scene).kernels("python").well_index
        sampling = make_sampling(scene, **BOX)
        counts = dict.fromkeys(("stays", "bounced", "rolled"), 0)
        landed = {True: 0, False: 0}  # by whether the coin first lands standing
        stayed = {True: 0, False: 0}
        ends_standing = 0
        for state in initial_states(scene, sampling, Draws(sampling).batch(0)[:n]):
            throw = coincli.simulate(scene, verify=False, record_events=True, y0=state[1],
                                     phi0=state[2], vx=state[3], vy=state[4], vphi=state[5])
            kinds = throw.events[:, 2]  # +1 a corner's onset, -1 its lift-off
            lands = well_index(p, throw.events[0, 5])  # phi at the first contact
            airborne = bool(np.any(np.cumsum(kinds)[1:] == 0))  # no corner touching, later
            end = throw.quarter_turns
            counts["stays" if end == lands else "bounced" if airborne else "rolled"] += 1
            standing = bool(lands % 2 != 0)
            landed[standing] += 1
            stayed[standing] += end == lands
            ends_standing += end % 2 != 0
        out[(t_d, c)] = {
            "c": c, "t_d": t_d, "throws": n, "lands_standing": landed[True] / n,
            "ends_standing": ends_standing / n,
            **{key: value / n for key, value in counts.items()},
            "stays_if_standing": stayed[True] / max(landed[True], 1),
            "stays_if_lying": stayed[False] / max(landed[False], 1),
            "e_under_centroid": corner_restitution(scene),
            "e_flat": corner_restitution(scene, lever=scene.coin.r_d)}
    return out


LANDING_SHARES = {"lands_standing": "lands standing", "ends_standing": "ends standing",
                  "stays": "ends where it landed", "bounced": "leaves after a bounce",
                  "rolled": "rolls out without leaving"}
WELLS_SHARES = {"ends_standing": "ends standing",
                "stays_if_standing": "of those landing standing, stay",
                "stays_if_lying": "of those landing lying, stay"}


def shares_table(rows: list[dict], shares: dict[str, str]) -> str:
    """Rows of :func:`landing` as a markdown table: the point, its corners' restitution, and
    the ``shares`` (key: header) in per cent."""
    head = ["t/d", "c (N s/m)", "e (under the centroid / flat)", *shares.values()]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [f"{r['t_d']:g}", f"{r['c']:g}",
                 f"{r['e_under_centroid']:.2g} / {r['e_flat']:.2g}",
                 *(f"{100 * r[key]:.1f} %" for key in shares)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("store", help="the store of the run of docs/thickness-damping.md")
    parser.add_argument("--landing", type=int, default=0, metavar="N",
                        help="also follow N throws one by one at t/d 0.5, 0.6 and 0.8")
    args = parser.parse_args()
    result = run(args.store)
    if result.cost.get("computed"):
        print(f"note: {result.cost['computed']:,} samples computed (the store was not "
              "complete)", file=sys.stderr)
    base = coincli.load_preset("paper")
    table, rows = crossing_table(result, base)
    print(table, end="\n\n")
    print(slice_table(result), end="\n\n")
    from coincli.stores.fractions_store import FractionsStore

    records = FractionsStore(args.store).runs()
    cpu = sum(r["cpu_seconds"] for r in records)
    wall = sum(r["wall_seconds"] for r in records)
    samples = sum(r["samples"] for r in records)
    print(f"cost: {samples:,} throws, {cpu:,.0f} CPU s ({1e3 * cpu / max(samples, 1):.3g} ms "
          f"a throw), {wall:,.0f} s wall over {len(records)} run(s): "
          + "; ".join(f"{r['mode']} x {r['workers']}" for r in records))
    draw(result, rows, ROOT / "docs" / "thickness-damping-crossing.png")
    points = [{"at": r.at, "t_d": r.scene["coin"]["thickness"] / D, "samples": r.samples,
               "certain": r.standing, "all_decided": r.all_decided["standing"],
               "uncertain": r.uncertain} for r in result.results]
    landed = landing(args.landing, dict.fromkeys(LANDING + WELLS)) if args.landing else {}
    if landed:
        print(shares_table([landed[point] for point in LANDING], LANDING_SHARES), end="\n\n")
        print(shares_table([landed[point] for point in WELLS], WELLS_SHARES), end="\n\n")
    out = {"command": "python benchmarks/thickness_damping.py STORE --landing "
                      f"{args.landing}", "samples": SAMPLES, "box": BOX, "crossing": rows,
           "points": points, "runs": records, "landing": list(landed.values())}
    (ROOT / "benchmarks" / "thickness-damping.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
