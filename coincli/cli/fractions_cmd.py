"""`coin fractions`: outcome probabilities by Monte Carlo over distributions of the five
initial conditions, with 95 % intervals; resumable in a Zarr store; continuation along a
physical parameter, or over a grid of two (--over, twice), with a plot."""

import contextlib
import math
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ..api import ParameterError, StopReason, __version__
from ..api.options import (
    DEFAULT_BATCH,
    DEFAULT_MAX_SAMPLES,
    DEFAULT_PRECISION,
    MAX_SECONDS,
    parameter_label,
)
from ..api.words import format_seconds
from . import interruptions, recording
from .app import app
from .common import (
    INIT,
    RUN,
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
    PresetOpt,
    QuietOpt,
    RtolOpt,
    SinglePassOpt,
    SlipVelocityOpt,
    StopOpt,
    TEndOpt,
    ThicknessOpt,
    ThreadsOpt,
    WorkersOpt,
    WorkerTimeoutOpt,
    build_scene,
    compile_first_for,
    console,
    err_console,
    fail,
    print_json,
    user_errors,
    whole_option,
)
from .recording import LiveConnectOpt, LiveRrdOpt, LiveSpawnOpt
from .text import (
    TOP_OUTCOMES,
    TURN,
    counted,
    interval,
    left_out,
    most_frequent,
    percent,
    print_rows,
    print_table,
    resolving,
    say,
    share,
)

SAMPLING = "Sampling and stopping"
OVER = "Continuation along one parameter or two"


def _dist(name: str, text: str):
    return typer.Option(f"--{name}", metavar="DIST", help=text,
                        rich_help_panel=INIT, show_default=False)


Y0Dist = Annotated[str | None, _dist("y0", "Initial height of the centroid, m, or in multiples "
                                     "of the half diagonal r (r:5r) [dim]\\[r][/dim].")]
Phi0Dist = Annotated[str | None, _dist("phi0", "Initial angle, rad; -pi:pi is a random "
                                       "landing angle (with vx and vphi symmetric about 0, "
                                       "as by default, P(n) = P(-n)) [dim]\\[0][/dim].")]
VxDist = Annotated[str | None, _dist("vx", "Initial horizontal velocity, m/s "
                                     "[dim]\\[0][/dim].")]
VyDist = Annotated[str | None, _dist("vy", "Initial vertical velocity, m/s "
                                     "[dim]\\[0.05:2][/dim].")]
VphiDist = Annotated[str | None, _dist("vphi", "Initial angular velocity, rad/s "
                                       "[dim]\\[-20:20][/dim].")]


@app.command("fractions")
def fractions_command(
    y0: Y0Dist = None, phi0: Phi0Dist = None, vx: VxDist = None, vy: VyDist = None,
    vphi: VphiDist = None,
    samples: Annotated[str | None, typer.Option(
        "--samples", metavar="N", help="Run exactly N samples (e.g. 100000, 1e5, 100k) "
        "instead of stopping at --precision.", rich_help_panel=SAMPLING)] = None,
    precision: Annotated[str | None, typer.Option(
        "--precision", metavar="P", help="Stop at the first batch at which the half-width "
        "(high - low) / 2 of the 95 % interval of every probability (--of) is at most P: a "
        f"probability (0.001) or percentage points (0.1%) [dim]\\[{DEFAULT_PRECISION:g}]"
        "[/dim]", rich_help_panel=SAMPLING, show_default=False)] = None,
    of: Annotated[str, typer.Option(
        "--of", metavar="all|standing", help="Which intervals --precision applies to: all "
        "(every outcome n, standing, lying and the uncertain fraction) or standing "
        "(P(standing) only).", rich_help_panel=SAMPLING)] = "all",
    max_samples: Annotated[str, typer.Option(
        "--max-samples", metavar="N", help="The sample budget of a --precision run (whole "
        "batches).", rich_help_panel=SAMPLING)] = str(DEFAULT_MAX_SAMPLES),
    seed: Annotated[int, typer.Option("--seed", metavar="S", help="Seed of the scrambling or "
                                      "of the generator: the same seed, the same samples.",
                                      rich_help_panel=SAMPLING, parser=whole_option)] = 0,
    sampler: Annotated[str, typer.Option(
        "--sampler", metavar="sobol|random", help="Scrambled Sobol points (scipy.stats.qmc) or "
        "independent draws (numpy's default_rng(\\[seed, batch])).",
        rich_help_panel=SAMPLING)] = "sobol",
    batch: Annotated[int, typer.Option("--batch", metavar="N", help="Samples a batch: the "
                                       "unit of work, of storing and of the stop test.",
                                       rich_help_panel=SAMPLING,
                                       parser=whole_option)] = DEFAULT_BATCH,
    over: Annotated[list[str] | None, typer.Option(
        "--over", metavar="NAME=LO:HI:STEPS", help="Repeat at STEPS values of a physical "
        "parameter (thickness, diameter, k, c, mass, inertia, g, mu, slip_velocity), or at "
        "the values listed "
        "(NAME=V1,V2,...), the same samples at every value; given twice, at every point of "
        "the grid of both. For thickness and diameter, mass and inertia follow a uniform solid "
        "disc unless --mass or --inertia is given.", rich_help_panel=OVER)] = None,
    plot: Annotated[Path | None, typer.Option(
        "--plot", metavar="FILE", help="With --over: draw P(outcome) against the parameter "
        "with 95 % bands; over two, a map of P(standing) with its 1/3 line and that line's "
        "95 % band (.png, .svg or .pdf).", rich_help_panel=OVER)] = None,
    store: Annotated[Path | None, typer.Option(
        "--store", metavar="PATH", help="Keep the samples and labels in this Zarr store; the "
        "same command resumes it.", rich_help_panel=RUN)] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", metavar="",
                                            help="Replace a --store of other "
                                            "samples.", rich_help_panel=RUN)] = False,
    threads: ThreadsOpt = None, workers: WorkersOpt = None,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", metavar="ADDRESS", rich_help_panel=RUN,
        help="Run the batches on the Dask cluster at this address (tcp://HOST:PORT); the "
             "store stays here.")] = None,
    worker_timeout: WorkerTimeoutOpt = None,
    quiet: QuietOpt = False,
    yes: Annotated[bool, typer.Option("--yes", "-y", metavar="",
                                      help="Start a run estimated to take "
                                      "more than 12 hours, or to spend its budget before "
                                      "--precision, anyway.", rich_help_panel=RUN)] = False,
    every_n: Annotated[bool, typer.Option("--all", metavar="", help="List every n (by default "
                                          f"the {TOP_OUTCOMES} most frequent; --json always "
                                          "lists every n).")] = False,
    json_out: JsonOpt = False,
    rrd: LiveRrdOpt = None, spawn: LiveSpawnOpt = False, connect: LiveConnectOpt = None,
    preset: PresetOpt = "paper",
    diameter: DiameterOpt = None, thickness: ThicknessOpt = None, mass: MassOpt = None,
    inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None, mu: MuOpt = None,
    slip_velocity: SlipVelocityOpt = None, g: GOpt = None, method: MethodOpt = None,
    dt: DtOpt = None, rtol: RtolOpt = None, t_end: TEndOpt = None,
    stop_on_settle: StopOpt = None, force: ForceOpt = False, single_pass: SinglePassOpt = False,
    max_steps: MaxStepsOpt = None,
) -> None:
    """Outcome probabilities of random throws: P(n), P(standing), P(lying) with 95 % intervals.

    Each initial condition is a DIST: a value (0.01, 2pi), LO:HI (uniform), normal(MEAN,SD) or normal(MEAN,SD,LO,HI) (truncated); numbers may use pi (-pi:pi), and y0 multiples of the half diagonal r (r:5r). Samples are drawn until every 95 % interval is narrower than --precision (or --samples of them), counting only verified (certain) labels and reporting the uncertain fraction beside them. The same command gives the same samples and results; with --store it resumes where it stopped, and several processes may run it on one store at once. A pilot of a few hundred samples estimates the run first: one estimated at over 12 hours, or to need more samples than --max-samples, is refused without --yes. Exit 1 when the budget is spent before --precision, 130 when interrupted.

    Example:

    coin fractions --y0 r:5r --phi0 -pi:pi --vx -0.5:0.5 --precision 0.05%
    """  # noqa: E501
    from .. import api
    from ..api.options import check_figure_path, check_where, parse_count, parse_precision

    with user_errors():
        scene = build_scene(preset, diameter=diameter, thickness=thickness, mass=mass,
                            inertia=inertia, k=k, c=c, mu=mu, slip_velocity=slip_velocity,
                            g=g, method=method, dt=dt, rtol=rtol,
                            t_end=t_end, stop_on_settle=stop_on_settle, max_steps=max_steps,
                            verify=False if single_pass else None)
        if plot is not None and not over:
            raise ParameterError("--plot draws a continuation: give --over NAME=LO:HI:STEPS")
        if plot is not None:
            check_figure_path(plot, "--plot")
        keep = tuple(name for name, given in (("mass", mass), ("inertia", inertia))
                     if given is not None)
        plan = api.plan_fractions(
            scene, y0=y0, phi0=phi0, vx=vx, vy=vy, vphi=vphi,
            samples=parse_count("samples", samples), precision=parse_precision(precision),
            of=of, max_samples=parse_count("max_samples", max_samples), seed=seed,
            sampler=sampler, batch=batch, over=over or None, keep=keep, force=force)
        check_where(threads, workers, scheduler, worker_timeout)
    where_to, no_viewer = recording.destination(rrd, spawn, connect)
    # on no terminal the note also comes first (on one, the result shows it), said once the
    # run has passed its checks: a store of other samples is refused in one line alone
    note = plan.note if not json_out and not console.is_terminal else None
    compile_first_for(plan.scenes, quiet)
    result, recorder = _run(plan, where_to, quiet, yes, note=note, store=store,
                            overwrite=overwrite, threads=threads, workers=workers,
                            scheduler=scheduler, worker_timeout=worker_timeout)
    _report(plan, result, store=store, plot=plot, json_out=json_out, every_n=every_n,
            recorder=recorder, where_to=where_to, no_viewer=no_viewer)


@contextlib.contextmanager
def _naming(store: Path | None):
    """A disk's error while the run writes ``store`` (a full disk) said naming the store, and
    that the batches it holds are kept."""
    from ..api.words import DISK_ERRORS, NotWritable, describe_error

    try:
        yield
    except OSError as exc:
        if store is None or isinstance(exc, NotWritable) or exc.errno not in DISK_ERRORS:
            raise
        raise NotWritable(exc.errno, describe_error(exc, f"cannot write {store}") + "; the "
                          "batches written so far are kept: rerun the command to "
                          "resume") from None


def _cost(est, scheduler) -> str:
    """What a run will cost, from its estimate (a FractionsEstimate)."""
    from ..api.words import format_duration

    on = (f"on {counted(est.workers, 'core')}" if est.workers
          else f"of CPU time over the cluster at {scheduler}")
    return (f"about {format_duration(est.seconds)} {on} for {est.samples:,} samples "
            f"({est.cpu_per_sample * 1e3:.3g} ms a sample, from a pilot of "
            f"{est.pilot_samples:,})")


def _too_long(est, scheduler) -> str:
    """One line: how long a run refused for its time would take (over MAX_SECONDS, the limit
    lifted by --yes, the API's default), and what to do."""
    return (f"this run would take {_cost(est, scheduler)}. Give --yes to start it anyway, ask "
            "for less precision or fewer samples, or run it on more machines sharing a "
            "--store (each claims its own batches)")


def _check_estimate(est, plan, scheduler, yes: bool, quiet: bool) -> None:
    """Before the run (the API refuses one estimated at over MAX_SECONDS unless --yes):
    refuse, unless --yes, a run whose stop rule likely needs more samples than its budget;
    say what a long run will cost."""
    over = f" over {len(plan.scenes)} values" if plan.parameters else ""
    if not est.budget_suffices and not yes and not est.held:  # a resume goes on
        raise fail(f"--precision needs about {est.needed:,} samples{over} (from a pilot of "
                   f"{est.pilot_samples:,}), more than the budget of {est.budget:,}: raise "
                   "--max-samples, ask for less precision, or give --yes to run to the "
                   "budget")
    if not est.budget_suffices:
        say(err_console, f"[yellow]note:[/] --precision needs about {est.needed:,} samples, "
                         f"more than the budget of {est.budget:,}: the run stops at the "
                         "budget (exit 1)")
    if est.seconds > 60 and not quiet:
        say(err_console, f"estimate: {_cost(est, scheduler)}")


def _header(plan, samples: int) -> str:
    s = plan.sampling
    how = "scrambled Sobol points" if s.sampler == "sobol" else "independent draws"
    return f"{samples:,} samples ({how}, seed {s.seed})"


def _from_store(cost: dict) -> str:
    """What a resumed run found counted in its store already, for its cost line."""
    held, damaged = cost.get("from_store"), cost.get("damaged_batches")
    return ((f"; {held:,} samples were in the store already" if held else "")
            + (f"; {counted(damaged, 'damaged batch', 'damaged batches')} of the store (a "
               "chunk that did not read back) computed again" if damaged else ""))


def _stopped(result) -> str:
    goal = result.goal
    if result.stopped is StopReason.PRECISION:
        of = "every probability" if goal["of"] == "all" else "P(standing)"
        return (f"{of} known to ±{100 * goal['precision']:.3g} percentage points or better "
                f"(95 %; widest now ±{100 * result.achieved:.3g})")
    if result.stopped is StopReason.BUDGET:
        return (f"the budget of {goal['max_samples']:,} samples is spent before ±"
                f"{100 * goal['precision']:.3g} pp (widest ±{100 * result.achieved:.3g} pp)")
    if result.stopped is StopReason.SAMPLES:
        return "the samples asked for are done"
    return "interrupted"


def fit(room: int, count: str, estimate: str, width: str, short: str) -> str:
    """A progress line's detail in at most ``room`` characters: the count, the estimate and the
    interval's width; else the estimate named shorter (``short``); else without the width; else
    the count alone."""
    for parts in ((count, estimate, width), (count, short, width), (count, short), (count,)):
        text = " ".join(part for part in parts if part)
        if len(text) <= room:
            return text
    return count


def _print_result(plan, r, every_n: bool = False) -> None:
    scene = plan.scene
    say(console, f"[bold]coin fractions[/]  {_header(plan, r.samples)}; stopped: "
                 f"{_stopped(r)}")
    say(console, f"drawn: {plan.sampling.describe(scene)}")
    basis = "certain labels" if r.verified else "settled runs (single pass: unverified)"
    title = f"Outcomes: probabilities over the {r.counted:,} {basis}, 95 % Wilson intervals"
    table = Table()
    for col, just in (("n", "right"), ("pose", "left"), ("turn", "left"), ("count", "right"),
                      ("P", "right"), ("95 % interval", "right")):
        table.add_column(col, justify=just, no_wrap=True)
    shown, hidden = (r.outcomes, []) if every_n else most_frequent(r.outcomes)
    for row in shown:
        style = "bold magenta" if row["pose"] == "standing" else None
        table.add_row(str(row["n"]), row["pose"], TURN[row["direction"]], f"{row['count']:,}",
                      percent(row["probability"], resolving(row)), interval(row), style=style)
    print_table(console, table, title)
    if hidden:
        say(console, left_out(hidden, sum(row["probability"] for row in hidden),
                              "certain labels" if r.verified else "settled runs"))
    summary = []
    summary.append(("standing", share(r.standing)))
    summary.append(("lying", share(r.lying)))
    u = r.uncertain
    what = (f"no two rungs of the ladder agreed, or no label: {u['chaotic']:,} chaotic (decided, "
            f"rungs disagree), {u['undecided']:,} undecided (a rung not settled)"
            if r.verified else "not settled")
    summary.append(("uncertain", f"{share(r.uncertain)} ({what})"))
    d = r.all_decided
    summary.append(("all decided", f"standing {percent(d['standing']['probability'])} (95 % CI "
                                    f"{interval(d['standing'])}) of {d['decided']:,} decided "
                                    "samples (each throw's deepest rung settled), chaotic ones "
                                    "included"))
    a = r.all_labelled
    summary.append(("all labelled", f"standing {percent(a['standing']['probability'])} (95 % CI "
                                     f"{interval(a['standing'])}) of {a['labelled']:,} "
                                     "labelled samples, uncertain ones included"))
    from ..api.words import describe_method as describe
    from ..api.words import friction_text, horizon_text

    summary.append(("method", describe(scene)))
    friction = friction_text(scene)
    if friction is not None:
        summary.append(("friction", friction))
    summary.append(("horizon", horizon_text(scene)))
    cost = r.cost
    if cost.get("computed"):
        where = counted(cost["workers"], "thread") if cost["mode"] == "threads" else "Dask"
        summary.append(("cost", f"{cost['computed']:,} trajectories in "
                                 f"{format_seconds(cost['wall_seconds'])} wall on {where} "
                                 f"({cost['trajectories_per_second']:,.0f} a second; "
                                 f"{cost['cpu_ms_per_trajectory']:.3g} CPU ms each, every "
                                 f"rung of the ladder counted){_from_store(cost)}"))
    else:
        summary.append(("cost", "nothing computed: every batch was in the store"))
    if r.store:
        summary.append(("store", r.store))
    print_rows(console, summary)


def _stopped_over(res) -> str:
    """Why the values of a continuation stopped: 'samples (every value)', or each reason with
    its values ('precision at 0.001, 0.0019; budget at 0.02'; over a grid, the points)."""
    reasons: dict = {}
    for r in res.results:
        reasons.setdefault(str(r.stopped), []).append(r.at)
    if len(reasons) == 1:
        return f"{next(iter(reasons))} (every value)"
    return "; ".join(f"{reason} at " + (
        ", ".join(" ".join(f"{v:.4g}" for v in at.values()) for at in where)
        if len(where) <= 6 else counted(len(where), "value")) for reason, where in reasons.items())


def _print_over(plan, res) -> None:
    first = res.results[0]
    names = " and ".join(res.parameters)
    size = f"{len(res.results)} values" if len(res.parameters) == 1 else \
        f"{' x '.join(str(n) for n in res.shape)} = {len(res.results)} points"
    say(console, f"[bold]coin fractions[/] over {names} ({size}), "
                 f"the same samples at every value ({plan.sampling.sampler}, seed "
                 f"{plan.sampling.seed})")
    say(console, f"drawn: {plan.sampling.describe()}")
    from ..api.words import describe_method as describe

    methods = list(dict.fromkeys(describe(scene) for scene in plan.scenes))  # mu: two ladders
    say(console, f"method: {methods[0]}" + (
        f" (with friction: {methods[1]})" if len(methods) == 2
        and plan.scenes[0].foundation.mu == 0 else
        "".join(f"; {m}" for m in methods[1:])))
    if res.note:
        say(console, f"note: {res.note}")
    basis = "certain labels" if first.verified else "settled runs"
    # at 80 columns: P(standing) named once, in the title, and why each value stopped said
    # under the table, not in a column
    table = Table(show_edge=False, pad_edge=False)
    cols = [(parameter_label(name), "right") for name in res.parameters]
    shaped = bool({"thickness", "diameter"} & set(res.parameters))
    if shaped:
        cols.append(("t/d", "right"))
    # a grid's samples, the same at every point, said in the title (a column less at 80)
    alike = len(res.parameters) > 1 and len({r.samples for r in res.results}) == 1
    cols += [*([] if alike else [("samples", "right")]), ("P", "right"),
             ("95 % interval", "right"), ("uncertain", "right")]
    for col, just in cols:
        table.add_column(col, justify=just, no_wrap=True)
    for r in res.results:
        row = [f"{value:.4g}" for value in r.at.values()]
        if shaped:
            row.append(f"{r.scene['coin']['thickness'] / r.scene['coin']['diameter']:.3g}")
        row += [*([] if alike else [f"{r.samples:,}"]), percent(r.standing["probability"]),
                interval(r.standing), percent(r.uncertain["probability"], 3)]
        table.add_row(*row)
    each = f", {first.samples:,} samples a point" if alike else ""
    print_table(console, table, f"P(standing) over the {basis}{each}, 95 % Wilson intervals")
    say(console, f"stopped: {_stopped_over(res)}")
    cost = res.cost
    if cost.get("computed"):
        say(console, f"cost: {cost['computed']:,} trajectories in {cost['wall_seconds']:.1f} s "
                     f"wall ({cost['trajectories_per_second']:,.0f} a second, "
                     f"{cost['cpu_ms_per_trajectory']:.3g} CPU ms each){_from_store(cost)}")
    if res.store:
        say(console, f"store: {res.store}")


__all__ = ["fractions_command"]


def _bars(plan, quiet: bool):
    """The progress bars of a run (not started) and the function that draws a
    FractionsProgress on them: a bar a value, or one for a whole grid."""
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn

    from .progress import Bars, RateColumn

    wide = err_console.width >= 100  # at 80 columns the rate goes: the estimate matters more
    bar_width = 20 if wide else 8
    progress = Bars(
        TextColumn("{task.fields[value]}"), BarColumn(bar_width=bar_width),
        TextColumn("{task.fields[detail]}"), *([RateColumn("traj")] if wide else []),
        TimeElapsedColumn(), console=err_console, disable=quiet, transient=False)
    tasks: dict[int, int] = {}
    grid_samples: dict[int, int] = {}  # a grid's points: samples counted, and expected
    grid_expected: dict[int, int] = {}
    label_width = 0

    def show(update) -> None:
        nonlocal label_width
        v = update.value
        p, lo, hi = update.standing
        estimate = "-" if math.isnan(p) else \
            f"{100 * p:.3g} % ({100 * lo:.2g}-{100 * hi:.2g})"
        width = "" if update.precision is None or math.isnan(update.widest) else \
            f"±{100 * update.widest:.2g}→{100 * update.precision:.2g} pp"
        samples, total = update.samples, max(update.expected, update.samples, 1)
        if len(plan.parameters) > 1:  # a grid: one bar, every point's samples
            grid_samples[v], grid_expected[v] = update.samples, total
            label = f"{' x '.join(plan.parameters)}: {update.values_done}/{update.values}"
            samples = sum(grid_samples.values())
            total = max(samples, sum(grid_expected.values())
                        + total * (update.values - len(grid_expected)))
            v = 0
        else:
            label = "" if update.values == 1 else \
                f"{plan.parameter} = {plan.values[v]:g} ({v + 1}/{update.values})"
        label_width = max(label_width, len(label))
        # what fits beside the label, the bar, the rate and the clock (rich cuts a line short)
        room = (err_console.width - label_width - bar_width - len("0:00:00")
                - (len("99,999 traj/s") + 1 if wide else 0) - 4)
        detail = fit(room, f"{samples:,}/{total:,}", f"P(standing) {estimate}", width,
                     short=f"P {estimate}")
        if v not in tasks:
            tasks[v] = progress.add_task("fractions", total=total, value=label, detail=detail)
        progress.update(tasks[v], completed=samples, total=total, detail=detail, value=label)

    return progress, show


def _run(plan, where_to, quiet: bool, yes: bool, *, note: str | None, store, scheduler,
         **options):
    """The run with its progress bars, its live recording and two-step Ctrl-C: (its result,
    the recorder or None). Refused in one line before any work, unless --yes, if its pilot
    estimates it at over MAX_SECONDS (the API refuses it) or to spend its budget before
    --precision; a store that cannot be written, a lost scheduler: one line. ``note`` is said
    once the run has passed these checks."""
    from .. import api
    from ..api.errors import SchedulerLost, StoreIncomplete, WorkTooLong
    from ..api.recording import fractions_recorder

    progress, draw = _bars(plan, quiet)

    def show(update) -> None:
        draw(update)
        if recorder is not None:
            recorder.progress(update)

    recorder = None
    recording_stack = contextlib.ExitStack()

    def started(est) -> None:  # the run passed its checks and its estimate: the work begins
        nonlocal recorder
        _check_estimate(est, plan, scheduler, yes, quiet)
        if note:
            say(err_console, f"[cyan]note:[/] {note}")
        recorder = fractions_recorder(plan, where_to)  # Rerun's code only when asked for
        if recorder is not None:
            recording_stack.enter_context(recorder)
        progress.start()

    try:
        stop = interruptions.GracefulStop("finishing the batches in flight, then stopping "
                                          "(rerun the same command with --store to resume)")
        with user_errors(), _naming(store), stop, recording_stack:
            try:
                result = api.run_fractions(plan, store=store, scheduler=scheduler,
                                           progress=show, stop=stop.event,
                                           max_seconds=None if yes else MAX_SECONDS,
                                           on_start=started, estimate=True, **options)
            except WorkTooLong as exc:
                raise fail(_too_long(exc.estimate, scheduler)) from None
            finally:
                progress.stop()
            if recorder is not None:
                recorder.result(result)
    except StoreIncomplete as exc:
        say(err_console, f"[bold red]error:[/] {escape(str(exc))}")
        raise typer.Exit(code=1) from None
    except SchedulerLost as exc:
        fail(interruptions.lost_scheduler(exc, "every batch received"))
        raise typer.Exit(code=interruptions.SCHEDULER_LOST) from None
    return result, recorder


def _report(plan, result, *, store, plot, json_out: bool, every_n: bool, recorder, where_to,
            no_viewer: bool) -> None:
    """The result (a table, or JSON), its picture, where the recording went, and the exit: 130
    interrupted, 1 short of the precision asked for."""
    from .. import api

    if plot is not None:
        with user_errors():
            api.render_fractions(result, plot)
    if json_out:
        print_json({"version": __version__, **result.to_dict()})
    elif not plan.parameters:
        _print_result(plan, result, every_n)
    else:
        _print_over(plan, result)
    if plot is not None and not json_out:
        say(console, f"wrote {plot}")
    if recorder is not None and recorder.error is None and not json_out:
        say(console, recording.recorded(where_to))
    if result.interrupted:
        say(err_console, f"[yellow]stopped:[/] {interruptions.stopped_by()}interrupted; the "
                         "estimates above are from the "
                         "samples done" + (f"; rerun the same command to resume {store}"
                                           if store is not None else ""))
        recording.finish(recorder, no_viewer, exit_code=None)
        raise typer.Exit(code=130)
    runs = result.results if plan.parameters else [result]
    short = [r for r in runs if r.stopped is StopReason.BUDGET]
    if short:
        where = "" if not plan.parameters else \
            f" at {len(short)} of {len(runs)} values of {' and '.join(plan.parameters)}"
        say(err_console, f"[yellow]stopped short:[/] the budget of "
                         f"{plan.goal.max_samples:,} samples was spent before the precision "
                         f"asked for{where}; raise --max-samples (the same command with "
                         "--store resumes from the samples done) or ask for less precision")
        recording.finish(recorder, no_viewer, exit_code=None)
        raise typer.Exit(code=1)
    recording.finish(recorder, no_viewer)

