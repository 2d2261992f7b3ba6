"""`coin presets`: list the shipped presets with their values."""

from __future__ import annotations

from rich.table import Table

from .. import presets as presets_mod
from ..defaults import DEFAULT_PRESET
from . import app
from .common import JsonOpt, console, print_json, user_errors


@app.command("presets")
def presets_command(json_out: JsonOpt = False) -> None:
    """List the presets in presets/ with their parameter values."""
    from ..integrators.registry import setting_text

    with user_errors():
        found = presets_mod.available()
    if json_out:
        print_json({p.name: {"path": str(p.path), "description": p.description,
                             **p.scene.to_dict()} for p in found})
        return
    table = Table(title=f"Presets ({presets_mod.presets_dir()})", title_justify="left")
    for col in ("name", "d (mm)", "t (mm)", "m (g)", "I (kg m^2)", "k (N/m)", "c (N s/m)",
                "integration"):
        table.add_column(col, overflow="fold")
    for p in found:
        s = p.scene
        integ = s.integration
        method = f"{integ.method.label} {setting_text(integ.method, integ.dt, integ.rtol)}"
        if not integ.stop_on_settle:
            method += f" full {integ.t_end:g} s"
        name = f"{p.name} (default)" if p.name == DEFAULT_PRESET else p.name
        table.add_row(name, f"{s.coin.diameter * 1e3:g}", f"{s.coin.thickness * 1e3:g}",
                      f"{s.coin.mass * 1e3:.5g}", f"{s.coin.inertia:.4g}",
                      f"{s.foundation.k:g}", f"{s.foundation.c:g}", method)
    console.print(table)
    for p in found:
        console.print(f"[bold]{p.name}[/]: {p.description}", highlight=False)
