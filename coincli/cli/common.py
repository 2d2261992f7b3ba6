"""Options shared by every command, the scene they build, and one-line error reporting."""

import contextlib
import json
import re
import sys
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape

from ..api import ParameterError, Scene
from ..api.options import (
    IC_NAMES,
    parse_number,
    parse_quantity,
    parse_whole,
    read_preset,
    shown,
    validate,
)
from .text import say


def number_option(value) -> float:
    """Read a float option with :func:`coincli.values.parse_number` (typer's ``parser=``): ASCII
    digits only, and a bad value quoted short, where click's float type takes any script's digits
    and quotes a bad value whole. Infinities pass, for the command to refuse naming the
    parameter."""
    if not isinstance(value, str):  # a default
        return value
    try:
        return parse_number(value, finite=False)
    except ParameterError as exc:
        raise typer.BadParameter(str(exc)) from None


def quantity_option(name: str):
    """The parser (typer's ``parser=``) of the option of initial condition ``name``: a number,
    an angle in multiples of pi or a height in multiples of r (:mod:`coincli.quantities`),
    resolved once the coin is known (:meth:`coincli.params.Scene.with_overrides`)."""
    def parse(value):
        if not isinstance(value, str):  # a default
            return value
        try:  # an infinity passes, for the command to refuse naming the parameter
            return parse_quantity(name, value, finite=False)
        except ParameterError as exc:  # click names the option before the message
            raise typer.BadParameter(str(exc).removeprefix(f"{name}: ")) from None

    return parse


def whole_option(value) -> int:
    """Read an int option with :func:`coincli.values.parse_whole` (ASCII digits, quoted short)."""
    if not isinstance(value, str):  # a default
        return value
    try:
        return parse_whole(value)
    except ParameterError as exc:
        raise typer.BadParameter(str(exc)) from None


console = Console()
err_console = Console(stderr=True)

PHYS = "Physical parameters (override the preset)"
INIT = "Initial state"
INTEG = "Integration"


def _paper_defaults() -> dict:
    """The default preset's values, for the help texts (read once: a small TOML file)."""
    try:
        scene = read_preset(None).scene
    except ParameterError:
        return {}
    integ = scene.integration
    return {"diameter": scene.coin.diameter, "thickness": scene.coin.thickness,
            "mass": scene.coin.mass, "inertia": scene.coin.inertia, "k": scene.foundation.k,
            "c": scene.foundation.c, "mu": scene.foundation.mu,
            "slip_velocity": scene.foundation.slip_velocity, "g": scene.g,
            "method": integ.method.label, "dt": integ.dt,
            "rtol": integ.rtol}


_PAPER = _paper_defaults()


def _opt(flag: str, text: str, unit: str, panel: str, key: str | None = None,
         number: bool = True):
    """An option overriding the preset: its unit as the metavar, the default preset's value in
    the help; a number unless ``number=False`` (an initial condition's: a quantity, see
    :func:`quantity_option`)."""
    key = key or flag.lstrip("-").replace("-", "_")
    if key in _PAPER:
        text += f" [dim]\\[paper: {_PAPER[key]:.6g}][/dim]" if isinstance(
            _PAPER[key], float) else f" [dim]\\[paper: {_PAPER[key]}][/dim]"
    parser = (quantity_option(key) if key in IC_NAMES else number_option) if number else None
    return typer.Option(flag, help=text, metavar=unit, rich_help_panel=panel, show_default=False,
                        parser=parser)


def _flag(flags: str, text: str, panel: str | None = None):
    return typer.Option(flags, help=text, metavar="", rich_help_panel=panel)


PresetOpt = Annotated[str, typer.Option("--preset", "-p", metavar="NAME|FILE",
                                        help="Preset name (see `coin presets`) or path to a "
                                             "TOML file.", rich_help_panel=PHYS)]
DiameterOpt = Annotated[float | None, _opt("--diameter", "Coin diameter d.", "m", PHYS)]
ThicknessOpt = Annotated[float | None, _opt("--thickness", "Coin thickness t.", "m", PHYS)]
MassOpt = Annotated[float | None, _opt("--mass", "Coin mass m.", "kg", PHYS)]
InertiaOpt = Annotated[float | None, _opt("--inertia", "Moment of inertia I about the axis "
                                          "normal to the plane.", "kg*m^2", PHYS)]
KOpt = Annotated[float | None, _opt("--k", "Foundation stiffness per corner.", "N/m", PHYS)]
COpt = Annotated[float | None, _opt("--c", "Viscous damping per corner.", "N*s/m", PHYS)]
GOpt = Annotated[float | None, _opt("--g", "Gravity.", "m/s^2", PHYS)]
MuOpt = Annotated[float | None, _opt("--mu", "Coulomb friction coefficient at the corners, "
                                     "0 to 10 (0: none, the paper's model).",
                                     "MU", PHYS)]
SlipVelocityOpt = Annotated[float | None, _opt(
    "--slip-velocity", "Slip velocity of the regularized friction: a corner slipping slower "
    "feels a friction force falling linearly to zero.", "m/s", PHYS)]

X0Opt = Annotated[float | None, _opt("--x0", "Initial x [dim]\\[0][/dim]", "m", INIT)]
Y0Opt = Annotated[float | None, _opt("--y0", "Initial height of the centroid, in m or in "
                                     "multiples of r, the half diagonal (2r) [dim]\\[r: as "
                                     "high as a coin balanced on a corner, the paper's "
                                     "start][/dim]", "m|Nr", INIT)]
Phi0Opt = Annotated[float | None, _opt("--phi0", "Initial angle, e.g. 0.3, pi/2 "
                                       "[dim]\\[0][/dim]", "rad", INIT)]
VxOpt = Annotated[float | None, _opt("--vx", "Initial horizontal velocity [dim]\\[0][/dim]",
                                     "m/s", INIT)]
VyOpt = Annotated[float | None, _opt("--vy", "Initial vertical velocity [dim]\\[0][/dim]",
                                     "m/s", INIT)]
VphiOpt = Annotated[float | None, _opt("--vphi", "Initial angular velocity [dim]\\[0][/dim]",
                                       "rad/s", INIT)]

MethodOpt = Annotated[str | None, _opt("--method", "Integration method (see `coin methods`).",
                                       "NAME", INTEG, number=False)]
DtOpt = Annotated[float | None, _opt("--dt", "Step of a fixed-step method, first step of an "
                                     "adaptive one.", "s", INTEG)]
RtolOpt = Annotated[float | None, _opt("--rtol", "Relative tolerance of an adaptive method "
                                       "(the first rung of the verification ladder).", "RTOL",
                                       INTEG)]
TEndOpt = Annotated[float | None, _opt(
    "--t-end", "A fixed horizon: every run ends at this time, decided or not (\"unsettled\"). "
    "[dim]\\[default: no horizon: a run ends when its outcome is decided, capped at 4 times the "
    "time its energy and the damping need][/dim]", "s", INTEG)]
StopOpt = Annotated[bool | None, _flag("--stop-on-settle/--full", "Stop as soon as the outcome "
                                       "is decided (E < E_crit), or always run to --t-end as "
                                       "the paper does [dim]\\[paper: --stop-on-settle][/dim]",
                                       INTEG)]
ForceOpt = Annotated[bool, _flag("--force", "Run a fixed step beyond the method's stable step "
                                 "anyway.", INTEG)]
SinglePassOpt = Annotated[bool, _flag("--single-pass", "Run once at the given setting, without "
                                      "climbing the ladder of tighter settings that verifies "
                                      "each label (labels are then unverified).", INTEG)]
MaxStepsOpt = Annotated[int | None, typer.Option("--max-steps", metavar="N", help="Step budget "
                                                 "of one run; a run that needs more ends with "
                                                 "status budget [dim]\\[1,000,000 for an "
                                                 "adaptive method, t_end / dt for a fixed "
                                                 "step; a finer fixed step of the ladder gets "
                                                 "it in proportion][/dim]",
                                                 rich_help_panel=INTEG, parser=whole_option)]
JsonOpt = Annotated[bool, typer.Option("--json", metavar="", help="Print one JSON object on "
                                       "stdout instead of tables.")]
RUN = "Where it runs"
ThreadsOpt = Annotated[int | None, typer.Option("--threads", metavar="N", parser=whole_option,
                                                rich_help_panel=RUN, help="Threads on this "
                                                "machine (default: one per core).")]
WorkersOpt = Annotated[int | None, typer.Option("--workers", metavar="N", parser=whole_option,
                                                rich_help_panel=RUN, help="Start a local Dask "
                                                "cluster of N worker processes and run on it.")]
QuietOpt = Annotated[bool, typer.Option("--quiet", "-q", metavar="", rich_help_panel=RUN,
                                        help="No progress bar.")]
WorkerTimeoutOpt = Annotated[float | None, typer.Option(
    "--worker-timeout", metavar="SECONDS", parser=number_option, rich_help_panel=RUN,
    help="On Dask (--workers, --scheduler): stop, exit 3 with the work done kept, once the "
         "cluster has had no worker for this long [dim]\\[default: wait until one joins, "
         "saying so][/dim]")]


LONG_TOKEN = 200  # characters without a space: no word or path, a value pasted by mistake


def clip_values(message: str) -> str:
    """``message`` with every run of LONG_TOKEN or more characters without a space cut short
    (:func:`coincli.values.shown`): whatever quoted a bad value whole (click's own messages
    do), the error stays one readable line."""
    return re.sub(rf"\S{{{LONG_TOKEN},}}", lambda m: shown(m.group()), message)


def _one_line(head: str, style: str, message: str) -> None:
    """``head: message`` on stderr as one line (``message`` plain text)."""
    text = f"[{style}]{head}:[/] {escape(clip_values(message))}"
    say(err_console, text, indent=len(head) + 2)


def fail(message: str) -> typer.Exit:
    """Print a one-line error and return the exit to raise (code 2, like a usage error)."""
    _one_line("error", "bold red", message)
    return typer.Exit(code=2)


def warn(message: str) -> None:
    """Print a one-line warning: the work goes on."""
    _one_line("warning", "yellow", message)


def in_cli_words(exc: ParameterError) -> str:
    """The message of ``exc`` as the command line says it: each parameter the message names
    as an option's (``exc.parameters``: the raiser lists only names that are options where the
    API is called from the command line) by its option, ``t_end`` as ``--t-end``."""
    # what is quoted ('out/rrd.txt') is the user's, said as given; a name after a dot is a
    # file's suffix or an attribute, not the parameter
    parts = re.split(r"((?<!\w)'[^']*'(?!\w))", str(exc))  # not the apostrophe of "store's"
    for name in getattr(exc, "parameters", ()):
        option = "--" + name.replace("_", "-")
        parts = [part if part.startswith("'") else
                 re.sub(rf"(?<![\w.-]){re.escape(name)}(?![\w-])",
                        lambda _, option=option: option, part) for part in parts]
    return "".join(parts)


@contextlib.contextmanager
def user_errors():
    """Turn the errors a user can cause into one line and exit code 2, never a traceback."""
    try:
        yield
    except ParameterError as exc:
        raise fail(in_cli_words(exc)) from None
    except OSError as exc:  # a read-only or full disk, a missing folder, no permission
        from ..api.words import describe_error

        raise fail(describe_error(exc)) from None


def build_scene(preset: str, **overrides) -> Scene:
    """The preset, overridden by every option the user gave, validated."""
    scene = read_preset(preset).scene.with_overrides(**overrides)
    return validate(scene)


STILL_COMPILING_EVERY = 30.0  # s between the lines of a compile whose stderr is no terminal


def compile_first(quiet: bool = False, scene: Scene | None = None, *,
                  model: str | None = None) -> None:
    """Before a command first runs the kernels of ``scene``'s model on this machine (``model``
    names one instead; neither: the paper's), compile them, saying so (once after installing
    or updating; the library compiles in silence): on a terminal a live line counts the
    minutes against the expected time (:func:`coincli.api.throws.compile_seconds`); when
    stderr is no terminal (a log, `make install`), a line every STILL_COMPILING_EVERY seconds,
    so that no minute passes in silence; with ``quiet``, one line before and one after. Ctrl-C
    stops it: exit 130."""
    import threading
    import time

    from ..api.throws import compile_seconds, kernel_model, kernels_cached

    name = model or kernel_model(scene)
    if kernels_cached(model=name):
        return
    from .. import api
    seconds = compile_seconds(model=name)
    what = "the numerical kernels" if name == "paper" else f"the {name} model's numerical kernels"
    why = " (a scene with --mu > 0)" if name == "friction" else ""
    start = time.monotonic()
    try:
        if quiet or not err_console.is_terminal:
            say(err_console, f"[yellow]compiling[/] {what} for this machine{why}: once "
                             f"after installing or updating, about "
                             f"{max(1, round(seconds / 60)):.0f} min")
            done = threading.Event()

            def still() -> None:
                while not done.wait(STILL_COMPILING_EVERY):
                    say(err_console, f"still compiling: {time.monotonic() - start:.0f} s of "
                                     f"about {seconds:.0f} s")

            if not quiet:
                threading.Thread(target=still, name="coin-compile-clock", daemon=True).start()
            try:
                api.compile_kernels(model=name)
            finally:
                done.set()
        else:
            from rich.progress import SpinnerColumn, TextColumn

            from .progress import Bars, CompileClock

            with Bars(SpinnerColumn(), TextColumn(f"[yellow]compiling[/] {what}"),
                      CompileClock(seconds), console=err_console, transient=True) as bars:
                bars.add_task("compile", total=None)
                api.compile_kernels(model=name)
    except KeyboardInterrupt:
        say(err_console, f"[yellow]interrupted:[/] while compiling {what}; nothing was done")
        raise typer.Exit(code=130) from None
    say(err_console, f"compiled {what} in {time.monotonic() - start:.0f} s; later runs load "
                     "them in a second")


def compile_first_for(scenes, quiet: bool = False) -> None:
    """:func:`compile_first` for every model the ``scenes`` run (a continuation over mu runs
    the paper's at mu = 0 and the friction model's beside it), each once."""
    from ..api.throws import kernel_model

    for name in dict.fromkeys(kernel_model(scene) for scene in scenes):
        compile_first(quiet, model=name)


def print_json(data) -> None:
    """One JSON object on stdout; NaN and infinities (no such JSON values) become null."""
    from ..api.words import jsonable

    sys.stdout.write(json.dumps(jsonable(data), indent=2, allow_nan=False) + "\n")
