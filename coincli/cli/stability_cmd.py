"""`coin stability`: the static energy table and the critical stiffnesses (paper, section 3),
and with ``--shock`` the minimal shocks that take a coin at rest out of its well."""

from typing import Annotated

import typer
from rich.table import Table

from ..api import __version__
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
    print_json,
    user_errors,
)
from .text import say


@app.command("stability")
def stability_command(
    preset: PresetOpt = "paper", diameter: DiameterOpt = None, thickness: ThicknessOpt = None,
    mass: MassOpt = None, inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None,
    mu: MuOpt = None, slip_velocity: SlipVelocityOpt = None, g: GOpt = None,
    shock: Annotated[bool, typer.Option(
        "--shock", metavar="", help="Also find the minimal shocks: the smallest kick (vphi, vx "
        "or vy) that takes a coin at rest, lying or standing, to another well, beside the kick "
        "the energy barrier alone asks (a few seconds).")] = False,
    json_out: JsonOpt = False,
) -> None:
    """Static states, the energy each needs to lose stability, k_min, k_cr and E_crit.

    With --shock, the smallest kicks that topple a standing coin or turn a lying one over, beside the kicks the static energy barrier alone asks.
    """  # noqa: E501 (typer keeps a docstring's line breaks)
    with user_errors():
        scene = build_scene(preset, diameter=diameter, thickness=thickness, mass=mass,
                            inertia=inertia, k=k, c=c, mu=mu, slip_velocity=slip_velocity,
                            g=g)
    from .. import api

    report = api.stability(scene)
    shocks = None
    if shock:
        compile_first(quiet=json_out, scene=scene)
        with user_errors():
            shocks = {state: {kind: api.minimal_shock(scene, state, kind) for kind in KICKS}
                      for state in STATES}
    if json_out:
        extra = {} if shocks is None else {
            "shocks": {state: {kind: found.value for kind, found in row.items()}
                       for state, row in shocks.items()},
            "shock_units": {kind: found.unit for kind, found in shocks[STATES[0]].items()},
            "shock_details": {state: {kind: found.to_dict() for kind, found in row.items()}
                              for state, row in shocks.items()}}
        print_json({"version": __version__, "parameters": scene.to_dict(), **report.to_dict(),
                    **extra})
        return
    from ..api.words import MJ as mj
    from ..api.words import critical_rows, energy_rows

    table = Table(title="Static states (energies in mJ)", title_justify="left")
    table.add_column("")
    table.add_column("rigid (eq. 8)", justify="right")
    table.add_column("elastic (eq. 10)", justify="right")
    for row in energy_rows(report):
        table.add_row(*row)
    console.print(table)
    crit = Table(title="Critical values", title_justify="left")
    crit.add_column("")
    crit.add_column("value", justify="right")
    crit.add_column("meaning")
    for row in critical_rows(report):
        crit.add_row(*row)
    console.print(crit)
    states = ["lying (phi = 0): static"]
    if report.standing_static:
        states.append("standing (phi = pi/2): static")
    elif report.standing_static_model:
        states.append("standing (phi = pi/2): static in the model (k > k_cr / 2), not by the "
                      "paper's k_cr")
    say(console, "Static states for k = {:g} N/m: {}.".format(report.k, "; ".join(states)))
    if not report.standing_static:
        if report.standing_well_depth > 0:
            say(console,
                f"[bold yellow]k = {report.k:g} N/m is below the paper's k_cr = "
                f"{report.k_cr:.2f} N/m: by its criterion (eq. 13) a standing coin cannot be at "
                "rest.[/] Counting the foundation's elastic energy, a shallow standing well of "
                f"{report.standing_well_depth * mj:.3g} mJ remains down to k = "
                f"{report.k_stand_exact:.1f} N/m (k_cr / 2, the model's threshold), so a coin "
                "may still end standing.")
        elif report.k > report.k_rock:
            say(console,
                f"[bold yellow]k = {report.k:g} N/m is below k_cr / 2 = "
                f"{report.k_stand_exact:.1f} N/m:[/] a standing coin is still a shallow minimum "
                f"of the potential (down to k = {report.k_rock:.1f} N/m, where rocking on its "
                "rim turns unstable), but its energy is above E_crit, so a throw that ends "
                "there is never certified: it stays unsettled.")
        else:
            say(console, f"[bold yellow]k = {report.k:g} N/m is below the paper's k_cr = "
                         f"{report.k_cr:.2f} N/m and below {report.k_rock:.1f} N/m, where "
                         "rocking on the rim "
                         "turns unstable: a standing coin cannot be at rest (by the paper's "
                         "criterion and by the exact energies); every coin ends lying.[/]")
    if not report.single_corner_contact:
        say(console, f"[yellow]k is below k_min = {report.k_min:.1f} N/m: a coin at phi_cr "
                     "sinks onto a second corner (eq. 10 does not hold).[/]")
    if shocks is not None:
        print_shocks(shocks, scene)


STATES = ("standing", "lying")
SIGNS = {True: "agree", False: "differ", None: "one"}  # do the two signs' values agree
KICKS = ("vphi", "vx", "vy")  # coincli.shock.Kick, named here without loading the kernels


def print_shocks(shocks: dict, scene) -> None:
    """The minimal shocks of ``scene`` as a table, with what each value means below it."""
    from ..api.words import MJ as mj
    from ..api.words import documentation, friction_text

    friction = friction_text(scene)
    table = Table(title="Minimal shocks: the smallest kick to another well"
                        + (f", with friction ({friction})" if friction else ""),
                  title_justify="left")
    for name in ("state", "kick"):
        table.add_column(name)
    for name in ("minimal shock", "static kick", "ratio"):
        table.add_column(name, justify="right")
    table.add_column("signs")
    notes: list[str] = []
    throws = seconds = 0
    for state, row in shocks.items():
        for kind, found in row.items():
            throws, seconds = throws + found.throws, seconds + found.seconds
            mark = ""
            for text in (found.reason, found.note):
                if text:
                    if text not in notes:
                        notes.append(text)
                    mark += f" ({notes.index(text) + 1})"
            static = "-" if found.static_kick is None else f"{found.static_kick:#.5g} {found.unit}"
            if found.value is None:
                table.add_row(state, kind, "none" + mark, static, "", "")
            else:
                table.add_row(state, kind, f"{found.value:#.5g} {found.unit}{mark}", static,
                              f"{found.ratio:.3f}", SIGNS[found.signs_agree])
            state = ""
    console.print(table)
    depth = {state: next(iter(row.values())).depth for state, row in shocks.items()}
    say(console, "A coin at rest on two corners is kicked once: vphi about its centroid, vx or vy "
                 "of its centroid, each sign searched; the minimal shock is the smallest kick "
                 "verified to take it to another well (0.01 % bisection). The static kick is "
                 "what the energy barrier alone asks, sqrt(2 dV / I) for vphi and sqrt(2 dV / m) "
                 "for vx and vy, with dV = E_crit minus the energy at rest, springs counted: "
                 + ", ".join(f"{dv * mj:.5g} mJ {state}" for state, dv in depth.items()) + ".")
    for i, text in enumerate(notes, 1):
        say(console, f"({i}) {text}.", indent=4)
    say(console, f"[dim]{throws:,} throws in {seconds:.1f} s. The table explained: "
                 f"{documentation('stability', 'coin stability')}.[/]")
