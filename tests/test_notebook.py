"""The documentation's notebook (docs/notebook.ipynb) runs from top to bottom in a Jupyter
kernel, as a notebook user runs it: a throw shown inline in Rerun's viewer, its Dataset plotted,
two basins side by side in one figure, a NetCDF round trip (whose asserts are in the notebook).
It is saved with the outputs the site shows (benchmarks/docs_notebook.py): those of this version,
of the kinds a fresh run gives, without the viewers."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

import coincli

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOK = ROOT / "docs" / "notebook.ipynb"
_spec = importlib.util.spec_from_file_location("docs_notebook",
                                               ROOT / "benchmarks" / "docs_notebook.py")
docs_notebook = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(docs_notebook)


def output_kinds(cell) -> set[str]:
    return {kind for out in cell.outputs for kind in out.get("data", {})}


def cell_with(nb, text: str):
    matches = [c for c in nb.cells if c.cell_type == "code" and text in c.source]
    assert len(matches) == 1, text
    return matches[0]


def test_every_picture_of_the_notebook_has_its_alternative_text_on_the_site():
    """Each cell that draws a picture says what it shows (its metadata "alt"), and the site's
    page gives every picture that text: nbconvert's lab template, which mkdocs-jupyter renders
    with, writes a placeholder, which the build's hook (benchmarks/docs_notebook.py, named in
    mkdocs.yml) replaces."""
    import json

    nb2html = pytest.importorskip("mkdocs_jupyter.nbconvert2").nb2html
    texts = docs_notebook.alt_texts(json.loads(NOTEBOOK.read_text()))
    assert len(texts) == 3 and all(len(text) > 40 for text in texts.values())
    page = docs_notebook.add_alt_attributes(nb2html(str(NOTEBOOK)), texts)
    alts = re.findall(r'<img\b[^>]*\salt="([^"]*)"', page)
    assert len(alts) == len(re.findall(r"<img\b", page)) == len(texts)
    assert "No description has been provided" not in page
    hooks = (ROOT / "mkdocs.yml").read_text().split("\nhooks:\n")[1].split("\n\n")[0]
    assert "benchmarks/docs_notebook.py" in hooks


@pytest.mark.slow
def test_the_notebook_runs_and_shows_what_it_says(tmp_path):
    nbformat = pytest.importorskip("nbformat")
    pytest.importorskip("nbclient")
    pytest.importorskip("rerun_notebook")
    nb = docs_notebook.execute(NOTEBOOK, tmp_path)
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

    # the saved notebook: this run's outputs, small, without a viewer's (which a static page
    # cannot show), made by this version (the Dataset's attributes name it)
    saved = nbformat.read(NOTEBOOK, as_version=4)
    fresh = docs_notebook.without_viewers(nb)
    regenerate = "run python benchmarks/docs_notebook.py"
    assert [output_kinds(c) for c in saved.cells if c.cell_type == "code"] == \
        [output_kinds(c) for c in fresh.cells if c.cell_type == "code"], regenerate
    assert "widgets" not in saved.metadata
    assert NOTEBOOK.stat().st_size < 500_000
    throw_repr = cell_with(saved, "run.to_dataset()").outputs[0]["data"]["text/plain"]
    assert re.search(rf"coincli_version:\s+{re.escape(coincli.__version__)}\n", throw_repr), \
        regenerate
