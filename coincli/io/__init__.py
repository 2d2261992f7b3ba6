"""Input/output: Rerun recordings, Zarr stores, charts. Heavy libraries load lazily."""
