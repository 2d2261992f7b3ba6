"""`coin accuracy`: the work-precision chart, and where each fixed-step method fails."""

from pathlib import Path
from typing import Annotated

import typer
from rich import box
from rich.table import Table

from ..api import Method, ParameterError
from .app import app
from .common import (
    COpt,
    DiameterOpt,
    GOpt,
    InertiaOpt,
    JsonOpt,
    KOpt,
    MassOpt,
    MuOpt,
    PresetOpt,
    SlipVelocityOpt,
    ThicknessOpt,
    build_scene,
    compile_first,
    console,
    err_console,
    fail,
    print_json,
    user_errors,
    whole_option,
)
from .text import percent, say


@app.command("accuracy")
def accuracy_command(
    out: Annotated[Path, typer.Option("--out", "-o", help="Chart: PNG, SVG or PDF.")] = Path(
        "accuracy.png"),
    table: Annotated[Path | None, typer.Option("--table", help="Table of every point (.json "
                                               "or .csv); default: next to the chart.")] = None,
    res: Annotated[str, typer.Option("--res", metavar="N|NxM",
                                     help="Label grid, N or NxM (vy0 x vphi0).")] = "32",
    vy_range: Annotated[str, typer.Option("--vy", "--vy-range", metavar="LO:HI",
                                          help="vy0 range, m/s.")] = "0.05:2",
    vphi_range: Annotated[str, typer.Option("--vphi", "--vphi-range", metavar="LO:HI",
                                            help="vphi0 range, rad/s.")] = "-20:20",
    methods: Annotated[str, typer.Option("--methods", help="Comma-separated methods "
                                         "(default: all of them, see coin methods).",
                                         show_default=False)] = ",".join(
        m.label for m in Method),
    quick: Annotated[bool, typer.Option("--quick", metavar="",
                                        help="Two settings per method (a smoke "
                                        "test, not a chart to trust).")] = False,
    threads: Annotated[int | None, typer.Option("--threads", help="Threads (default: one per "
                                                "core).", parser=whole_option, metavar="N")] = None,
    stability: Annotated[bool, typer.Option("--stability", metavar="", help="Only find where each "
                                            "fixed-step method fails (bisection).")] = False,
    preset: PresetOpt = "paper", diameter: DiameterOpt = None, thickness: ThicknessOpt = None,
    mass: MassOpt = None, inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None,
    mu: MuOpt = None, slip_velocity: SlipVelocityOpt = None, g: GOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Chart accuracy against cost for every method, or (--stability) find where they fail.

    Trajectory error: the state of five throws ~0.06 s after their first impact against the event method at rtol 1e-12. Label error: the fraction of robust cells of a basin grid whose n differs from that reference; robust cells are those where it agrees with RK4 at h = 2.5e-7.
    """  # noqa: E501
    from ..api import studies
    from ..api.options import check_figure_path, check_writable
    from ..api.words import describe_error

    with user_errors():
        scene = build_scene(preset, diameter=diameter, thickness=thickness, mass=mass,
                            inertia=inertia, k=k, c=c, mu=mu, slip_velocity=slip_velocity,
                            g=g)
        if stability:
            run_stability(scene, json_out)
            return
        plan = studies.plan_accuracy(scene, vy=vy_range, vphi=vphi_range, res=res,
                                     methods=methods, quick=quick, threads=threads)
        check_figure_path(out, "chart")
        table = table or out.with_suffix(".json")
        if table.suffix not in (".json", ".csv"):
            raise ParameterError(f"--table must end in .json or .csv, got {table}")
        # both outputs writable before minutes of computing
        check_writable(out, what="chart", create_parents=True)
        check_writable(table, what="table", create_parents=True)
    compile_first(scene=scene)
    with console.status("") as status:
        study = studies.accuracy_study(
            plan, progress=lambda text: status.update(f"accuracy: {text}"))
    grid = plan.grid
    try:
        studies.plot_accuracy(study, out, title=f"coin {scene.coin.diameter * 1e3:g} x "
                                                f"{scene.coin.thickness * 1e3:g} mm, k = "
                                                f"{scene.foundation.k:g} N/m, c = "
                                                f"{scene.foundation.c:g} N s/m; grid "
                                                f"{grid.shape[0]} x {grid.shape[1]} over vy0 "
                                                f"{vy_range}, vphi0 {vphi_range}")
    except OSError as exc:
        raise fail(describe_error(exc, f"cannot write {out}")) from None
    try:
        studies.write_accuracy_table(study, table, scene)
    except OSError as exc:
        raise fail(describe_error(exc, f"cannot write {table}")) from None
    if json_out:
        print_json(__import__("json").loads(table.read_text()) if table.suffix == ".json"
                   else {"table": str(table)})
        return
    print_study(study)
    say(console, f"chart: {out}   table: {table}")


def print_study(study) -> None:
    cells = study.robust.size
    say(console, f"References on {cells} cells: event at rtol = 1e-12 and rk4 at h = 2.5e-7 "
                 f"agree on {percent(study.reference_agreement)}; the {study.robust_cells} "
                 "cells where both settle to the same n are the robust cells.")
    say(console, f"Trajectory reference: event and dopri5 at rtol = 1e-12 differ by "
                 f"{study.trajectory_reference_gap:.1e} (median state error, natural units).")
    table = Table(title="Work and precision (labels: robust cells)", title_justify="left",
                  box=box.SIMPLE_HEAD, pad_edge=False)
    for col in ("method", "setting", "CPU ms", "state err", "wrong", "no label"):
        table.add_column(col, justify="left" if col in ("method", "setting") else "right",
                         no_wrap=True)
    best = study.best_under(0.01)
    for p in study.points:
        table.add_row(p.setting.method.label, f"{'rtol' if p.setting.adaptive else 'h'}="
                      f"{p.setting.knob:g}" + (" *" if best is p else ""),
                      f"{p.cpu_per_trajectory * 1e3:.3g}", f"{p.trajectory_error:.2e}",
                      percent(p.label_error), f"{p.nonfinite + p.unsettled:,}")
    if study.paper_point is not None:
        pp = study.paper_point
        table.add_row("[bold]paper[/]", "h=1e-6, 2 s", f"{pp.cpu_per_trajectory * 1e3:.3g}",
                      f"{pp.trajectory_error:.2e}", percent(pp.label_error), "")
    console.print(table)
    if best is not None:
        say(console, "* the cheapest setting whose label error is below 1 % with 95 % "
                     "confidence. CPU ms: per trajectory. state err: after the first impacts, "
                     "natural units. wrong: robust cells with another n than the reference. "
                     "no label: cells that went non-finite or were not decided by t_end. "
                     "paper: symplectic Euler over the full 2 s.")
    vp = study.verified_point
    if vp is not None:
        say(console, f"[bold]Default, verified[/] ({vp.setting.label}): "
                     f"{vp.cpu_per_trajectory * 1e3:.3g} ms a cell; of the {study.robust_cells} "
                     f"robust cells {percent(vp.label_error)} certain and wrong, "
                     f"{percent(vp.uncertain)} uncertain.")


def run_stability(scene, json_out: bool) -> None:
    from ..api.studies import step_limits

    compile_first(scene=scene)  # the bisection runs the compiled kernels
    with console.status("bisecting the failing step of each fixed-step method"):
        limits = step_limits(scene)
    if json_out:
        print_json(limits.to_dict())
        return
    friction = scene.foundation.mu > 0
    damped = scene.foundation.c > 0
    table = Table(title="Where the fixed-step methods fail: a coin resting on two corners, "
                        f"kicked by {limits.kick} rad/s, run {limits.seconds} s; a "
                        "step fails if it goes non-finite or gains energy"
                        + (", or does not come to rest" if damped else ""),
                  title_justify="left")
    columns = ["method", "predicted stable step",
               *(["linearized at rest, with friction"] if friction else []),
               "measured failure step", "measured / predicted"]
    for col in columns:
        table.add_column(col, justify="right" if col != "method" else "left")
    for r in limits.methods:
        at_rest = [f"{r['at_rest_stable_step']:.3g} s"] if friction else []
        table.add_row(r["method"], f"{r['predicted_stable_step']:.3g} s", *at_rest,
                      f"{r['measured_failure_step']:.3g} s", f"{r['ratio']:.2f}")
    console.print(table)
    say(err_console, "predicted: spectral radius of the method's step on the damped rocking "
                     "mode"
        + (" and on friction's stick at rest, a decay of the slip, on a standing coin (its "
           "stick is stiffer than the lying coin's of the test)" if friction else "")
        + " (coin methods); simulate and basin refuse a larger --dt without --force."
        + (" Linearized at rest: the largest step whose map, linearized at the resting "
           "lying coin under the friction law, has spectral radius at most 1." if friction
           else ""))
