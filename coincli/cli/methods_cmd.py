"""`coin methods`: the integration methods with their properties for the current parameters."""

from rich import box
from rich.table import Table

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
    console,
    print_json,
    user_errors,
)
from .text import say


@app.command("methods")
def methods_command(
    preset: PresetOpt = "paper", diameter: DiameterOpt = None, thickness: ThicknessOpt = None,
    mass: MassOpt = None, inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None,
    mu: MuOpt = None, slip_velocity: SlipVelocityOpt = None, g: GOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """List the integration methods: order, adaptive, symplectic, and stable step."""
    with user_errors():
        scene = build_scene(preset, diameter=diameter, thickness=thickness, mass=mass,
                            inertia=inertia, k=k, c=c, mu=mu, slip_velocity=slip_velocity,
                            g=g)
    from ..api.throws import method_table

    found = method_table(scene)
    omega, zeta, rows = found.omega, found.zeta, found.methods
    if json_out:
        print_json(found.to_dict())
        return
    stick = (f"; friction's stick at rest decays at {found.stick_rate:.4g} /s"
             if found.stick_rate > 0 else "")
    say(console, f"[bold]Integration methods[/] (stiffest mode: rocking on two corners, "
                 f"omega = {omega:.4g} rad/s, damping ratio {zeta:.3f}{stick})")
    table = Table(box=box.SIMPLE_HEAD, pad_edge=False)
    for col, justify in (("method", "left"), ("order", "right"), ("adaptive", "left"),
                         ("symplectic", "left"), ("stable step", "right")):
        table.add_column(col, justify=justify, no_wrap=True)
    for r in rows:
        name = f"{r['name']} (default)" if r["default"] else r["name"]
        limit = "-" if r["stable_step"] is None else f"{r['stable_step']:.3g} s"
        table.add_row(name, str(r["order"]), "yes" if r["adaptive"] else "no",
                      "yes" if r["symplectic"] else "no", limit)
    console.print(table)
    for r in rows:
        say(console, f"[bold]{r['name']}[/]: {r['summary']}")
    say(console, "stable step: the largest fixed step whose error on the stiffest mode "
                 + ("and on the stick " if found.stick_rate > 0 else "")
                 + "does not grow (simulate and basin refuse a larger --dt without --force).")
