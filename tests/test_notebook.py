"""The documentation's notebook (docs/notebook.ipynb) runs from top to bottom in a Jupyter
kernel, as a notebook user runs it: a throw shown inline in Rerun's viewer, its Dataset plotted,
two basins side by side in one figure, a NetCDF round trip (whose asserts are in the notebook)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[1] / "docs" / "notebook.ipynb"


def output_kinds(cell) -> set[str]:
    return {kind for out in cell.outputs for kind in out.get("data", {})}


def cell_with(nb, text: str):
    matches = [c for c in nb.cells if c.cell_type == "code" and text in c.source]
    assert len(matches) == 1, text
    return matches[0]


@pytest.mark.slow
def test_the_notebook_runs_and_shows_what_it_says(tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("rerun_notebook")
    shutil.copy(NOTEBOOK, tmp_path / NOTEBOOK.name)
    nb = nbformat.read(tmp_path / NOTEBOOK.name, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), \
        "the notebook is checked in without outputs"
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    errors = [out for c in nb.cells if c.cell_type == "code" for out in c.outputs
              if out.output_type == "error"]
    assert not errors
    run_repr = cell_with(nb, "coincli.simulate(").outputs[0]["data"]["text/plain"]
    assert run_repr.startswith("Trajectory(n = 6 (lying), settled")
    assert "application/vnd.jupyter.widget-view+json" in output_kinds(
        cell_with(nb, "run.show("))  # Rerun's viewer, inline
    assert "text/html" in output_kinds(cell_with(nb, "run.to_dataset()"))
    assert "image/png" in output_kinds(cell_with(nb, 'throw["phi"].plot'))
    assert "text/html" in output_kinds(cell_with(nb, "run.events_table()"))
    assert "image/png" in output_kinds(cell_with(nb, "render_basin(paper, ax=left"))
    assert "application/vnd.jupyter.widget-view+json" in output_kinds(
        cell_with(nb, "coincli.viewer("))  # the viewer a later cell's sweep is shown in
    assert (tmp_path / "live.zarr" / "zarr.json").is_file()
    assert (tmp_path / "paper-basin.nc").stat().st_size > 0
