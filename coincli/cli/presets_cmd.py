"""`coin presets`: list the shipped presets with their values."""

from rich import box
from rich.table import Table

from ..api.options import DEFAULT_PRESET, available_presets, presets_dir
from .app import app
from .common import JsonOpt, console, print_json, user_errors
from .text import say


@app.command("presets")
def presets_command(json_out: JsonOpt = False) -> None:
    """List the presets in presets/ with their parameter values."""
    from ..api.words import describe_method as describe
    from ..api.words import friction_text

    with user_errors():
        found = available_presets()
    if json_out:
        print_json({p.name: {"path": str(p.path), "description": p.description,
                             **p.scene.to_dict()} for p in found})
        return
    say(console, f"[bold]Presets[/] in {presets_dir()} (--preset NAME, or "
                 "--preset PATH.toml for your own)")
    table = Table(box=box.SIMPLE_HEAD, pad_edge=False)
    for col in ("name", "d (mm)", "t (mm)", "m (g)", "I (kg m^2)", "k (N/m)", "c (N s/m)"):
        table.add_column(col, justify="left" if col == "name" else "right", no_wrap=True)
    for p in found:
        s = p.scene
        name = f"{p.name} (default)" if p.name == DEFAULT_PRESET else p.name
        table.add_row(name, f"{s.coin.diameter * 1e3:g}", f"{s.coin.thickness * 1e3:g}",
                      f"{s.coin.mass * 1e3:.5g}", f"{s.coin.inertia:.4g}",
                      f"{s.foundation.k:g}", f"{s.foundation.c:g}")
    console.print(table)
    for p in found:
        integ = p.scene.integration
        run_to = ("stop when decided" if integ.stop_on_settle else "run to the end") + (
            f", t_end = {integ.t_end:g} s" if p.scene.fixed_horizon else ", capped (no t_end)")
        friction = friction_text(p.scene)  # the table has no room for it at 80 columns
        grip = f", friction {friction}" if friction else ""
        say(console, f"[bold]{p.name}[/]: {describe(p.scene)}, {run_to}{grip}. "
                     f"{p.description}")
