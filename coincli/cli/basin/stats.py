"""`coin basin stats STORE`: outcome probabilities with 95 % intervals, certain and uncertain
cells, cost."""

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ...api import __version__
from ..common import (
    JsonOpt,
    console,
    fail,
    print_json,
    user_errors,
)
from ..text import (
    TOP_OUTCOMES,
    TURN,
    counted,
    left_out,
    most_frequent,
    percent,
    print_rows,
    say,
    share,
)
from .group import basin_app, tile_list


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
    from ... import api
    from ...api.basins import export_stats, open_store
    from ...api.options import check_writable
    from ...api.words import describe_error, store_method_text

    with user_errors():
        view = open_store(path)
        if csv_out is not None:
            check_writable(csv_out, what="CSV file")  # before reading the whole store
        stats = api.basin_stats(path)
        if csv_out is not None:
            try:
                export_stats(stats, csv_out)
            except OSError as exc:
                raise fail(describe_error(exc, f"cannot write {csv_out}")) from None
    attrs = view.attrs
    if json_out:
        print_json({"path": str(path), "version": __version__, "store_version": attrs["version"],
                    "parameters": attrs["parameters"], "sweep": attrs["sweep"],
                    "method": attrs["method"],
                    "tiles": stats["tiles_total"], **stats})
        return
    ax0, ax1 = attrs["sweep"]["axes"]
    console.print(f"[bold]coin basin stats[/] {path}", highlight=False)
    say(console, f"{ax0['name']} {ax0['lo']:g}:{ax0['hi']:g} {ax0['units']} x {ax1['name']} "
                 f"{ax1['lo']:g}:{ax1['hi']:g} {ax1['units']}, {ax0['n']} x {ax1['n']} cells, "
                 f"{store_method_text(attrs['method'])}"
                 + (f", friction mu = {attrs['parameters']['foundation']['mu']:g}"
                    if attrs["parameters"]["foundation"].get("mu") else ""))
    if attrs["method"].get("horizon"):
        console.print(f"horizon: {attrs['method']['horizon']}", highlight=False)
    _print_outcomes(stats, every_n)
    _print_summary(stats)


def _num(x, fmt: str = ".3f") -> str:
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, fmt)


def _print_outcomes(stats: dict, every_n: bool) -> None:
    """The table of outcomes: the most frequent n (every n with ``every_n``)."""
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


def _print_summary(stats: dict) -> None:
    """The cells, their status, the certainty, P(standing) and the cost, a row each."""
    warnings = stats["warnings"]
    verified = stats["verified"]
    summary = []
    summary.append(("cells", f"{stats['cells']:,}: {stats['computed']:,} computed "
                             f"({stats['tiles_done']}/{stats['tiles_total']} tiles), "
                             f"{stats['not_computed']:,} not computed"))
    if stats["tiles_damaged"]:
        damaged = stats["tiles_damaged"]
        summary.append(("damaged", f"{counted(len(damaged), 'tile')} failed the integrity "
                                   f"check, counted as not computed: {tile_list(damaged)}; "
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
