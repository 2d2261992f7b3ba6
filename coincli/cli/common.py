"""Options shared by every command, the scene they build, and one-line error reporting."""

from __future__ import annotations

import contextlib
import json
import sys
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from ..params import ParameterError, Scene, validate
from ..presets import load

console = Console()
err_console = Console(stderr=True)

PHYS = "Physical parameters (override the preset)"
INIT = "Initial state"
INTEG = "Integration"

PresetOpt = Annotated[str, typer.Option("--preset", "-p", help="Preset name (see `coin presets`) "
                                        "or path to a TOML file.", rich_help_panel=PHYS)]
DiameterOpt = Annotated[float | None, typer.Option("--diameter", help="Coin diameter d (m).",
                                                   rich_help_panel=PHYS)]
ThicknessOpt = Annotated[float | None, typer.Option("--thickness", help="Coin thickness t (m).",
                                                    rich_help_panel=PHYS)]
MassOpt = Annotated[float | None, typer.Option("--mass", help="Coin mass m (kg).",
                                               rich_help_panel=PHYS)]
InertiaOpt = Annotated[float | None, typer.Option("--inertia", help="Moment of inertia I "
                                                  "(kg m^2).", rich_help_panel=PHYS)]
KOpt = Annotated[float | None, typer.Option("--k", help="Foundation stiffness per corner "
                                            "(N/m).", rich_help_panel=PHYS)]
COpt = Annotated[float | None, typer.Option("--c", help="Viscous damping per corner (N s/m).",
                                            rich_help_panel=PHYS)]
GOpt = Annotated[float | None, typer.Option("--g", help="Gravity (m/s^2).", rich_help_panel=PHYS)]

X0Opt = Annotated[float | None, typer.Option("--x0", help="Initial x (m).", rich_help_panel=INIT)]
Y0Opt = Annotated[float | None, typer.Option("--y0", help="Initial height of the centroid (m) "
                                             "(default r, as in the paper).",
                                             rich_help_panel=INIT)]
Phi0Opt = Annotated[float | None, typer.Option("--phi0", help="Initial angle (rad).",
                                               rich_help_panel=INIT)]
VxOpt = Annotated[float | None, typer.Option("--vx", help="Initial horizontal velocity (m/s).",
                                             rich_help_panel=INIT)]
VyOpt = Annotated[float | None, typer.Option("--vy", help="Initial vertical velocity (m/s).",
                                             rich_help_panel=INIT)]
VphiOpt = Annotated[float | None, typer.Option("--vphi", help="Initial angular velocity "
                                               "(rad/s).", rich_help_panel=INIT)]

MethodOpt = Annotated[str | None, typer.Option("--method", help="Integration method (see "
                                               "`coin methods`).", rich_help_panel=INTEG)]
DtOpt = Annotated[float | None, typer.Option("--dt", help="Step of a fixed-step method, first "
                                             "step of an adaptive one (s).",
                                             rich_help_panel=INTEG)]
RtolOpt = Annotated[float | None, typer.Option("--rtol", help="Relative tolerance of an "
                                               "adaptive method.", rich_help_panel=INTEG)]
TEndOpt = Annotated[float | None, typer.Option("--t-end", help="End time (s).",
                                               rich_help_panel=INTEG)]
StopOpt = Annotated[bool | None, typer.Option("--stop-on-settle/--full", help="Stop as soon as "
                                              "the outcome is certain (E < E_crit), or always "
                                              "run to --t-end as the paper does.",
                                              rich_help_panel=INTEG)]
ForceOpt = Annotated[bool, typer.Option("--force", help="Run a fixed step beyond the method's "
                                        "stable step anyway.", rich_help_panel=INTEG)]
SinglePassOpt = Annotated[bool, typer.Option("--single-pass", help="Run once at the given "
                                             "setting, without climbing the ladder of tighter "
                                             "settings that verifies each label (the label "
                                             "is then unverified).", rich_help_panel=INTEG)]
MaxStepsOpt = Annotated[int | None, typer.Option("--max-steps", help="Step budget of one run "
                                                 "(default: 1,000,000 for an adaptive method, "
                                                 "t_end / dt for a fixed step); a run that "
                                                 "needs more ends with status budget.",
                                                 rich_help_panel=INTEG)]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON object on stdout instead "
                                       "of tables.")]


def fail(message: str) -> typer.Exit:
    """Print a one-line error and return the exit to raise (code 2, like a usage error)."""
    err_console.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    return typer.Exit(code=2)


@contextlib.contextmanager
def user_errors():
    """Turn the errors a user can cause into one line and exit code 2, never a traceback."""
    try:
        yield
    except ParameterError as exc:
        raise fail(str(exc)) from None
    except OSError as exc:  # a read-only or full disk, a missing folder, no permission
        from ..io.paths import describe

        raise fail(describe(exc)) from None


def build_scene(preset: str, **overrides) -> Scene:
    """The preset, overridden by every option the user gave, validated."""
    scene = load(preset).scene.with_overrides(**overrides)
    return validate(scene)


def print_json(data) -> None:
    """One JSON object on stdout; NaN and infinities (no such JSON values) become null."""
    from ..jsonable import jsonable

    sys.stdout.write(json.dumps(jsonable(data), indent=2, allow_nan=False) + "\n")
