"""`coin basin analyze STORE`: how fractal the boundaries are (basin entropy, the ball test, the
uncertainty exponent, Wada), on the whole map and by band."""

import contextlib
import math
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ...api import __version__
from ...api.words import format_seconds
from .. import recording
from ..common import (
    JsonOpt,
    compile_first,
    console,
    err_console,
    print_json,
    user_errors,
    whole_option,
)
from ..recording import LiveConnectOpt, LiveRrdOpt, LiveSpawnOpt
from ..text import (
    command,
    percent,
    print_table,
    say,
)
from .group import basin_app, metadata_note


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
    from ... import api
    from ...api.basins import open_store
    from ...api.options import check_figure_path, check_rrd_path, check_where, parse_eps

    with user_errors():
        eps_list = parse_eps(eps, eps_values)
        if figure is not None:
            check_figure_path(figure)
            check_rrd_path(figure)  # a writable file path
        store = open_store(path)
        basin = store.read()
        check_where(threads, None, None)
    metadata_note(store)
    where_to, no_viewer = recording.destination(rrd, spawn, connect)
    if points != 0:  # the perturbation method runs the simulator (by default too)
        from ...api.basins import basin_scene

        with user_errors():
            scene = basin_scene(path)
        compile_first(quiet, scene)  # the store's model: friction's if it has friction
    result, recorder = _run(basin, where_to, quiet, box=box, bands=bands, points=points,
                            eps=eps_list, seed=seed, threads=threads, radius=radius,
                            balls=balls, max_dilation=max_dilation)
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


def _run(basin, where_to, quiet: bool, **options):
    """The analysis with its progress bars and its live recording: (its result, the recorder
    or None). Ctrl-C: the simulator's threads stop within a chunk of points, nothing is
    written, exit 130."""
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn

    from ... import api
    from ..progress import Bars

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

    from ...api.recording import analysis_recorder  # Rerun's code only when asked for

    recorder = analysis_recorder(basin, where_to, bands=options["bands"], eps=options["eps"])
    try:
        with user_errors(), progress, recorder or contextlib.nullcontext():
            result = api.analyze(basin, progress=show,
                                 on_band=None if recorder is None else recorder.band,
                                 **options)
            if recorder is not None:
                recorder.result(result)
    except KeyboardInterrupt:
        err_console.print("[yellow]interrupted:[/] no result")
        raise typer.Exit(code=130) from None
    return result, recorder


def _print_analysis(path: Path, result, data: dict) -> None:
    from ...api.words import LOG2

    ax0, ax1 = result.axes
    opts = result.options
    w = result.whole
    console.print(f"[bold]coin basin analyze[/] {path}", highlight=False)
    say(console, f"{ax0['name']} {ax0['lo']:g}:{ax0['hi']:g} {ax0['units']} x {ax1['name']} "
                 f"{ax1['lo']:g}:{ax1['hi']:g} {ax1['units']}, {ax0['n']} x {ax1['n']} cells"
                 + (f", friction mu = {result.friction:g}" if result.friction else "") + "; "
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
        _print_exponents(result, data, regions, head)
    wada = "; ".join(f"{'whole map' if r is w else _span(r)}: "
                     f"{'yes' if r.wada.is_wada else 'no'}" for r in regions)
    say(console, f"Wada (merging method, up to {opts.max_dilation} cells; {w.wada.n_classes} "
                 f"classes on the whole map): {wada}")
    s, c = result.seconds, result.cpu_seconds
    sim = (f", perturbation method {format_seconds(s['perturbation'])} "
           f"({result.trajectories:,} labels on {opts.threads} "
           f"thread{'s' if opts.threads != 1 else ''})" if p is not None
           else f" (no perturbation method: {command('--points', 0)})")
    say(console, f"took {format_seconds(s['total'])} wall, {format_seconds(c['total'])} CPU: "
                 f"map measures {format_seconds(s['map'])}{sim}")


def _print_exponents(result, data: dict, regions: list, head: str) -> None:
    """The table of the uncertainty exponent, region by region, and what it means."""
    ax0 = result.axes[0]
    opts = result.options
    w, p = result.whole, result.whole.perturbation
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
                 + ("; - where the map (or band) is too small to count boxes on"
                    if any(r.grid_exponent is None for r in regions) else "")
                 + ("; * outside 0 to 2: no dimension follows, the map does not resolve "
                    "the scaling there" if impossible else "") + ".[/dim]")
