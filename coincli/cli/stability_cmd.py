"""`coin stability`: the static energy table and the critical stiffnesses (paper, section 3)."""


from rich.table import Table

from ..version import __version__
from . import app
from .common import (
    COpt,
    DiameterOpt,
    GOpt,
    InertiaOpt,
    JsonOpt,
    KOpt,
    MassOpt,
    PresetOpt,
    ThicknessOpt,
    build_scene,
    console,
    print_json,
    user_errors,
)
from .text import say


@app.command("stability")
def stability_command(
    preset: PresetOpt = "paper", diameter: DiameterOpt = None, thickness: ThicknessOpt = None,
    mass: MassOpt = None, inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None,
    g: GOpt = None, json_out: JsonOpt = False,
) -> None:
    """Static states, the energy each needs to lose stability, k_min, k_cr and E_crit."""
    with user_errors():
        scene = build_scene(preset, diameter=diameter, thickness=thickness, mass=mass,
                            inertia=inertia, k=k, c=c, g=g)
    from .. import api

    report = api.stability(scene)
    if json_out:
        print_json({"version": __version__, "parameters": scene.to_dict(), **report.to_dict()})
        return
    from ..statics import MJ as mj
    from ..statics import critical_rows, energy_rows

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
    say(console, "Static states for k = {:g} N/m: {}.".format(report.k, "; ".join(states)))
    if not report.standing_static:
        if report.standing_well_depth > 0:
            say(console,
                f"[bold yellow]k = {report.k:g} N/m is below k_cr = {report.k_cr:.2f} N/m: by the "
                "paper's criterion (eq. 13) a standing coin cannot be at rest.[/] Counting the "
                "foundation's elastic energy, a shallow standing well of "
                f"{report.standing_well_depth * mj:.3g} mJ remains down to k = "
                f"{report.k_stand_exact:.1f} N/m, so a coin may still end standing.")
        elif report.k > report.k_rock:
            say(console,
                f"[bold yellow]k = {report.k:g} N/m is below k_cr / 2 = "
                f"{report.k_stand_exact:.1f} N/m:[/] a standing coin is still a shallow minimum "
                f"of the potential (down to k = {report.k_rock:.1f} N/m, where rocking on its "
                "rim turns unstable), but its energy is above E_crit, so a throw that ends "
                "there is never certified: it stays unsettled.")
        else:
            say(console, f"[bold yellow]k = {report.k:g} N/m is below k_cr = {report.k_cr:.2f} "
                         f"N/m and below {report.k_rock:.1f} N/m, where rocking on the rim "
                         "turns unstable: a standing coin cannot be at rest (by the paper's "
                         "criterion and by the exact energies); every coin ends lying.[/]")
    if not report.single_corner_contact:
        say(console, f"[yellow]k is below k_min = {report.k_min:.1f} N/m: a coin at phi_cr "
                     "sinks onto a second corner (eq. 10 does not hold).[/]")
