"""`coin simulate`: one trajectory, summarised."""

from __future__ import annotations

import math

from rich.table import Table

from .. import __version__
from ..simulate import Trajectory, simulate
from . import app
from .common import (
    COpt, DiameterOpt, DtOpt, ForceOpt, GOpt, InertiaOpt, JsonOpt, KOpt, MassOpt, MethodOpt,
    Phi0Opt, PresetOpt, RtolOpt, StopOpt, TEndOpt, ThicknessOpt, VphiOpt, VxOpt, VyOpt, X0Opt,
    Y0Opt, build_scene, console, print_json, user_errors,
)


@app.command("simulate")
def simulate_command(
    preset: PresetOpt = "paper",
    x0: X0Opt = None, y0: Y0Opt = None, phi0: Phi0Opt = None,
    vx: VxOpt = None, vy: VyOpt = None, vphi: VphiOpt = None,
    diameter: DiameterOpt = None, thickness: ThicknessOpt = None, mass: MassOpt = None,
    inertia: InertiaOpt = None, k: KOpt = None, c: COpt = None, g: GOpt = None,
    method: MethodOpt = None, dt: DtOpt = None, rtol: RtolOpt = None, t_end: TEndOpt = None,
    stop_on_settle: StopOpt = None, force: ForceOpt = False, json_out: JsonOpt = False,
) -> None:
    """Run one throw and print its outcome: n quarter turns, lying or standing, when it settled.

    Example (the standing throw of the paper's fig. 2): coin simulate --vy 1.197 --vphi 3.508
    """
    with user_errors():
        scene = build_scene(preset, x0=x0, y0=y0, phi0=phi0, vx=vx, vy=vy, vphi=vphi,
                            diameter=diameter, thickness=thickness, mass=mass, inertia=inertia,
                            k=k, c=c, g=g, method=method, dt=dt, rtol=rtol, t_end=t_end,
                            stop_on_settle=stop_on_settle)
        trajectory = simulate(scene, force=force)
    if json_out:
        print_json({**trajectory.summary(), "version": __version__,
                    "parameters": scene.to_dict()})
    else:
        print_summary(trajectory)
    if trajectory.status == "non-finite":
        raise SystemExit(1)


def print_summary(tr: Trajectory) -> None:
    s = tr.summary()
    integ = tr.scene.integration
    init = tr.scene.initial
    console.print(f"[bold]coin simulate[/]  vy0 = {init.vy:g} m/s, vphi0 = {init.vphi:g} rad/s, "
                  f"phi0 = {init.phi0:g}, vx0 = {init.vx:g}, y0 = {tr.scene.y0:.6g} m")
    table = Table(show_header=False, box=None, pad_edge=False)
    table.add_column(style="bold")
    table.add_column()
    if tr.quarter_turns is None:
        outcome = "[red]no outcome: the run went non-finite[/]"
    else:
        colour = "magenta" if tr.pose == "standing" else "cyan"
        outcome = f"n = {tr.quarter_turns} quarter turns: [{colour}]{tr.pose}[/]"
    table.add_row("outcome", outcome)
    if tr.settled:
        table.add_row("settled", f"yes, at t = {tr.settle_time:.6g} s (energy below E_crit = "
                                 f"{tr.e_crit * 1e3:.4g} mJ: n is final)")
    else:
        table.add_row("settled", f"[yellow]no[/] ({tr.status} at t = {tr.t_final:g} s)")
    if tr.rounded_quarter_turns is not None and tr.rounded_quarter_turns != tr.quarter_turns:
        table.add_row("round(2 phi/pi)", f"{tr.rounded_quarter_turns} at t = {tr.t_final:g} s")
    fs = s["final_state"]
    table.add_row("final state", f"t = {tr.t_final:.6g} s  x = {fs['x']:.6g} m  "
                                 f"y = {fs['y']:.6g} m  phi = {fs['phi']:.6g} rad "
                                 f"({math.degrees(fs['phi']):.2f} deg)")
    table.add_row("", f"vx = {fs['vx']:.4g} m/s  vy = {fs['vy']:.4g} m/s  "
                      f"vphi = {fs['vphi']:.4g} rad/s")
    table.add_row("energy", f"{tr.energy_initial * 1e3:.5g} mJ -> {tr.energy_final * 1e3:.5g} "
                            f"mJ ({s['energy_dissipated'] * 1e3:.5g} mJ dissipated)")
    setting = (f"dt = {integ.dt:g} s" if tr.scene.integration.method not in ("dopri5", "event")
               else f"rtol = {integ.rtol:g}")
    run_to = "stop when settled" if integ.stop_on_settle else f"full {integ.t_end:g} s"
    table.add_row("method", f"{integ.method}, {setting}, {run_to}")
    table.add_row("cost", f"{tr.steps:,} steps, {tr.wall_time * 1e3:.3g} ms wall")
    console.print(table)
    for note in tr.notes:
        console.print(f"[yellow]note:[/] {note}")
