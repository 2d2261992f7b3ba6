"""`coin basin inspect`: from a cell of a basin map back to its throw. It prints what the store
holds for the cell, replays the throw with the store's exact parameters and ladder (the label
must come out the same), and the `coin simulate` command that reproduces it; it can record
the replay for the Rerun viewer as `coin simulate` does."""

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ...api import Certainty, __version__
from ...api.options import DEFAULT_LOG_EVERY, DEFAULT_PRESET, IC_NAMES
from ..common import (
    compile_first,
    console,
    err_console,
    fail,
    print_json,
    user_errors,
)
from ..recording import (
    REC,
    ConnectOpt,
    LogEveryOpt,
    SpawnOpt,
    check_log_every,
    destination,
    print_recording,
    record_throw,
)
from ..text import LABEL_WIDTH, NBSP, command, print_rows, say
from .group import basin_app, metadata_note

CELL = "Which cell"


def _at(name: str, unit: str):
    return typer.Option(f"--{name}", metavar="X", help=f"The cell nearest to this {name} "
                        f"({unit}), if it is a swept axis of the store.", rich_help_panel=CELL)


InspectRrdOpt = Annotated[Path | None, typer.Option("--rrd", metavar="PATH", help="Replay the "
                                                    "throw into this .rrd file (open it with "
                                                    "`rerun PATH`).", rich_help_panel=REC)]

# `coin simulate` options for the scene's values, in the order the command prints them
PHYSICAL = ("diameter", "thickness", "mass", "inertia", "k", "c", "mu", "slip_velocity", "g")
INTEGRATION = ("method", "dt", "rtol", "t_end")


def _flat(scene) -> dict:
    """The scene's values by their option names (y0 resolved, the method by name; mu and
    slip_velocity, which a frictionless scene does not record, as the scene has them)."""
    d = scene.to_dict()
    foundation = scene.foundation
    friction = {"mu": float(foundation.mu), "slip_velocity": float(foundation.slip_velocity)}
    flat = {"g": d["g"], **d["coin"], **friction, **d["foundation"], **d["initial"],
            **d["integration"]}
    return flat


def _words(scene, preset, force: bool, always=()) -> list[str] | None:
    """The `coin simulate` words that make ``scene`` from ``preset`` (None if no options can:
    a preset's step budget cannot be unset). Initial values named in ``always`` are given
    even where the preset has them."""
    from ...api.options import validate

    want, have = _flat(scene), _flat(preset.scene)
    words = ["coin", "simulate"]
    if preset.name != DEFAULT_PRESET:
        words += ["--preset", preset.name]
    overrides = {}  # what `coin simulate` makes of the words, for the proof below
    for name in (*PHYSICAL, *IC_NAMES, *INTEGRATION):
        if want[name] != have[name] or name in always:
            value = want[name]
            if value is None:  # t_end: no horizon, which no option sets against a preset's
                if have[name] is None:
                    continue
                return None
            text = value if isinstance(value, str) else repr(float(value))
            words += [f"--{name.replace('_', '-')}", text]
            overrides[name] = text if isinstance(value, str) else float(text)
    if want["stop_on_settle"] != have["stop_on_settle"]:
        words.append("--stop-on-settle" if want["stop_on_settle"] else "--full")
        overrides["stop_on_settle"] = want["stop_on_settle"]
    if want["max_steps"] != have["max_steps"]:
        if want["max_steps"] is None:
            return None
        words += ["--max-steps", str(want["max_steps"])]
        overrides["max_steps"] = want["max_steps"]
    if not want["verify"]:
        words.append("--single-pass")
        overrides["verify"] = False
    elif not have["verify"]:
        return None
    if force:
        words.append("--force")
    try:  # proof: the options as `coin simulate` reads them give this very scene
        rebuilt = validate(preset.scene.with_overrides(**overrides))
    except Exception:  # noqa: BLE001 - this preset cannot give the scene: try another
        return None
    return words if rebuilt.to_dict() == scene.to_dict() else None


def simulate_words(scene, swept=()) -> list[str]:
    """The shortest `coin simulate` command line (as words) that reproduces ``scene`` exactly:
    the shipped preset that needs the fewest options, the others as options, every number in
    repr() precision (it reads back to the same float), the swept initial values always."""
    from ...api import ParameterError
    from ...api.options import available_presets, check_step, read_preset

    try:
        check_step(scene)
        force = False
    except ParameterError:
        force = True
    presets = [read_preset(DEFAULT_PRESET)] + [p for p in available_presets()
                                               if p.name != DEFAULT_PRESET]
    found = [w for w in (_words(scene, p, force, swept) for p in presets) if w is not None]
    if not found:  # cannot happen with the paper preset's own defaults; said plainly if it does
        raise ParameterError("no `coin simulate` command reproduces this scene")
    return min(found, key=len)


def _label(n, certainty: Certainty, status) -> str:
    if n is None:
        return f"no count ({status.label})"
    pose = "standing" if n % 2 else "lying"
    return f"n = {n} ({pose}, {certainty.label})"


@basin_app.command("inspect")
def inspect_command(
    path: Annotated[Path, typer.Argument(help="A basin store (complete or partial).",
                                         metavar="STORE")],
    x0: Annotated[str | None, _at("x0", "m")] = None,
    y0: Annotated[str | None, _at("y0", "m")] = None,
    phi0: Annotated[str | None, _at("phi0", "rad")] = None,
    vx: Annotated[str | None, _at("vx", "m/s")] = None,
    vy: Annotated[str | None, _at("vy", "m/s")] = None,
    vphi: Annotated[str | None, _at("vphi", "rad/s")] = None,
    cell: Annotated[str | None, typer.Option("--cell", metavar="I,J", help="The cell by its "
                                             "index along the first and the second swept "
                                             "axis (from 0).", rich_help_panel=CELL)] = None,
    json_out: Annotated[bool, typer.Option("--json", metavar="", help="Print one JSON object "
                                           "on stdout instead of tables.")] = False,
    rrd: InspectRrdOpt = None, spawn: SpawnOpt = False, connect: ConnectOpt = None,
    log_every: LogEveryOpt = DEFAULT_LOG_EVERY,
) -> None:
    """Show the throw behind a cell of a basin map, replayed with the store's exact parameters.

    The cell nearest to the values of the two swept axes (e.g. --vy 1.2 --vphi 3.5), or --cell I,J. Prints what the store holds for it (label, certainty, rung, settle time), replays the throw up the same ladder (exit 1 if the replay's label differs, or the cell is not computed yet), and the `coin simulate` command that reproduces it. With --rrd, --spawn or --connect the replay is recorded for the Rerun viewer.

    Example:

    coin basin inspect out.zarr --vy 1.2 --vphi 3.5 --rrd throw.rrd
    """  # noqa: E501
    from ...api.basins import inspect_cell, open_store, replay_cell

    # checked before the replay; --spawn without a display is said now (the outcome and any
    # file still follow, exit 1)
    where_to, no_viewer = destination(rrd, spawn, connect)
    recording = where_to is not None
    rrd, spawn, connect = ((where_to.rrd, where_to.spawn, where_to.connect) if recording
                           else (None, False, None))
    with user_errors():
        store = open_store(path)
        found = inspect_cell(path, cell=cell, x0=x0, y0=y0, phi0=phi0, vx=vx, vy=vy,
                             vphi=vphi)
        scene, stored = found.scene, found.stored
        if recording:
            check_log_every(scene, log_every)
        words = simulate_words(scene, swept=found.dims)
        compile_first(scene=scene)
        try:
            run = replay_cell(found, sample_dt=log_every if recording else None,
                              record_events=recording)
        except KeyboardInterrupt:
            err_console.print("[yellow]interrupted[/]: no replay, nothing written")
            raise typer.Exit(code=130) from None
    info, not_written = None, None
    if recording:
        info, not_written = record_throw(run, rrd=rrd, spawn=spawn, connect=connect,
                                         log_every=log_every)
    replay_rung = len(run.rungs) - 1
    matches = (stored.computed and run.quarter_turns == stored.quarter_turns
               and run.certainty == stored.certainty)
    if json_out:
        cell_dict = found.to_dict()
        print_json({
            "path": str(path), "version": __version__,
            **{key: cell_dict[key] for key in ("cell", "dims", "values", "initial", "stored")},
            "replayed": {"quarter_turns": run.quarter_turns, "status": run.status.label,
                         "certainty": run.certainty.label, "rung": replay_rung,
                         "rung_setting": run.rungs[-1].setting if run.rungs else None,
                         "settle_time": None if math.isnan(run.settle_time)
                         else run.settle_time, "steps": run.steps},
            "matches": matches, "ladder_matches": found.ladder_matches,
            "command": " ".join(words), "parameters": scene.to_dict(),
            "rrd": str(info.rrd) if info is not None and info.rrd is not None else None})
    else:
        _print_cell(path, found, run, matches, words)
        metadata_note(store)
        if not found.ladder_matches:
            say(err_console, "[yellow]note:[/] the store records another verification ladder "
                             "than this version climbs (a store of another version)")
        if info is not None:
            print_recording(info)
    if not_written is not None:
        raise fail(f"could not write the recording: {not_written}")
    if not stored.computed:
        raise typer.Exit(code=1)
    if not matches:
        say(err_console, f"[bold red]mismatch:[/] the store holds "
                         f"{_label(stored.quarter_turns, stored.certainty, stored.status)}, "
                         f"the replay gives {_label(run.quarter_turns, run.certainty, run.status)}")
        raise typer.Exit(code=1)
    if no_viewer:
        raise typer.Exit(code=1)


def _print_cell(path, found, run, matches: bool, words) -> None:
    """What the store holds for the cell (``found``, a CellRecord), what its replay gives, and
    the command that reproduces it."""
    replay_rung = len(run.rungs) - 1
    state, stored, index = found.initial, found.stored, found.cell
    where = ", ".join(f"{d} = {state[d]:.6g}" for d in found.dims)
    say(console, f"[bold]coin basin inspect[/] {escape(str(path))}  "
                 f"cell{NBSP}({index[0]},{NBSP}{index[1]}): "
                 f"{where}")
    if stored.computed:
        rung = (f" at {found.rung_setting} (rung {stored.rung})"
                if stored.rung is not None else "")
        settle = ("" if math.isnan(stored.settle_time)
                  else f", decided at t = {stored.settle_time:.6g} s")
        rows = [("stored", f"{_label(stored.quarter_turns, stored.certainty, stored.status)}"
                           f"{rung}{settle}")]
    else:
        rows = [("stored", "not computed yet (its tile is not done): rerun the sweep")]
    verdict = ("the same" if matches else "[red]differs from the stored one[/]"
               if stored.computed else "nothing stored to compare")
    rows.append(("replayed", f"{_label(run.quarter_turns, run.certainty, run.status)} at "
                             f"{run.rungs[-1].setting} (rung {replay_rung}): {verdict}"))
    rows.append(("reproduce", command(*words)))
    print_rows(console, rows, LABEL_WIDTH)
