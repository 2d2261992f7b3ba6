# %% [markdown]
# # coin from Python: one throw, a small basin, its statistics and its picture
#
# A worked example of the public API (`import coincli`). It runs as a script
# (`python docs/example.py`, as the test suite does) or cell by cell in Jupyter or VS Code
# (the `# %%` markers). Everything below is also what `coin simulate`, `coin basin`,
# `coin basin stats` and `coin basin render` call.

# %%
import coincli

base = coincli.load_preset("paper")
run = coincli.simulate(base, vy=1.197, vphi=3.508)  # a Trajectory: outcome, status, energies
scene = run.scene  # the scene with those initial values
print(f"fig.-2 throw: n = {run.quarter_turns} ({run.pose}), {run.status.label} at "
      f"t = {run.settle_time:.4f} s, {run.steps} steps")

# %% [markdown]
# `classify` gives only the outcome of one initial condition: the count of quarter turns, the
# status (`Status.SETTLED` means the energy fell below E_crit, so the count is final) and when.

# %%
outcome = coincli.classify(scene.with_overrides(vy=1.1975))
print(outcome, outcome.pose)

# %% [markdown]
# A basin: two initial conditions swept over a grid (here 48 x 48 cells over the paper's
# default ranges), returned as an xarray Dataset. With `store="out.zarr"` it would be computed
# into a resumable Zarr store instead (the same store `coin basin` writes).

# %%
ds = coincli.basin(coincli.load_preset("paper"), vy=(0.05, 2.0), vphi=(-20.0, 20.0), res=48)
print(ds)

# %% [markdown]
# Statistics: the probability of each outcome and of standing, with a 95 % Wilson interval.

# %%
stats = coincli.basin_stats(ds)
standing = stats["standing"]
low, high = standing["ci95"]
print(f"standing: {standing['count']} of {standing['of']} cells = "
      f"{100 * standing['probability']:.2f} % (95 % CI {100 * low:.2f} to {100 * high:.2f} %)")

# %% [markdown]
# The Dataset is ordinary xarray: select, plot, compute as usual.

# %%
lying_flat = (ds["quarter_turns"] == 0).mean().item()
print(f"{100 * lying_flat:.1f} % of the throws end where they started (n = 0)")
print(ds["quarter_turns"].sel(vy=1.2, vphi=3.5, method="nearest").item())

# %% [markdown]
# The picture, in the paper's colours.

# %%
fig = coincli.render_basin(ds, "example-basin.png")  # the Figure, also written to the file
print("wrote example-basin.png")
