"""`coin basin`: resumable chunked sweeps of the outcome n over two initial conditions, into a
Zarr store; `coin basin render` draws one, `coin basin stats` summarises one.

`coin basin OUT.zarr [OPTIONS]` is short for `coin basin sweep OUT.zarr [OPTIONS]`: the group
routes any first argument that is not a subcommand name to `sweep`.
"""

import contextlib
import math
import signal
import threading
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table
from typer.core import TyperGroup

from ..defaults import DEFAULT_CHUNK, DEFAULT_RANGES, DEFAULT_RES
from ..params import ParameterError
from ..version import __version__
from . import app, recording
from .common import (
    INIT,
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
    PresetOpt,
    RtolOpt,
    SinglePassOpt,
    StopOpt,
    TEndOpt,
    ThicknessOpt,
    build_scene,
    compile_first,
    console,
    err_console,
    fail,
    in_cli_words,
    print_json,
    user_errors,
    whole_option,
)
from .recording import LiveConnectOpt, LiveRrdOpt, LiveSpawnOpt
from .text import (
    TOP_OUTCOMES,
    TURN,
    command,
    counted,
    left_out,
    most_frequent,
    percent,
    print_rows,
    print_table,
    say,
    share,
)

SWEEP = "Sweep"
RUN = "Where it runs"


class BasinGroup(TyperGroup):
    """`coin basin PATH ...` runs `sweep`; `coin basin render|stats|sweep ...` as usual."""

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ctx.help_option_names:
            args = ["sweep", *args]
        return super().parse_args(ctx, args)


basin_app = typer.Typer(
    cls=BasinGroup,
    no_args_is_help=True,
    help="Map the final number n of quarter turns over two initial conditions.\n\n"
         "coin basin OUT.zarr [OPTIONS] runs (or resumes) a sweep: it is short for "
         "`coin basin sweep OUT.zarr`, whose --help lists the options. Then "
         "`coin basin render OUT.zarr -o basin.png`, `coin basin stats OUT.zarr`, "
         "`coin basin show OUT.zarr` (in the Rerun viewer), and "
         "`coin basin verify OUT.zarr` to check a store.",
)
app.add_typer(basin_app, name="basin")


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


class _Stop:
    """First Ctrl-C: finish the tiles in flight, then stop. Second: stop at once."""

    def __init__(self):
        self.event = threading.Event()
        self.previous = None

    @property
    def requested(self) -> bool:
        return self.event.is_set()

    def __enter__(self):
        self.previous = signal.getsignal(signal.SIGINT)
        if self.previous is signal.SIG_IGN:  # e.g. a background job: leave it alone
            self.previous = None
            return self
        try:
            signal.signal(signal.SIGINT, self._handle)
        except ValueError:  # not the main thread: Ctrl-C is not ours to handle
            self.previous = None
        return self

    def _handle(self, signum, frame):
        if self.requested:
            raise KeyboardInterrupt
        self.event.set()
        err_console.print("[yellow]interrupt:[/] finishing the tiles in flight, then stopping "
                          "(Ctrl-C again to stop at once; rerun the same command to resume)")

    def __exit__(self, *exc):
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)
        return False


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
    threads: Annotated[int | None, typer.Option("--threads", help="Threads computing tiles "
                                                "on this machine (default: one per core).",
                                                rich_help_panel=RUN, parser=whole_option,
                                                metavar="N")] = None,
    workers: Annotated[int | None, typer.Option("--workers", help="Start a local Dask "
                                                "cluster of N worker processes and run the "
                                                "tiles on it.", rich_help_panel=RUN,
                                                parser=whole_option, metavar="N")] = None,
    scheduler: Annotated[str | None, typer.Option("--scheduler", help="Run the tiles as Dask "
                                                  "tasks on the cluster at this address "
                                                  "(tcp://HOST:PORT); every worker writes its "
                                                  "tiles to PATH, so PATH must be the same "
                                                  "shared directory on all of them.",
                                                  rich_help_panel=RUN)] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", metavar="", help="No progress bar.",
                                        rich_help_panel=RUN)] = False,
    yes: Annotated[bool, typer.Option("--yes", "-y", metavar="",
                                      help="Start a sweep estimated to take "
                                      "more than 12 hours anyway.",
                                      rich_help_panel=RUN)] = False,
    rrd: LiveRrdOpt = None, spawn: LiveSpawnOpt = False, connect: LiveConnectOpt = None,
    preset: PresetOpt = "paper",
    diameter: DiameterOpt = None, thickness: ThicknessOpt = None, mass: MassOpt = None,
    inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None, g: GOpt = None,
    method: MethodOpt = None, dt: DtOpt = None, rtol: RtolOpt = None, t_end: TEndOpt = None,
    stop_on_settle: StopOpt = None, force: ForceOpt = False, single_pass: SinglePassOpt = False,
    max_steps: MaxStepsOpt = None,
) -> None:
    """Sweep two initial conditions over a grid and store n for every cell (resumable).

    Defaults: the paper's setting (x0 = 0, y0 = r, phi0 = 0, vx0 = 0) over vy0 in 0.05:2 m/s and vphi0 in -20:20 rad/s, 512 x 512 cells. Running the same command again resumes the sweep (and recomputes any damaged tile); several processes or machines may run it on one store at once. Ctrl-C stops after the tiles in flight, a second Ctrl-C at once. A sweep estimated at over 12 hours is refused without --yes.

    Example:

    coin basin out.zarr --vy 0:2 --vphi -20:20 --res 512
    """  # noqa: E501
    from ..io.sweep_recording import recorder_for

    # a recording's process starts first (if `coin` has not started it already): it imports
    # Rerun while this one plans the sweep
    recorder = recorder_for(rrd is not None or spawn or connect is not None)
    try:
        from .. import api

        with user_errors():
            scene = build_scene(preset, diameter=diameter, thickness=thickness, mass=mass,
                                inertia=inertia, k=k, c=c, g=g, method=method, dt=dt,
                                rtol=rtol, t_end=t_end, stop_on_settle=stop_on_settle,
                                max_steps=max_steps, verify=False if single_pass else None)
            plan = api.plan_sweep(scene, res=res, chunk=chunk, force=force,
                                  mirror=not no_mirror, x0=x0, y0=y0, phi0=phi0, vx=vx, vy=vy,
                                  vphi=vphi)
            api.check_where(threads, workers, scheduler)
        where_to, no_viewer = recording.destination(rrd, spawn, connect)
        # before the sweep: its pilot estimate is the first run of the kernels (a store that
        # is already complete on a fresh install is the one case compiled for without need)
        compile_first(quiet)
    except BaseException:
        if recorder is not None:  # the recording will not be made: its process ends
            recorder.cancel()
        raise
    if recorder is not None:
        if where_to is None:  # --spawn alone, without a display
            recorder.cancel()
            recorder = None
        else:
            recorder.record(path, plan.attrs, where_to, verified=plan.spec.ladder.verified)
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from ..io import store as store_io
    from ..io.paths import DISK_ERRORS, NotWritable, describe
    from ..io.runner import SchedulerLost
    from . import interruptions
    from .progress import Bars, RateColumn

    grid = plan.grid
    progress = Bars(
        TextColumn("[bold]basin[/]"), BarColumn(),
        TextColumn("{task.fields[tiles]}/{task.fields[ntiles]} tiles"),
        RateColumn("cells"), TimeElapsedColumn(),
        TextColumn("ETA"), TimeRemainingColumn(),
        console=err_console, disable=quiet, transient=False)
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
        if start.repaired:
            say(err_console, f"[yellow]repaired:[/] {path}: {len(start.repaired)} metadata "
                             f"file(s) differed from the sweep's and were rewritten: "
                             f"{', '.join(start.repaired[:6])}")
        if start.damaged:
            say(err_console, f"[yellow]damaged:[/] {counted(len(start.damaged), 'tile')} of "
                             f"{path} failed the integrity check, recomputed now: "
                             f"{_tile_list(start.damaged)}")
        if 0 < start.tiles_done < start.tiles_total:
            say(err_console, f"resuming {path}: {start.tiles_done} of "
                             f"{counted(start.tiles_total, 'tile')} done already, "
                             f"{counted(start.tiles_total - start.tiles_done, 'tile')} to "
                             "compute")
        est = start.estimate
        if est is not None and est.seconds > 60:
            say(err_console, f"estimate: {_estimate_text(est, plan, scheduler)}")
        if start.cells_todo and not quiet:
            progress.start()

    try:
        with _Stop() as stop, recorder or contextlib.nullcontext():
            try:
                report = api.sweep(plan, path, overwrite=overwrite, threads=threads,
                                   workers=workers, scheduler=scheduler, progress=show,
                                   stop=stop.event, on_start=started,
                                   max_seconds=None if yes else MAX_SECONDS)
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
        raise fail(describe(exc, f"cannot write {path}" if disk else "cannot run the sweep")
                   + ("; the tiles written so far are kept: rerun the command to resume"
                      if disk and store_io.is_store(path) else "")) from None
    if recorder is not None and recorder.error is None:
        say(console, recording.recorded(where_to))
    total = report.tiles_total
    if report.tiles_before == total:
        say(console, f"{path}: every tile is done already ({counted(total, 'tile')}, "
                     f"{counted(grid.n_cells, 'cell')}). "
                     f"Next: {command('coin', 'basin', 'render', path)}; "
                     f"{command('coin', 'basin', 'stats', path)}")
        recording.finish(recorder, no_viewer)
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
                 f"{report.wall_seconds:.1f} s wall, {rate:,.0f} "
                 f"cells/s on {where}{others}.")
    if report.interrupted or not report.complete:
        say(err_console, f"[yellow]stopped:[/] {interruptions.stopped_by()}"
                         f"{counted(total - report.tiles_done, 'tile')} left; run the same "
                         "command again to resume.")
        recording.finish(recorder, no_viewer, exit_code=None)
        raise typer.Exit(code=130)
    say(console, f"Next: {command('coin', 'basin', 'render', path, '-o', 'basin.png')}; "
                 f"{command('coin', 'basin', 'stats', path)}")
    recording.finish(recorder, no_viewer)


MAX_SECONDS = 12 * 3600.0  # a sweep estimated longer is refused without --yes


def _tile_list(tiles, most: int = 8) -> str:
    text = ", ".join(f"({i}, {j})" for i, j in list(tiles)[:most])
    return text + (f" and {len(tiles) - most} more" if len(tiles) > most else "")


def _estimate_text(est, plan, scheduler) -> str:
    from ..api import format_duration

    bound = "at least" if est.at_least else "about"
    on = (f"on {est.workers} {'core' if est.workers == 1 else 'cores'}" if est.workers
          else f"of CPU time over the cluster at {scheduler}")
    mirrored = ", as many again mirrored" if plan.grid.mirror_dims else ""
    return (f"{bound} {format_duration(est.seconds)} {on} for {est.cells:,} cells{mirrored} "
            f"({est.cpu_per_cell * 1e3:.3g} ms a cell, from a pilot of {est.pilot_cells} "
            f"cells)")


def _too_long(est, plan, scheduler) -> str:
    """One line: how long, and how to split the sweep."""
    from ..api import format_duration

    n0, n1 = plan.grid.shape
    scale = math.sqrt(MAX_SECONDS / est.seconds) if est.seconds > 0 else 1.0
    r0, r1 = (max(2, int(n * scale) // 64 * 64 or int(n * scale)) for n in (n0, n1))
    smaller = f"--res {r0}" if (n0 == n1 and r0 == r1) else f"--res {r0}x{r1}"
    machines = math.ceil(est.seconds / MAX_SECONDS)
    return (f"this sweep would take {_estimate_text(est, plan, scheduler)}. Give --yes to start it "
            f"anyway, or split it: a smaller {smaller} (about "
            f"{format_duration(MAX_SECONDS)} here), narrower ranges, or this same command on "
            f"{machines} machines sharing the store (each claims its own tiles)")


@basin_app.command("verify")
def verify_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    json_out: JsonOpt = False,
) -> None:
    """Check a store without computing anything: checksums, digests and metadata.

    Every chunk's checksum, every tile's data against its digest, every metadata file.

    Exit code 0 if the store is intact (complete or not), 1 if anything is damaged (listed: rerunning the sweep command recomputes those tiles), 2 if it is no basin store.
    """  # noqa: E501 (typer keeps a docstring's line breaks)
    from .. import api
    from ..io.store import StoreDamaged

    damage = None
    with user_errors():
        try:
            found = api.verify_basin(path)
        except StoreDamaged as exc:  # its metadata: no tile can be checked
            damage = exc
    if damage is not None:
        exc = damage
        if json_out:
            print_json({"path": str(path), "intact": False, "error": in_cli_words(exc)})
        else:
            say(err_console, f"[bold red]damaged:[/] {escape(in_cli_words(exc))}")
        raise typer.Exit(code=1) from None
    total = int(found.done.size)
    unrepaired = [k for k in found.metadata if k not in found.repaired]
    if json_out:
        print_json({"path": str(path), "intact": found.intact, "tiles": total,
                    "tiles_done": found.tiles_done, "not_computed": total - found.tiles_done
                    - len(found.damaged),
                    "damaged": [{"tile": list(t), "reason": why}
                                for t, why in sorted(found.damaged.items())],
                    "metadata": unrepaired, "parameters_changed": found.problems,
                    "leftover_temporary_files": found.leftovers, "seconds": found.seconds})
    elif found.intact:
        missing = total - found.tiles_done
        say(console, f"{path}: intact: {found.tiles_done} of {total} tiles done and verified"
                     + (f", {missing} not computed yet" if missing else "")
                     + f" ({found.seconds:.2f} s)")
    else:
        what = [counted(len(found.damaged), "tile")] if found.damaged else []
        what += [counted(len(unrepaired), "metadata file")] if unrepaired else []
        say(console, f"{path}: DAMAGED: {' and '.join(what)}; {found.tiles_done} of {total} "
                     f"tiles intact ({found.seconds:.2f} s). Rerun the sweep command (with the "
                     "store's parameters) to "
                     + " and ".join((["recompute the damaged tiles"] if found.damaged else [])
                                    + (["rewrite the metadata"] if unrepaired else [])) + ".")
        for problem in found.problems:
            say(console, f"  parameters changed in {problem}")
        for tile, why in sorted(found.damaged.items()):
            say(console, f"  tile {tile}: {why}")
        for key in unrepaired:
            say(console, f"  metadata {key}: differs from what the parameters of its tiles "
                         "give")
    if found.leftovers and not json_out:
        say(err_console, f"note: {found.leftovers} temporary file(s) of interrupted writes "
                         "(*.partial); the next sweep removes them")
    if not found.intact:
        raise typer.Exit(code=1)


def _mark(text: str) -> tuple[float, float]:
    """--mark V,W as two numbers."""
    from ..params import parse_number, shown

    parts = text.split(",")
    if len(parts) != 2:
        raise ParameterError(f"--mark '{shown(text)}' is not V,W (the values of the two swept "
                             "axes)")
    try:
        return parse_number(parts[0]), parse_number(parts[1])
    except ParameterError as exc:
        raise ParameterError(f"--mark '{shown(text)}': {exc}") from None


@basin_app.command("render")
def render_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    out: Annotated[Path | None, typer.Option("--out", "-o", metavar="FILE", help="PNG, SVG or "
                                             "PDF to write (default: the store's name with "
                                             ".png).")] = None,
    title: Annotated[str | None, typer.Option("--title", help="Title of the picture.")] = None,
    dpi: Annotated[int, typer.Option("--dpi", help="Resolution of the PNG.",
                                     parser=whole_option, metavar="N")] = 150,
    n_max: Annotated[int | None, typer.Option("--n-max", metavar="N", help="Colour scale up "
                                              "to |n| = N (larger |n| take its ends) "
                                              "[dim]\\[24][/dim]", parser=whole_option)] = None,
    field: Annotated[str, typer.Option("--field", metavar="NAME", help="What to draw: n (the "
                                       "outcome) or settle_time (when it was decided).")]
    = "n",
    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also save the map to this Rerun "
                                             "recording (SegmentationImage with an "
                                             "AnnotationContext).")] = None,
    mark: Annotated[list[str] | None, typer.Option("--mark", metavar="V,W", help="Mark the "
                                                   "throw at V (first swept axis), W (second) "
                                                   "with a white circle; repeatable. `coin "
                                                   "basin inspect STORE` with the same values "
                                                   "replays it.")] = None,
) -> None:
    """Draw a basin store to a PNG, SVG or PDF in the paper's colours, or its settle-time map.

    n < 0 (clockwise) yellow to red, n > 0 (counter-clockwise) green to blue, n = 0 white, standing (odd n) black; uncertain cells grey, no outcome by t_end purple, non-finite magenta, not computed hatched. Works on partial stores.
    """  # noqa: E501
    from .. import api
    from ..io.paths import check_rrd_path, check_writable, describe
    from ..io.store import read_basin

    with user_errors():
        if dpi < 10 or dpi > 1200:
            raise ParameterError(f"--dpi must be between 10 and 1200, got {dpi}")
        if rrd is not None and rrd.suffix != ".rrd":
            raise ParameterError(f"--rrd {rrd}: the file name must end in .rrd")
        target = out if out is not None else path.with_suffix(".png")
        if target.suffix.lower() not in (".png", ".svg", ".pdf"):
            raise ParameterError(f"-o {target}: the file name must end in .png, .svg or .pdf")
        if n_max is not None and n_max < 1:
            raise ParameterError(f"--n-max must be at least 1, got {n_max}")
        marks = [_mark(text) for text in mark or ()]
        basin = read_basin(path)
        check_writable(target, what="picture")  # before drawing
        if rrd is not None:
            check_rrd_path(rrd)
        try:
            api.render_basin(basin, target, title=title, dpi=dpi, n_max=n_max, field=field,
                             marks=marks)
        except OSError as exc:
            raise fail(describe(exc, f"cannot write {target}")) from None
        console.print(f"wrote {target}")
        _damaged_note(path, basin.damaged, "drawn as not computed")
        if rrd is not None:
            from ..io.live import Destination, show_basin  # as `coin basin show --rrd`

            try:
                show_basin(basin, Destination(rrd=rrd))
            except OSError as exc:
                raise fail(describe(exc, f"cannot write {rrd}")) from None
            say(console, f"wrote {rrd} (open with: {command('rerun', rrd)})")


@basin_app.command("show")
def show_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    rrd: LiveRrdOpt = None, spawn: LiveSpawnOpt = False, connect: LiveConnectOpt = None,
) -> None:
    """Open a basin store in the Rerun viewer: the map of n in the paper's colours (hover a cell: "n = 7, standing"), the uncertain and unfinished cells over it, cells not computed left grey.

    Opens a viewer unless --rrd or --connect is given (--spawn as well: both). Works on partial stores.

    Example:

    coin basin show out.zarr --rrd out.rrd
    """  # noqa: E501
    from ..io.live import show_basin
    from ..io.store import read_basin

    with user_errors():
        basin = read_basin(path)
    if rrd is None and connect is None:  # a viewer, then, or nothing to do
        from ..io.rrd import NO_DISPLAY, display_available

        if not display_available():
            say(err_console, f"[bold red]error:[/] {NO_DISPLAY} here: write the recording "
                             "with --rrd FILE (open it with `rerun FILE` where there is one), "
                             "or stream it to a running viewer with --connect URL")
            raise typer.Exit(code=1)
        spawn = True
    where_to, no_viewer = recording.destination(rrd, spawn, connect)
    _damaged_note(path, basin.damaged, "shown as not computed")
    try:
        show_basin(basin, where_to)
    except (OSError, RuntimeError) as exc:
        from ..io.paths import describe

        raise fail("could not write the recording: "
                   + (describe(exc) if isinstance(exc, OSError) else str(exc))) from None
    done, total = int(basin.done.sum()), int(basin.done.size)
    say(console, f"{path}: {done} of {counted(total, 'tile')} computed; "
                 f"{recording.recorded(where_to)}")
    if no_viewer:
        raise typer.Exit(code=1)


def _damaged_note(path, damaged, treated: str) -> None:
    if damaged:
        say(err_console, f"[yellow]damaged:[/] {counted(len(damaged), 'tile')} of {path} "
                         f"failed the integrity check, {treated}: {_tile_list(damaged)}; rerun "
                         "the sweep command to recompute")



@basin_app.command("stats")
def stats_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    json_out: JsonOpt = False,
    csv_out: Annotated[Path | None, typer.Option("--csv", metavar="FILE", help="Also write the "
                                                 "outcome table to this CSV file.")] = None,
    every_n: Annotated[bool, typer.Option("--all", metavar="", help="List every n (by default "
                                          f"the {TOP_OUTCOMES} most frequent; --json and --csv "
                                          "always list every n).")] = False,
) -> None:
    """Outcome probabilities (95 % Wilson intervals), certain and uncertain cells, and cost.

    Count and fraction of each n over the labelled cells and, for a verified sweep, over the certain cells only; P(standing) with and without the uncertain cells; the cells unsettled, non-finite, over budget or not computed; the CPU and wall time of the sweep.
    """  # noqa: E501 (typer keeps a docstring's line breaks)
    from .. import api
    from ..io.paths import check_writable, describe
    from ..io.store import open_view

    with user_errors():
        view = open_view(path)
        if csv_out is not None:
            check_writable(csv_out, what="CSV file")  # before reading the whole store
        stats = api.basin_stats(path)
        if csv_out is not None:
            try:
                _write_csv(stats, csv_out)
            except OSError as exc:
                raise fail(describe(exc, f"cannot write {csv_out}")) from None
    attrs = view.attrs
    warnings = stats["warnings"]
    if json_out:
        print_json({"path": str(path), "version": __version__, "store_version": attrs["version"],
                    "sweep": attrs["sweep"], "method": attrs["method"],
                    "tiles": stats["tiles_total"], **stats})
        return
    ax0, ax1 = attrs["sweep"]["axes"]
    console.print(f"[bold]coin basin stats[/] {path}", highlight=False)
    console.print(f"{ax0['name']} {ax0['lo']:g}:{ax0['hi']:g} {ax0['units']} x {ax1['name']} "
                  f"{ax1['lo']:g}:{ax1['hi']:g} {ax1['units']}, {ax0['n']} x {ax1['n']} cells, "
                  f"{attrs['method']['name']}", highlight=False)
    if attrs["method"].get("horizon"):
        console.print(f"horizon: {attrs['method']['horizon']}", highlight=False)
    verified = stats["verified"]
    table = Table(title="Outcomes (fractions of the labelled cells)", title_justify="left")
    for col, just in (("n", "right"), ("pose", "left"), ("turn", "left"), ("cells", "right"),
                      ("fraction", "right")):
        table.add_column(col, justify=just, no_wrap=True)
    certain_rows = {}
    if verified:
        table.add_column("certain", justify="right", no_wrap=True)
        table.add_column("of certain", justify="right", no_wrap=True)
        certain_rows = {r["n"]: r for r in stats["outcomes_certain"]}
    shown, hidden = ((stats["outcomes"], []) if every_n
                     else most_frequent(stats["outcomes"]))
    for row in shown:
        style = "bold magenta" if row["pose"] == "standing" else None
        cells = [str(row["n"]), row["pose"], TURN[row["direction"]], f"{row['count']:,}",
                 percent(row["fraction"])]
        if verified:
            r = certain_rows.get(row["n"])
            cells += [f"{r['count']:,}", percent(r["fraction"])] if r else ["0", "-"]
        table.add_row(*cells, style=style)
    console.print(table)
    if hidden:
        say(console, left_out(hidden, sum(row["fraction"] for row in hidden), "labelled cells"))
    summary = []
    summary.append(("cells", f"{stats['cells']:,}: {stats['computed']:,} computed "
                             f"({stats['tiles_done']}/{stats['tiles_total']} tiles), "
                             f"{stats['not_computed']:,} not computed"))
    if stats["tiles_damaged"]:
        damaged = stats["tiles_damaged"]
        summary.append(("damaged", f"{counted(len(damaged), 'tile')} failed the integrity "
                                   f"check, counted as not computed: {_tile_list(damaged)}; "
                                   "rerun the sweep command to recompute"))
    counts = ", ".join(f"{count:,} {name}" for name, count in stats["status"].items()
                       if count and name != "not computed")
    summary.append(("status", counts or "-"))
    summary += [("warning" if i == 0 else "", w) for i, w in enumerate(warnings)]
    if verified:
        u = stats["uncertain"]
        summary.append(("certain", share(stats["certain"])))
        summary.append(("uncertain", f"{u['count']:,} of {u['of']:,} = {percent(u['probability'])}"
                                     f" (no two rungs agreed): {u['chaotic']:,} chaotic "
                                     f"(decided, rungs disagree), {u['undecided']:,} undecided "
                                     f"(a rung not settled); {u['standing']:,} of them "
                                     "standing"))
        summary.append(("standing", f"{share(stats['standing_certain'])} of the certain "
                                    "cells"))
        summary.append(("", f"{share(stats['standing_decided'])} of the decided cells"))
        summary.append(("", f"{share(stats['standing'])} of all labelled cells"))
    else:
        summary.append(("standing", share(stats["standing"])))
        summary.append(("verified", "no: a single pass (labels unverified)"))
    cost = stats["cost"]
    if not stats["computed"]:
        summary.append(("cost", "nothing computed yet"))
    elif "cpu_seconds" in cost:
        summary.append(("cost", f"{_num(cost['cpu_seconds'], '.4g')} CPU s, "
                                f"{_num(cost['cpu_ms_per_cell'], '.3g')} ms a cell, "
                                f"{_num(cost['trajectories_per_cpu_second'], ',.0f')} cells "
                                "per CPU s"))
    if cost.get("wall_seconds"):
        runs = cost["runs"]
        summary.append(("wall", f"{_num(cost['wall_seconds'], '.4g')} s over {runs} "
                                f"run{'s' if runs != 1 else ''}, "
                                f"{_num(cost['trajectories_per_second'], ',.0f')} cells/s"))
    print_rows(console, summary)


def _write_csv(stats: dict, target: Path) -> None:
    import csv

    from ..io.paths import atomic_output

    certain = {r["n"]: r for r in stats.get("outcomes_certain", [])}
    with atomic_output(target) as tmp, open(tmp, "w", newline="") as fh:
        writer = csv.writer(fh)
        header = ["n", "pose", "direction", "cells", "fraction", "low", "high"]
        if stats["verified"]:
            header += ["certain_cells", "fraction_of_certain", "certain_low", "certain_high"]
        writer.writerow(header)
        for row in stats["outcomes"]:
            line = [row["n"], row["pose"], row["direction"], row["count"], row["fraction"],
                    row["low"], row["high"]]
            if stats["verified"]:
                r = certain.get(row["n"])
                line += ([r["count"], r["fraction"], r["low"], r["high"]] if r
                         else [0, 0.0, "", ""])
            writer.writerow(line)


__all__ = ["basin_app"]


def _num(x, fmt: str = ".3f") -> str:
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, fmt)


def _span(region) -> str:
    lo, hi = region.span
    return f"{lo:.3g}-{hi:.3g}"


def _local(exp_local) -> str:
    """'0.93 -> 0.31': the local exponent at the smallest and at the largest eps."""
    finite = [x for x in exp_local if math.isfinite(x)]
    if not finite:
        return "-"
    if len(finite) == 1:
        return f"{finite[0]:.2f}"
    return f"{finite[0]:.2f} -> {finite[-1]:.2f}"


@basin_app.command("analyze")
def analyze_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    box: Annotated[int, typer.Option("--box", metavar="CELLS", help="Box size of the basin "
                                     "entropy, in cells.", parser=whole_option)] = 5,
    bands: Annotated[int, typer.Option("--bands", metavar="N", help="Bands of the first swept "
                                       "axis (vy0 by default) measured one by one.",
                                       parser=whole_option)] = 4,
    points: Annotated[int | None, typer.Option("--points", metavar="N", help="Random initial "
                                               "conditions of the perturbation method; 0 "
                                               "skips it. [dim]\\[150,000: about a minute on "
                                               "2 cores][/dim]", parser=whole_option)] = None,
    eps: Annotated[str, typer.Option("--eps", metavar="LO:HI", help="Perturbation sizes, "
                                     "relative to each swept axis's range (log-spaced).")]
    = "1e-9:1e-4",
    eps_values: Annotated[int, typer.Option("--eps-values", metavar="N", help="How many "
                                            "perturbation sizes in --eps.",
                                            parser=whole_option)] = 6,
    radius: Annotated[float, typer.Option("--radius", metavar="CELLS", help="Ball radius of "
                                          "the fractal test.")] = 5.0,
    balls: Annotated[int, typer.Option("--balls", metavar="N", help="Boundary balls of the "
                                       "fractal test.", parser=whole_option)] = 1000,
    max_dilation: Annotated[int, typer.Option("--max-dilation", metavar="CELLS", help="Largest "
                                              "dilation of the Wada merging test.",
                                              parser=whole_option)] = 6,
    seed: Annotated[int, typer.Option("--seed", metavar="N", help="Seed of the random points, "
                                      "perturbations and balls.", parser=whole_option)] = 0,
    threads: Annotated[int | None, typer.Option("--threads", metavar="N", help="Threads "
                                                "running the simulator (default: one per "
                                                "core).", parser=whole_option)] = None,
    figure: Annotated[Path | None, typer.Option("--figure", "-o", metavar="FILE", help="Also "
                                                "draw f(eps) and the measures by band to this "
                                                ".png or .svg.")] = None,
    json_out: JsonOpt = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", metavar="",
                                        help="No progress bar.")] = False,
    rrd: LiveRrdOpt = None, spawn: LiveSpawnOpt = False, connect: LiveConnectOpt = None,
) -> None:
    """How fractal the basin boundaries are: whole map and by band of the first axis.

    On the map (uncertain and not-computed cells left out): basin entropy S_b and boundary basin entropy S_bb in boxes (Daza et al. 2016) with the log-2 criterion, the ball test for fractal boundaries (Puy et al. 2021), the Wada merging test. With the simulator: the uncertainty exponent alpha by the perturbation method (McDonald et al. 1985) from random initial conditions perturbed far below the grid spacing, classified with verified labels (only certain ones count); D = 2 - alpha.

    Example:

    coin basin analyze out.zarr --bands 4 -o analysis.png
    """  # noqa: E501
    from .. import api
    from ..analysis import DEFAULT_POINTS
    from ..analysis import eps_values as make_eps
    from ..grid import parse_range
    from ..io.paths import check_figure_path, check_rrd_path
    from ..io.store import read_basin

    with user_errors():
        span = parse_range("eps", eps)
        if not isinstance(span, tuple):
            raise ParameterError(f"--eps '{eps}' is not a LO:HI range")
        eps_list = make_eps(span[0], span[1], eps_values)
        if figure is not None:
            check_figure_path(figure)
            check_rrd_path(figure)  # a writable file path
        basin = read_basin(path)
        api.check_where(threads, None, None)
    where_to, no_viewer = recording.destination(rrd, spawn, connect)
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn

    from .progress import Bars

    progress = Bars(TextColumn("[bold]analyze[/] {task.description}"), BarColumn(),
                        TextColumn("{task.percentage:>3.0f} %"), TimeElapsedColumn(),
                        console=err_console, disable=quiet, transient=True)
    tasks: dict = {}

    def show(stage, done, total):
        if stage not in tasks:
            text = ("measures on the map" if stage == "map"
                    else "perturbation method (simulator)")
            tasks[stage] = progress.add_task(text, total=total)
        progress.update(tasks[stage], completed=done, total=total)

    n_points = DEFAULT_POINTS if points is None else points
    if n_points:
        compile_first(quiet)
    recorder = None
    if where_to is not None:
        from ..io.live import AnalysisRecorder  # Rerun's code only when asked for

        recorder = AnalysisRecorder(basin, where_to, bands=bands, eps=eps_list)
    try:  # Ctrl-C: the simulator's threads stop within a chunk of points, nothing is written
        with user_errors(), progress, recorder or contextlib.nullcontext():
            result = api.analyze(basin, box=box, bands=bands, points=n_points, eps=eps_list,
                                 seed=seed, threads=threads, radius=radius, balls=balls,
                                 max_dilation=max_dilation, progress=show,
                                 on_band=None if recorder is None else recorder.band)
            if recorder is not None:
                recorder.result(result)
    except KeyboardInterrupt:
        err_console.print("[yellow]interrupted:[/] no result")
        raise typer.Exit(code=130) from None
    if figure is not None:
        with user_errors():
            api.render_analysis(result, figure)
    data = result.to_dict()
    if json_out:
        print_json({"path": str(path), "version": __version__, **data,
                    **({"figure": str(figure)} if figure is not None else {})})
    else:
        _print_analysis(path, result, data)
        if figure is not None:
            console.print(f"wrote {figure}")
        if recorder is not None and recorder.error is None:
            say(console, recording.recorded(where_to))
    recording.finish(recorder, no_viewer)


def _print_analysis(path: Path, result, data: dict) -> None:
    from ..boundary import LOG2

    ax0, ax1 = result.axes
    opts = result.options
    w = result.whole
    console.print(f"[bold]coin basin analyze[/] {path}", highlight=False)
    say(console, f"{ax0['name']} {ax0['lo']:g}:{ax0['hi']:g} {ax0['units']} x {ax1['name']} "
                 f"{ax1['lo']:g}:{ax1['hi']:g} {ax1['units']}, {ax0['n']} x {ax1['n']} cells; "
                 f"evidence: {'certain' if result.verified else 'settled (unverified)'} "
                 f"labels, {percent(1 - w.uncertain_cells)} of the cells")
    regions = [w, *result.bands]
    head = f"{ax0['name']} ({ax0['units']})"

    # the tables fit 80 columns without their outer edges (rich would cut a cell short)
    ent = Table(show_edge=False, pad_edge=False)
    for col in (head, "S_b", "S_bb", "S_bb>log2", "balls S_bb", "ball test"):
        ent.add_column(col, justify="left" if col in (head, "ball test") else "right",
                       no_wrap=True)
    for r in regions:
        e, ft = r.entropy, r.fractal_test
        ent.add_row("whole map" if r is w else _span(r), _num(e.basin_entropy),
                    _num(e.boundary_basin_entropy), "yes" if e.fractal_boundary else "no",
                    "-" if ft is None or not ft.balls
                    else f"{_num(ft.boundary_basin_entropy, '.3f')}±{_num(ft.stderr, '.3f')}",
                    "-" if ft is None else ft.verdict, style="bold" if r is w else None)
    print_table(console, ent, f"Basin entropy (boxes of {opts.box} x {opts.box} cells) and "
                              "fractal tests")
    ft = w.fractal_test
    say(console, f"[dim]S_bb>log2: the log-2 criterion (Daza et al. 2016), S_bb > {LOG2:.3f}: "
                 "sufficient for a fractal boundary, not necessary. ball test: Puy et al. "
                 f"(2021), S_bb in {opts.balls:,} random balls of radius {opts.radius:g} cells; "
                 f"smooth when within {_num(ft.low if ft else math.nan)} to "
                 f"{_num(ft.high if ft else math.nan)} (a smooth boundary gives "
                 f"{_num(ft.smooth_value if ft else math.nan)}), fractal outside it, above or "
                 "below (their rule, as in Attractors.jl).[/dim]")

    p = w.perturbation
    if p is not None:
        conf = int(round(100 * opts.confidence))
        exp = Table(show_edge=False, pad_edge=False)
        for col in (head, "alpha", f"{conf} % interval", "D", "local alpha", "left out",
                    "grid"):
            exp.add_column(col, justify="left" if col == head else "right", no_wrap=True)
        impossible = False  # a grid alpha outside 0 to 2 (it would make D < 0 or D > 2)

        def grid_alpha(r) -> str:
            nonlocal impossible
            alpha = r.grid_exponent.alpha if r.grid_exponent else None
            if alpha is not None and math.isfinite(alpha) and not 0.0 <= alpha <= 2.0:
                impossible = True
                return f"{alpha:.2f}*"
            return _num(alpha, ".2f")

        for r, d in zip(regions, [data, *data["bands"]], strict=True):
            x = r.exponent
            exp.add_row("whole map" if r is w else _span(r), _num(r.alpha, ".2f"),
                        "-" if x is None or not math.isfinite(x.alpha_low)
                        else f"{x.alpha_low:.2f} to {x.alpha_high:.2f}",
                        _num(None if x is None else x.boundary_dimension, ".2f"),
                        _local(d["perturbation"]["local_exponents"] if d["perturbation"]
                               else []),
                        percent(r.uncertain_fraction), grid_alpha(r),
                        style="bold" if r is w else None)
        print_table(console, exp, f"Uncertainty exponent: perturbation method, "
                                  f"{p.n_points:,} points, eps {p.eps[0]:.0e} to "
                                  f"{p.eps[-1]:.0e}")
        say(console, "[dim]alpha: slope of log f(eps) against log eps, f the fraction of "
                     "points whose certain label changes under a perturbation eps (relative to "
                     f"each axis's range; the grid spacing is {1 / (ax0['n'] - 1):.1e}); "
                     "D = 2 - alpha. local alpha: the slope between the two smallest and "
                     "between the two largest eps at which some label changes. left out: "
                     "points whose label (or a perturbed one) was not certain. grid: alpha by "
                     "box counting on the map (Attractors.jl's estimator), for comparison"
                     + ("; * outside 0 to 2: no dimension follows, the map does not resolve "
                        "the scaling there" if impossible else "") + ".[/dim]")
    wada = "; ".join(f"{'whole map' if r is w else _span(r)}: "
                     f"{'yes' if r.wada.is_wada else 'no'}" for r in regions)
    say(console, f"Wada (merging method, up to {opts.max_dilation} cells; {w.wada.n_classes} "
                 f"classes on the whole map): {wada}")
    s, c = result.seconds, result.cpu_seconds
    sim = (f", perturbation method {s['perturbation']:.1f} s ({result.trajectories:,} labels "
           f"on {opts.threads} thread{'s' if opts.threads != 1 else ''})" if p is not None
           else f" (no perturbation method: {command('--points', 0)})")
    say(console, f"took {s['total']:.1f} s wall, {c['total']:.1f} CPU s: map measures "
                 f"{s['map']:.1f} s{sim}")


from . import export_cmd  # noqa: E402, F401 - registers `coin basin export` (needs basin_app)
