"""`coin simulate`: one trajectory, summarised."""

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ..api import Certainty, Status, __version__
from ..api.options import DEFAULT_LOG_EVERY
from .app import app
from .common import (
    COpt,
    DiameterOpt,
    DtOpt,
    ForceOpt,
    GOpt,
    InertiaOpt,
    JsonOpt,
    KOpt,
    MassOpt,
    MaxStepsOpt,
    MethodOpt,
    MuOpt,
    Phi0Opt,
    PresetOpt,
    RtolOpt,
    SinglePassOpt,
    SlipVelocityOpt,
    StopOpt,
    TEndOpt,
    ThicknessOpt,
    VphiOpt,
    VxOpt,
    VyOpt,
    X0Opt,
    Y0Opt,
    build_scene,
    compile_first,
    console,
    err_console,
    fail,
    print_json,
    user_errors,
)
from .recording import (
    REC,
    ConnectOpt,
    LogEveryOpt,
    SpawnOpt,
    check_log_every,
    destination,
    print_recording,
    record_throw,
)
from .text import LABEL_WIDTH, NBSP, percent, print_rows, say

RrdOpt = Annotated[Path, typer.Option("--rrd", metavar="PATH", help="Write the recording of the "
                                      "throw to this .rrd file (open it with `rerun PATH`).",
                                      rich_help_panel=REC)]
NoRrdOpt = Annotated[bool, typer.Option("--no-rrd", metavar="",
                                        help="Write no .rrd file (with neither "
                                        "--spawn nor --connect: print the numbers only).",
                                        rich_help_panel=REC)]
EXPORTS = "Exports"
CsvOpt = Annotated[Path | None, typer.Option("--csv", metavar="FILE", help="Write the sampled "
                                             "time series (state and energies, every "
                                             "--log-every s) as CSV, names and units in its "
                                             "header line.", rich_help_panel=EXPORTS)]
GifOpt = Annotated[Path | None, typer.Option("--gif", metavar="FILE", help="Write an animation "
                                             "of the throw: FILE.gif, or FILE.mp4 with ffmpeg on "
                                             "PATH (about 4 s, the throw slowed down to fit).",
                                             rich_help_panel=EXPORTS)]


@app.command("simulate")
def simulate_command(
    preset: PresetOpt = "paper",
    x0: X0Opt = None, y0: Y0Opt = None, phi0: Phi0Opt = None,
    vx: VxOpt = None, vy: VyOpt = None, vphi: VphiOpt = None,
    diameter: DiameterOpt = None, thickness: ThicknessOpt = None, mass: MassOpt = None,
    inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None, mu: MuOpt = None,
    slip_velocity: SlipVelocityOpt = None, g: GOpt = None, method: MethodOpt = None,
    dt: DtOpt = None, rtol: RtolOpt = None, t_end: TEndOpt = None,
    stop_on_settle: StopOpt = None, force: ForceOpt = False, single_pass: SinglePassOpt = False,
    max_steps: MaxStepsOpt = None, json_out: JsonOpt = False,
    rrd: RrdOpt = Path("coin.rrd"), no_rrd: NoRrdOpt = False, spawn: SpawnOpt = False,
    connect: ConnectOpt = None, log_every: LogEveryOpt = DEFAULT_LOG_EVERY, csv: CsvOpt = None,
    gif: GifOpt = None,
) -> None:
    """Run one throw and print its outcome: n quarter turns, lying or standing, and whether that label is certain.

    The throw is verified on a ladder of tighter settings (--single-pass: once). Its recording for the Rerun viewer is written to coin.rrd in the current folder unless told otherwise (--rrd FILE: there instead; --no-rrd: none); --csv and --gif export its time series and an animation.

    Example, the throw of the paper's fig. 2 (lying after six quarter turns here; from vy0 = 1.1974 m/s on it stands after seven, as the paper says):

    coin simulate --vy 1.197 --vphi 3.508
    """  # noqa: E501
    from ..api.throws import simulate  # coincli.simulate, without the rest of the API

    # checked before the run; --spawn without a display is said now, the outcome still follows
    where_to, no_viewer = destination(None if no_rrd else rrd, spawn, connect)
    recording = where_to is not None
    rrd_path, spawn, connect = ((where_to.rrd, where_to.spawn, where_to.connect) if recording
                                else (None, False, None))
    sampled = recording or csv is not None or gif is not None  # what needs the time series
    with user_errors():
        scene = build_scene(preset, x0=x0, y0=y0, phi0=phi0, vx=vx, vy=vy, vphi=vphi,
                            diameter=diameter, thickness=thickness, mass=mass, inertia=inertia,
                            k=k, c=c, mu=mu, slip_velocity=slip_velocity, g=g, method=method,
                            dt=dt, rtol=rtol, t_end=t_end,
                            stop_on_settle=stop_on_settle, max_steps=max_steps,
                            verify=False if single_pass else None)
        if sampled:  # --no-rrd is the way out when the recording's file alone asks for frames
            check_log_every(scene, log_every, no_rrd_helps=rrd_path is not None and not spawn
                             and not connect and csv is None and gif is None)
        _check_exports(csv, gif)
        _announce(scene)
        try:
            trajectory = simulate(scene, sample_dt=log_every if sampled else None,
                                  record_events=recording or gif is not None, force=force,
                                  before_compile=lambda: compile_first(scene=scene))
        except KeyboardInterrupt:
            err_console.print("[yellow]interrupted[/]: no outcome, nothing written")
            raise typer.Exit(code=130) from None
    info = None
    not_written = []  # (what, why) of each output asked for and not written
    try:
        if recording:
            info, why = record_throw(trajectory, rrd=rrd_path, spawn=spawn, connect=connect,
                                     log_every=log_every)
            if why is not None:
                not_written.append(("the recording", why))
        written = _write_exports(trajectory, csv, gif, not_written)
    except KeyboardInterrupt:  # the outcome is known: printed; each output complete or absent
        if not json_out:
            print_summary(trajectory)
        err_console.print("[yellow]interrupted[/] while writing the outputs: those not "
                          "finished are absent", highlight=False, soft_wrap=True)
        raise typer.Exit(code=130) from None
    if json_out:
        print_json({**trajectory.summary(), "version": __version__,
                    "parameters": scene.to_dict(),
                    "rrd": str(info.rrd) if info is not None and info.rrd is not None else None,
                    **{name: str(path) for name, path in written.items()}})
    else:
        print_summary(trajectory)
        if info is not None:
            print_recording(info)
        print_exports(trajectory, written)
    for what, why in not_written:  # after the outcome, which is printed whatever else failed
        if what != not_written[-1][0]:
            say(err_console, f"[bold red]error:[/] could not write {what}: {escape(why)}")
            continue
        raise fail(f"could not write {what}: {why}")
    if trajectory.status not in (Status.SETTLED, Status.UNSETTLED) or no_viewer:
        raise SystemExit(1)  # no outcome (non-finite, out of budget), or no viewer to open


SLOW_STEPS = 1e8  # fixed steps above which a run is announced (about 2 s of compiled work)


def _announce(scene) -> None:
    """Say before it starts how long a long fixed-step run will take at most."""
    from ..api.throws import step_bound
    from ..api.words import format_duration

    bound = step_bound(scene)  # every rung's budget, or the steps to the throw's cap
    if not (bound.adaptive and scene.integration.stop_on_settle):
        compile_first(scene=scene)  # not a short run: the compiled kernels do it
    if bound.adaptive:
        return
    steps, dts = bound.steps, bound.dts
    if steps > SLOW_STEPS:
        seconds = steps * 2e-8  # ~20 ns a step compiled, the paper's method
        rungs = (f"{dts[0]:g} s" if len(dts) == 1 else
                 f"{dts[0]:g} s down to {dts[-1]:g} s over {len(dts)} rungs")
        err_console.print(f"[yellow]note[/]: up to {steps:,} steps of {rungs} "
                          f"(about {format_duration(seconds)}); Ctrl-C stops it",
                          highlight=False)


def _check_exports(csv, gif) -> None:
    """Fail in one line, before the run, on a path --csv or --gif cannot write."""
    from ..api import ParameterError
    from ..api.options import check_animation_path, check_writable

    if csv is not None:
        check_writable(csv, what="--csv file")
    if gif is not None:
        try:
            check_animation_path(gif)
        except ParameterError as exc:
            raise fail(f"--gif {gif}: {exc}") from None


def _write_exports(trajectory, csv, gif, not_written: list) -> dict:
    """Write the CSV and the animation asked for: {"csv": path, "animation": path} of those
    written; (what, why) of the others appended to ``not_written``."""
    from ..api import ParameterError
    from ..api.words import describe_error

    written = {}
    for name, path, write in (("csv", csv, trajectory.to_csv),
                              ("animation", gif, trajectory.animate)):
        if path is None:
            continue
        if trajectory.samples is None or not len(trajectory.samples):
            not_written.append((str(path), "the run kept no samples"))
            continue
        try:
            written[name] = write(path)
        except OSError as exc:
            not_written.append((str(path), describe_error(exc)))
        except (ParameterError, RuntimeError, ValueError) as exc:
            not_written.append((str(path), str(exc)))
    return written


def print_exports(trajectory, written: dict) -> None:
    from ..api.options import DEFAULT_FPS, DEFAULT_SECONDS

    rows = []
    if "csv" in written:
        rows.append(("csv", f"{escape(str(written['csv']))}: {len(trajectory.samples):,} rows"))
    if "animation" in written:
        rows.append(("animation", f"{escape(str(written['animation']))}: {DEFAULT_SECONDS:g} s at "
                                  f"{DEFAULT_FPS} frames a second"))
    print_rows(console, rows, LABEL_WIDTH)


def outcome_text(tr) -> str:
    """The headline: the outcome and how sure it is, or why there is none."""
    if tr.status == Status.SETTLED:
        colour = "magenta" if tr.pose == "standing" else "cyan"
        text = f"n = {tr.quarter_turns} quarter turns: [{colour}]{tr.pose}[/]"
        if tr.certainty == Certainty.CERTAIN:
            return f"{text} (certain: {tr.rungs[-2].setting} and {tr.rungs[-1].setting} agree)"
        if tr.certainty == Certainty.UNCERTAIN:
            return (f"{text} [yellow](uncertain: no two rungs of the ladder agreed, every one "
                    "decided: chaotic at this precision)[/]")
        if tr.certainty == Certainty.UNDECIDED:
            return f"{text} [yellow](undecided: a rung of the ladder did not settle)[/]"
        return f"{text} (single pass, not verified)"
    if tr.status == Status.UNSETTLED:
        return (f"[yellow]none by t_end[/]: still moving at t = {tr.t_final:g} s "
                f"(round(2 phi / pi) = {tr.rounded_quarter_turns} there, not final)")
    if tr.status == Status.BUDGET:
        return f"[red]none[/]: the step budget ran out at t = {tr.t_final:.4g} s"
    if tr.status == Status.INTERRUPTED:
        return f"[red]none[/]: interrupted at t = {tr.t_final:.4g} s"
    return f"[red]none[/]: the run went non-finite near t = {tr.t_final:.4g} s"


SUGGESTED_MU = 0.3  # the coefficient a frictionless throw's line names (a coin on wood, about)
FRICTION_MATTERS = 0.01  # friction of SUGGESTED_MU taking this share of the energy is worth a try


def ladder_text(tr) -> str:
    """Each rung's n, and where a rung gave the n of the rung before it without agreeing with
    it (the ladder's rule: entering the final well and settling at the same moments), by how
    much its times differ: why the ladder climbed on."""
    from ..api.words import ladder_of

    ladder = ladder_of(tr.scene)
    parts = []
    for k, r in enumerate(tr.rungs):
        text = f"{r.setting}: n = {r.quarter_turns}".replace(" ", NBSP)
        before = tr.rungs[k - 1] if k else None
        if (before is not None and r.quarter_turns == before.quarter_turns
                and r.status == before.status == Status.SETTLED):
            gaps = ladder.gaps(before, r)
            if gaps:
                text += f" ({' and '.join(gaps)} from the rung before)"
        parts.append(text)
    return "; ".join(parts)


def friction_work_text(tr) -> str | None:
    """Whether friction did any work on the throw: with friction, the energy it took and its
    share of the initial energy; without, what a coefficient mu would take (mu times the
    sliding work, to first order), and whether that is worth a try. None: not integrated."""
    work, sliding = tr.friction_work, tr.sliding_work
    if work is None or sliding is None or not tr.energy_initial > 0:
        return None
    start = tr.energy_initial
    foundation = tr.scene.foundation
    if foundation.mu > 0:
        return (f"took {work * 1e3:.4g} mJ, {percent(work / start)} of the throw's "
                f"{start * 1e3:.5g} mJ (mu = {foundation.mu:g}, slip velocity "
                f"{foundation.slip_velocity:g} m/s)")
    if sliding <= 1e-9 * start:
        return ("none (mu = 0, the paper's model), and none would act: no corner slid along "
                "the foundation while pressed on it")
    share = SUGGESTED_MU * sliding / start
    advice = (f" ({percent(share, 2)} at mu = {SUGGESTED_MU:g}): try --mu {SUGGESTED_MU:g}"
              if share >= FRICTION_MATTERS else f" (only {percent(share, 2)} at mu = "
              f"{SUGGESTED_MU:g}): friction hardly matters here")
    return (f"none (mu = 0, the paper's model); friction of coefficient mu would take about "
            f"mu x {sliding * 1e3:.4g} mJ of the throw's {start * 1e3:.5g} mJ{advice}")


def print_summary(tr) -> None:
    from ..api.words import describe_method as describe
    from ..api.words import horizon_text, scene_horizon

    s = tr.summary()
    integ = tr.scene.integration
    init = tr.scene.initial
    say(console, f"[bold]coin simulate[/]  vy0 = {init.vy:g} m/s, vphi0 = {init.vphi:g} rad/s, "
                 f"phi0 = {init.phi0:g}, vx0 = {init.vx:g}, y0 = {tr.scene.y0:.6g} m",
        indent=LABEL_WIDTH)
    rows = [("outcome", outcome_text(tr))]
    if tr.settled:
        rows.append(("decided", f"at t = {tr.settle_time:.6g} s: the energy fell below "
                                f"E_crit = {tr.e_crit * 1e3:.4g} mJ, so n is final"))
    if tr.rounded_quarter_turns is not None and tr.rounded_quarter_turns != tr.quarter_turns:
        rows.append(("rounded n", f"round(2 phi / pi) = {tr.rounded_quarter_turns} at "
                                  f"t = {tr.t_final:g} s"))
    fs = s["final_state"]
    rows.append(("final state", f"t = {tr.t_final:.6g} s  x = {fs['x']:.6g} m  "
                                f"y = {fs['y']:.6g} m  phi = {fs['phi']:.6g} rad "
                                f"({math.degrees(fs['phi']):.2f} deg)"))
    rows.append(("", f"vx = {fs['vx']:.4g} m/s  vy = {fs['vy']:.4g} m/s  "
                     f"vphi = {fs['vphi']:.4g} rad/s"))
    lost = s["energy_dissipated"]
    if abs(lost) < 1e-12 * tr.energy_initial:  # rounding of a flight: nothing was lost
        lost = 0.0
    rows.append(("energy", f"{tr.energy_initial * 1e3:.5g} mJ -> {tr.energy_final * 1e3:.5g} "
                           f"mJ ({lost * 1e3:.5g} mJ dissipated)"))
    friction = friction_work_text(tr)
    if friction:
        rows.append(("friction", friction))
    horizon = scene_horizon(tr.scene)
    run_to = "stop when decided" if integ.stop_on_settle else f"full {horizon:g} s"
    rows.append(("method", f"{describe(tr.scene)}, {run_to}"))
    rows.append(("horizon", f"{horizon:.4g} s" + (
        "" if tr.scene.fixed_horizon else f": {horizon_text(tr.scene)}")))
    if len(tr.rungs) > 1:
        rows.append(("ladder", ladder_text(tr)))
    rungs = len(tr.rungs)
    rows.append(("cost", f"{tr.steps:,} step{'s' if tr.steps != 1 else ''}"
                         + (f" over {rungs} rungs" if rungs > 1 else "")
                         + f", {tr.wall_time * 1e3:.3g} ms wall"))
    print_rows(console, rows, LABEL_WIDTH)
    for note in tr.notes:
        say(console, f"[yellow]note:[/] {note}")
