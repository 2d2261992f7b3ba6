#!/usr/bin/env python
"""The documentation's notebook (docs/notebook.ipynb) run and saved with its outputs, which the
site's page shows (mkdocs-jupyter renders the saved outputs; the build runs nothing).

    python benchmarks/docs_notebook.py     # about 10 s once the kernels are compiled

It runs in a Jupyter kernel in a temporary folder (the notebook's store and NetCDF file go there)
and keeps every output but a Rerun viewer's: a viewer draws what a running kernel sends it, so a
static page would load the viewer (tens of MB) to show it empty. `make docs` runs it;
tests/test_notebook.py runs the notebook the same way and checks that the saved outputs are of
this version and of the same kinds as a fresh run's.

Every cell that draws a picture carries its alternative text in its metadata (``"alt"``, the
key nbconvert reads); it is copied into the picture's output metadata when the notebook is
saved. nbconvert's lab template, which mkdocs-jupyter renders the page with, writes no alt
attribute, so this file is also a hook of the site's build (mkdocs.yml, ``hooks:``): its
:func:`on_page_content` gives each picture of the notebook's page its text.
"""

from __future__ import annotations

import html
import json
import re
import sys
import tempfile
from pathlib import Path

NOTEBOOK = Path(__file__).resolve().parents[1] / "docs" / "notebook.ipynb"
WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
PICTURES = ("image/png", "image/jpeg")


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


def alt_texts(nb: dict) -> dict[str, str]:
    """The alternative text of every picture of a notebook (a dict as read from its JSON, or
    nbformat's), by the picture's base64 data: its output's ``alt`` or else its cell's;
    ValueError naming the first cell that draws one without."""
    out = {}
    for number, cell in enumerate(nb["cells"], start=1):
        for output in cell.get("outputs", []):
            for kind in PICTURES:
                if kind not in output.get("data", {}):
                    continue
                alt = (output.get("metadata", {}).get(kind, {}).get("alt")
                       or cell.get("metadata", {}).get("alt"))
                if not alt:
                    raise ValueError(f"cell {number} of the notebook draws a picture without "
                                     "alternative text: give the cell the metadata "
                                     '{"alt": "what the picture shows"}')
                data = output["data"][kind]
                out["".join(data).replace("\n", "")] = alt
    return out


def with_alt_texts(nb):
    """The notebook with each cell's ``alt`` in the output metadata of its pictures (where
    nbconvert, and other readers, look for it first)."""
    for cell in nb.cells:
        alt = cell.metadata.get("alt")
        for output in cell.get("outputs", []) if alt else ():
            for kind in PICTURES:
                if kind in output.get("data", {}):
                    output.setdefault("metadata", {}).setdefault(kind, {})["alt"] = alt
    alt_texts(nb)  # every picture has one
    return nb


def add_alt_attributes(page: str, texts: dict[str, str]) -> str:
    """The HTML of a notebook's page with each picture's ``alt`` attribute (the picture found
    by its data; nbconvert's placeholder, "No description has been provided for this image",
    replaced)."""
    def with_alt(match: re.Match) -> str:
        tag = match.group(0)
        src = re.search(r'\ssrc="data:image/(?:png|jpeg);base64,([^"]+)"', tag)
        alt = texts.get(src.group(1)) if src else None
        if alt is None:
            return tag
        tag = re.sub(r'\salt="[^"]*"', "", tag)
        return tag.replace("<img", f'<img alt="{html.escape(alt)}"', 1)

    return re.sub(r"<img\b[^>]*>", with_alt, page)


def on_page_content(page_html: str, page, **kwargs) -> str:
    """mkdocs hook: the notebook's page with the alternative text of its pictures."""
    source = getattr(page.file, "abs_src_path", None) or ""
    if not source.endswith(".ipynb"):
        return page_html
    return add_alt_attributes(page_html, alt_texts(json.loads(Path(source).read_text())))


def main() -> int:
    import nbformat

    with tempfile.TemporaryDirectory() as folder:
        nb = with_alt_texts(without_viewers(execute(NOTEBOOK, Path(folder))))
    nbformat.write(nb, NOTEBOOK)
    print(f"wrote {NOTEBOOK.relative_to(NOTEBOOK.parents[1])} with its outputs "
          f"({NOTEBOOK.stat().st_size // 1024} kB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
