"""`coin basin [sweep] STORE`: a resumable, chunked sweep of two initial conditions into a Zarr
store, with a progress bar, an estimate, a live recording and two-step Ctrl-C."""

import contextlib
import math
from pathlib import Path
from typing import Annotated

import typer

from ...api import ParameterError
from ...api.options import DEFAULT_CHUNK, DEFAULT_RANGES, DEFAULT_RES, MAX_SECONDS
from ...api.words import format_seconds
from .. import recording
from ..common import (
    INIT,
    RUN,
    COpt,
    DiameterOpt,
    DtOpt,
    ForceOpt,
    GOpt,
    InertiaOpt,
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
    compile_first,
    console,
    err_console,
    fail,
    in_cli_words,
    user_errors,
)
from ..recording import LiveConnectOpt, LiveRrdOpt, LiveSpawnOpt
from ..text import (
    command,
    counted,
    say,
)
from .group import basin_app, tile_list

SWEEP = "Sweep"




def _ic(name: str, help_text: str, default_note: str = ""):
    return typer.Option(f"--{name}", metavar="X|LO:HI",
                        help=help_text + " A LO:HI range sweeps it (cell centres "
                        "linspace(LO, HI, n), both ends included)." + default_note,
                        rich_help_panel=INIT)


X0Range = Annotated[str | None, _ic("x0", "Initial x, m (default 0).")]


Y0Range = Annotated[str | None, _ic("y0", "Initial height of the centroid, m (default r).")]


Phi0Range = Annotated[str | None, _ic("phi0", "Initial angle, rad (default 0).")]


VxRange = Annotated[str | None, _ic("vx", "Initial horizontal velocity, m/s (default 0).")]


VyRange = Annotated[str, _ic("vy", "Initial vertical velocity, m/s.")]


VphiRange = Annotated[str, _ic("vphi", "Initial angular velocity, rad/s.")]


DEFAULT_TEXT = {name: f"{lo:g}:{hi:g}" for name, (lo, hi) in DEFAULT_RANGES.items()}


@basin_app.command("sweep")
def sweep_command(
    path: Annotated[Path, typer.Argument(help="The Zarr store to create or resume "
                                         "(a directory, e.g. out.zarr).",
                                         metavar="STORE")],
    x0: X0Range = None, y0: Y0Range = None, phi0: Phi0Range = None, vx: VxRange = None,
    vy: VyRange = DEFAULT_TEXT["vy"], vphi: VphiRange = DEFAULT_TEXT["vphi"],
    res: Annotated[str, typer.Option("--res", metavar="N|NxM",
                                     help="Cells per axis: N, or NxM (N along the "
                                     "first swept axis, M along the second).",
                                     rich_help_panel=SWEEP)] = str(DEFAULT_RES),
    chunk: Annotated[str, typer.Option("--chunk", metavar="N|NxM",
                                       help="Tile size in cells, N or NxM: the "
                                       "unit of work, of writing and of resuming.",
                                       rich_help_panel=SWEEP)] = str(DEFAULT_CHUNK),
    no_mirror: Annotated[bool, typer.Option("--no-mirror", metavar="",
                                            help="Compute every tile, also "
                                            "where the sweep is its own mirror image (phi0, "
                                            "vx, vphi zero or swept symmetrically: by default "
                                            "one tile of each pair is computed and the other "
                                            "is its mirror, n -> -n).",
                                            rich_help_panel=SWEEP)] = False,
    overwrite: Annotated[bool, typer.Option("--overwrite", metavar="",
                                            help="Replace an existing store "
                                            "instead of resuming it.",
                                            rich_help_panel=SWEEP)] = False,
    threads: ThreadsOpt = None, workers: WorkersOpt = None,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", metavar="ADDRESS", rich_help_panel=RUN,
        help="Run the tiles as Dask tasks on the cluster at this address (tcp://HOST:PORT); "
             "every worker writes its tiles to STORE, so STORE must be the same shared "
             "directory on all of them.")] = None,
    worker_timeout: WorkerTimeoutOpt = None,
    quiet: QuietOpt = False,
    yes: Annotated[bool, typer.Option("--yes", "-y", metavar="",
                                      help="Start a sweep estimated to take "
                                      "more than 12 hours anyway.",
                                      rich_help_panel=RUN)] = False,
    rrd: LiveRrdOpt = None, spawn: LiveSpawnOpt = False, connect: LiveConnectOpt = None,
    preset: PresetOpt = "paper",
    diameter: DiameterOpt = None, thickness: ThicknessOpt = None, mass: MassOpt = None,
    inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None, mu: MuOpt = None,
    slip_velocity: SlipVelocityOpt = None, g: GOpt = None, method: MethodOpt = None,
    dt: DtOpt = None, rtol: RtolOpt = None, t_end: TEndOpt = None,
    stop_on_settle: StopOpt = None, force: ForceOpt = False, single_pass: SinglePassOpt = False,
    max_steps: MaxStepsOpt = None,
) -> None:
    """Sweep two initial conditions over a grid and store n for every cell (resumable).

    Defaults: the paper's setting (x0 = 0, y0 = r, phi0 = 0, vx0 = 0) over vy0 in 0.05:2 m/s and vphi0 in -20:20 rad/s, 512 x 512 cells. Running the same command again resumes the sweep (and recomputes any damaged tile); several processes or machines may run it on one store at once. Ctrl-C stops after the tiles in flight, a second Ctrl-C at once. A sweep estimated at over 12 hours is refused without --yes.

    Example:

    coin basin out.zarr --vy 0:2 --vphi -20:20 --res 512
    """  # noqa: E501
    from ... import api
    from ...api.options import check_where

    with user_errors():
        scene = build_scene(preset, diameter=diameter, thickness=thickness, mass=mass,
                            inertia=inertia, k=k, c=c, mu=mu, slip_velocity=slip_velocity,
                            g=g, method=method, dt=dt,
                            rtol=rtol, t_end=t_end, stop_on_settle=stop_on_settle,
                            max_steps=max_steps, verify=False if single_pass else None)
        plan = api.plan_sweep(scene, res=res, chunk=chunk, force=force,
                              mirror=not no_mirror, x0=x0, y0=y0, phi0=phi0, vx=vx, vy=vy,
                              vphi=vphi)
        check_where(threads, workers, scheduler, worker_timeout)
    where_to, no_viewer = recording.destination(rrd, spawn, connect)
    # before the sweep: its pilot estimate is the first run of the kernels (a store that
    # is already complete on a fresh install is the one case compiled for without need)
    compile_first(quiet, scene)
    report, recorder = _run(plan, path, where_to, overwrite=overwrite, threads=threads,
                            workers=workers, scheduler=scheduler, quiet=quiet, yes=yes,
                            worker_timeout=worker_timeout)
    if recorder is not None and recorder.error is None:
        say(console, recording.recorded(where_to))
    _report(path, plan, report, scheduler)
    if report.interrupted or not report.complete:
        recording.finish(recorder, no_viewer, exit_code=None)
        raise typer.Exit(code=130)
    recording.finish(recorder, no_viewer)


def _run(plan, path: Path, where_to, *, overwrite: bool, threads, workers, scheduler,
         quiet: bool, yes: bool, worker_timeout=None):
    """The sweep with its progress bar, its live recording and two-step Ctrl-C: (its
    SweepReport, the recorder or None). Fails in one line on what the sweep refuses."""
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from ... import api
    from ...api.errors import SchedulerLost
    from ...api.options import is_store
    from ...api.recording import sweep_recorder
    from ...api.words import DISK_ERRORS, NotWritable, describe_error
    from .. import interruptions
    from ..progress import Bars, RateColumn

    progress = Bars(
        TextColumn("[bold]basin[/]"), BarColumn(),
        TextColumn("{task.fields[tiles]}/{task.fields[ntiles]} tiles"),
        RateColumn("cells"), TimeElapsedColumn(),
        TextColumn("ETA"), TimeRemainingColumn(),
        console=err_console, disable=quiet, transient=False)
    recorder = sweep_recorder(plan, path, where_to)  # its process starts: it imports Rerun
    task = None

    def show(update) -> None:
        nonlocal task
        if task is None:
            task = progress.add_task("sweep", total=update.cells_todo, tiles=0,
                                     ntiles=update.tiles_total)
        progress.update(task, completed=update.cells_done, tiles=update.tiles_done)
        if recorder is not None:  # the tiles just written, read back from the store
            recorder.progress(update)

    def started(start) -> None:
        if recorder is not None:  # the sweep passed its checks: the recording begins
            recorder.begin()
        _say_start(path, plan, start, scheduler)
        if start.cells_todo and not quiet:
            progress.start()

    stop = interruptions.GracefulStop("finishing the tiles in flight, then stopping (rerun the "
                                      "same command to resume)")
    try:
        with stop, recorder or contextlib.nullcontext():
            try:
                report = api.sweep(plan, path, overwrite=overwrite, threads=threads,
                                   workers=workers, scheduler=scheduler, progress=show,
                                   stop=stop.event, on_start=started,
                                   max_seconds=None if yes else MAX_SECONDS,
                                   worker_timeout=worker_timeout)
            finally:
                progress.stop()
    except api.SweepTooLong as exc:
        raise fail(_too_long(exc.estimate, plan, scheduler)) from None
    except ParameterError as exc:
        raise fail(in_cli_words(exc)) from None
    except SchedulerLost as exc:
        fail(interruptions.lost_scheduler(exc, "every finished tile"))
        raise typer.Exit(code=interruptions.SCHEDULER_LOST) from None
    except OSError as exc:  # a read-only or full disk; no scheduler at that address
        disk = exc.errno in DISK_ERRORS or isinstance(exc, NotWritable)
        raise fail(describe_error(exc, f"cannot write {path}" if disk
                                  else "cannot run the sweep")
                   + ("; the tiles written so far are kept: rerun the command to resume"
                      if disk and is_store(path) and not isinstance(exc, NotWritable)
                      else "")) from None
    return report, recorder


def _say_start(path: Path, plan, start, scheduler) -> None:
    """What the store held, and how long the work should take."""
    if start.repaired:
        say(err_console, f"[yellow]repaired:[/] {path}: {len(start.repaired)} metadata "
                         f"file(s) differed from the sweep's and were rewritten: "
                         f"{', '.join(start.repaired[:6])}")
    if start.damaged:
        say(err_console, f"[yellow]damaged:[/] {counted(len(start.damaged), 'tile')} of "
                         f"{path} failed the integrity check, recomputed now: "
                         f"{tile_list(start.damaged)}")
    if 0 < start.tiles_done < start.tiles_total:
        say(err_console, f"resuming {path}: {start.tiles_done} of "
                         f"{counted(start.tiles_total, 'tile')} done already, "
                         f"{counted(start.tiles_total - start.tiles_done, 'tile')} to "
                         "compute")
    est = start.estimate
    if est is not None and est.seconds > 60:
        say(err_console, f"estimate: {_estimate_text(est, plan, scheduler)}")


def _report(path: Path, plan, report, scheduler) -> None:
    """What the run did, and what is next."""
    from .. import interruptions

    total = report.tiles_total
    if report.tiles_before == total:
        say(console, f"{path}: every tile is done already ({counted(total, 'tile')}, "
                     f"{counted(plan.grid.n_cells, 'cell')}). "
                     f"Next: {command('coin', 'basin', 'render', path)}; "
                     f"{command('coin', 'basin', 'stats', path)}")
        return
    rate = report.cells / report.wall_seconds if report.wall_seconds > 0 else math.nan
    where = (counted(report.workers, "thread") if report.mode == "threads"
             else f"Dask ({scheduler or f'{report.workers} local workers'})")
    others = (f"; {counted(report.tiles_elsewhere, 'tile')} by other processes"
              if report.tiles_elsewhere else "")
    share = ("half" if 2 * report.mirrored_cells == report.cells
             else f"{report.mirrored_cells:,}")
    halves = (f", {share} of them as the mirror images of the others: "
              f"{' and '.join(plan.grid.mirror_dims)} reversed, n -> -n"
              if report.mirrored_cells else "")
    say(console, f"{path}: {report.tiles_done}/{total} tiles done; this run computed "
                 f"{counted(report.tiles_computed, 'tile')} "
                 f"({counted(report.cells, 'cell')}{halves}) in "
                 f"{format_seconds(report.wall_seconds)} wall, {rate:,.0f} "
                 f"cells/s on {where}{others}.")
    if report.interrupted or not report.complete:
        say(err_console, f"[yellow]stopped:[/] {interruptions.stopped_by()}"
                         f"{counted(total - report.tiles_done, 'tile')} left; run the same "
                         "command again to resume.")
        return
    picture = path.with_suffix(".png")  # beside the store (out/basin.zarr: out/basin.png)
    say(console, f"Next: {command('coin', 'basin', 'render', path, '-o', picture)}; "
                 f"{command('coin', 'basin', 'stats', path)}")


def _estimate_text(est, plan, scheduler) -> str:
    from ...api.words import format_duration

    bound = "at least" if est.at_least else "about"
    on = (f"on {est.workers} {'core' if est.workers == 1 else 'cores'}" if est.workers
          else f"of CPU time over the cluster at {scheduler}")
    mirrored = ", as many again mirrored" if plan.grid.mirror_dims else ""
    return (f"{bound} {format_duration(est.seconds)} {on} for {est.cells:,} cells{mirrored} "
            f"({est.cpu_per_cell * 1e3:.3g} ms a cell, from a pilot of {est.pilot_cells} "
            f"cells)")


def _too_long(est, plan, scheduler) -> str:
    """One line: how long, and how to split the sweep (MAX_SECONDS: the limit lifted by
    --yes, the API's default)."""
    from ...api.words import format_duration

    n0, n1 = plan.grid.shape
    scale = math.sqrt(MAX_SECONDS / est.seconds) if est.seconds > 0 else 1.0
    r0, r1 = (max(2, int(n * scale) // 64 * 64 or int(n * scale)) for n in (n0, n1))
    smaller = f"--res {r0}" if (n0 == n1 and r0 == r1) else f"--res {r0}x{r1}"
    machines = math.ceil(est.seconds / MAX_SECONDS)
    return (f"this sweep would take {_estimate_text(est, plan, scheduler)}. Give --yes to start it "
            f"anyway, or split it: a smaller {smaller} (about "
            f"{format_duration(MAX_SECONDS)} here), narrower ranges, or this same command on "
            f"{machines} machines sharing the store (each claims its own tiles)")
