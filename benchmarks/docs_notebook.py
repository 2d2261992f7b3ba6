#!/usr/bin/env python
"""The documentation's notebook (docs/notebook.ipynb) run and saved with its outputs, which the
site's page shows (mkdocs-jupyter renders the saved outputs; the build runs nothing).

    python benchmarks/docs_notebook.py     # about 10 s once the kernels are compiled

It runs in a Jupyter kernel in a temporary folder (the notebook's store and NetCDF file go there)
and keeps every output but a Rerun viewer's: a viewer draws what a running kernel sends it, so a
static page would load the viewer (tens of MB) to show it empty. `make docs` runs it;
tests/test_notebook.py runs the notebook the same way and checks that the saved outputs are of
this version and of the same kinds as a fresh run's.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

NOTEBOOK = Path(__file__).resolve().parents[1] / "docs" / "notebook.ipynb"
WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"


def execute(notebook: Path, folder: Path):
    """The notebook run from top to bottom in a Jupyter kernel whose working folder is `folder`
    (a cell that raises stops the run with nbclient's CellExecutionError)."""
    import nbclient
    import nbformat

    nb = nbformat.read(notebook, as_version=4)
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3", record_timing=False,
                            resources={"metadata": {"path": str(folder)}}).execute()
    return nb


def without_viewers(nb):
    """The notebook without its widgets' outputs and state (Rerun's viewers)."""
    for cell in nb.cells:
        if cell.cell_type == "code":
            cell.outputs = [out for out in cell.outputs if WIDGET_VIEW not in out.get("data", {})]
    nb.metadata.pop("widgets", None)
    return nb


def main() -> int:
    import nbformat

    with tempfile.TemporaryDirectory() as folder:
        nb = without_viewers(execute(NOTEBOOK, Path(folder)))
    nbformat.write(nb, NOTEBOOK)
    print(f"wrote {NOTEBOOK.relative_to(NOTEBOOK.parents[1])} with its outputs "
          f"({NOTEBOOK.stat().st_size // 1024} kB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
