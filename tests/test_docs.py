"""The documentation is executed: every `coin ...` command shown in a console block of README.md
and docs/*.md runs, and exits as the page says; every Python block of the pages that show the API
runs. The README stays user documentation, and the citation files agree with the package.

Conventions of the pages (an HTML comment on the line before a fenced block, so that it does not
show):

- ``<!-- long -->``: the block takes minutes; it runs only with COIN_DOCS_LONG=1, which
  `make docs` sets (run after the short blocks of its page, in page order);
- ``<!-- exit N -->``: every command of the block exits with code N (default 0).

In a console block, a line ``$ coin ...`` (continued by a trailing backslash) is a command; other
``$`` lines (make, pip, python, source) and the output lines are not run. The commands of one
page run in order in one empty folder (with ``out/`` and ``docs/`` in it, for the outputs the
pages write there), so a page may build a store and then read it.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

import coincli

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LONG = os.environ.get("COIN_DOCS_LONG") == "1"
DIARY_WORDS = ("evening", "morning", "tenant", "quiet host", "loaded host", "as released")
MARKER = re.compile(r"<!--\s*(long|exit\s+(\d+))\s*-->")
FENCE = re.compile(r"^```(\w*)\s*$")


@dataclass
class Block:
    page: Path
    line: int  # of the opening fence, 1-based
    language: str
    text: str
    long: bool
    exit_code: int

    def commands(self) -> list[list[str]]:
        """The `coin` command lines of a console block, as argument lists without `coin`."""
        out, pending = [], ""
        for raw in self.text.splitlines():
            if pending:
                pending += " " + raw.strip()
            elif raw.startswith("$ "):
                pending = raw[2:].strip()
            else:
                continue
            if pending.endswith("\\"):
                pending = pending[:-1].rstrip()
                continue
            words = shlex.split(pending, comments=True)
            pending = ""
            # `coin a && coin b` is two commands
            while words:
                cut = words.index("&&") if "&&" in words else len(words)
                if words[0] == "coin":
                    out.append(words[1:cut])
                words = words[cut + 1:]
        return out


def blocks(page: Path) -> list[Block]:
    """The fenced blocks of a page, each with the markers on the line before it."""
    lines = page.read_text().splitlines()
    found, i = [], 0
    while i < len(lines):
        fence = FENCE.match(lines[i])
        if not fence:
            i += 1
            continue
        start = i
        i += 1
        while i < len(lines) and not lines[i].startswith("```"):
            i += 1
        marker = MARKER.search(lines[start - 1]) if start else None
        found.append(Block(page, start + 1, fence.group(1), "\n".join(lines[start + 1:i]),
                           long=bool(marker and marker.group(1) == "long"),
                           exit_code=int(marker.group(2)) if marker and marker.group(2) else 0))
        i += 1
    return found


def page_id(page: Path) -> str:
    return str(page.relative_to(ROOT))


def run_coin(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["COLUMNS"] = "100"
    return subprocess.run([sys.executable, "-m", "coincli", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=3600 if LONG else 120)


def selected(page: Path, language: str) -> list[Block]:
    return [b for b in blocks(page) if b.language == language and (LONG or not b.long)]


@pytest.mark.parametrize("page", [p for p in PAGES if selected(p, "console")], ids=page_id)
def test_every_command_shown_runs_and_exits_as_documented(page, tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "docs").mkdir()
    ran = 0
    for block in selected(page, "console"):
        for args in block.commands():
            result = run_coin(args, tmp_path)
            where = f"{page_id(page)}:{block.line}: coin {shlex.join(args)}"
            assert result.returncode == block.exit_code, (
                f"{where} exited {result.returncode}, the page says {block.exit_code}\n"
                f"{result.stdout[-2000:]}{result.stderr[-2000:]}")
            assert "Traceback" not in result.stderr, where
            ran += 1
    if not ran:
        pytest.skip("no coin command on this page outside long blocks")


PYTHON_PAGES = [ROOT / "README.md", ROOT / "docs" / "api.md"]


@pytest.mark.parametrize("page", PYTHON_PAGES, ids=page_id)
def test_the_python_shown_runs(page, tmp_path, monkeypatch):
    """A page's Python blocks, in order, in one namespace, in an empty folder."""
    monkeypatch.chdir(tmp_path)
    code = selected(page, "python")
    assert code, f"{page_id(page)} shows no Python"
    namespace: dict = {"__name__": "__docs__"}
    for block in code:
        exec(compile(block.text, f"{page_id(page)}:{block.line}", "exec"), namespace)


def test_every_page_has_its_commands_checked():
    """Pages with `coin` commands either run them here or mark them long; no other fence
    languages hide commands (a `$ coin` line in a ```bash or ```text block would go unrun)."""
    for page in PAGES:
        for block in blocks(page):
            if block.language != "console":
                assert not re.search(r"^\$ coin\b", block.text, re.M), (
                    f"{page_id(page)}:{block.line}: a coin command outside a console block")


def test_markers_stand_before_a_block():
    """A misplaced marker would silently run a long block, or expect the wrong exit code."""
    for page in PAGES:
        lines = page.read_text().splitlines()
        for i, line in enumerate(lines):
            if MARKER.search(line):
                assert i + 1 < len(lines) and FENCE.match(lines[i + 1]), (
                    f"{page_id(page)}:{i + 1}: a marker not followed by a fenced block")


def test_the_readme_is_user_documentation():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 300
    lowered = text.lower()
    for word in DIARY_WORDS:
        assert word not in lowered, f"README.md says {word!r}"
    # CI runs the README's test command
    assert "$ make test" in text


def test_license_changelog_and_citation_exist_and_agree_with_the_package():
    assert "MIT License" in (ROOT / "LICENSE").read_text()
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert f"## {coincli.__version__}" in changelog
    citation = (ROOT / "CITATION.cff").read_text()
    version = re.search(r'^version:\s*"?([^"\n]+)"?\s*$', citation, re.M)
    assert version and version.group(1) == coincli.__version__
    assert re.search(r"^cff-version: 1\.2\.0$", citation, re.M)
    assert "Basin boundaries of plane model of impacting coin" in citation


def test_the_site_links_every_page():
    """mkdocs.yml's nav names every page under docs/ (a page left out would not be reachable)."""
    nav = (ROOT / "mkdocs.yml").read_text()
    for page in (ROOT / "docs").glob("*.md"):
        assert re.search(rf":\s*{re.escape(page.name)}\s*$", nav, re.M), f"{page.name} not in nav"


MINUTES = {1: "a minute", 2: "two minutes", 3: "three minutes", 4: "four minutes"}
DURATION = re.compile(r"about (?:a|an|one|two|three|four|five|\d+(?:\.\d+)?) ?"
                      r"(?:minutes?|min|s|seconds?)\b")


def test_one_figure_for_the_first_compile_everywhere():
    """How long the first compile takes is said one way wherever it is said (the README, the
    pages, the notebook, the Makefile): the generated table's figure (docs/performance.md, from
    benchmarks/first-compile.json) rounded up to whole minutes, which is FIRST_COMPILE_SECONDS,
    the figure of the command's notices and of its live clock."""
    import json
    import math

    from coincli.jit import FIRST_COMPILE_SECONDS

    record = json.loads((ROOT / "benchmarks" / "first-compile.json").read_text())
    wall = record["compile"]["wall_s"]
    assert f"({wall:.1f} s wall)" in (ROOT / "docs" / "performance.md").read_text()
    minutes = max(1, math.ceil(wall / 60))
    assert FIRST_COMPILE_SECONDS == 60 * minutes, (
        f"the table says {wall:.0f} s: coincli.jit.FIRST_COMPILE_SECONDS = {60 * minutes}")
    said = f"about {MINUTES.get(minutes, f'{minutes} minutes')}"
    notebook = json.loads((ROOT / "docs" / "notebook.ipynb").read_text())
    texts = {page_id(p): p.read_text() for p in PAGES}
    texts["Makefile"] = (ROOT / "Makefile").read_text()
    texts["docs/notebook.ipynb"] = "\n\n".join("".join(c["source"]) for c in notebook["cells"]
                                               if c["cell_type"] == "markdown")
    found = []
    for name, text in texts.items():
        text = re.sub(r"<!-- first-compile:start -->.*?<!-- first-compile:end -->", "", text,
                      flags=re.S)
        for sentence in re.split(r"(?<=[.;!?])\s+|\n\s*\n", text):
            if re.search(r"compil", sentence, re.I):
                found += [(name, d) for d in DURATION.findall(" ".join(sentence.split()))]
    assert found and all(d == said for _, d in found), [f for f in found if f[1] != said]


def _docs_pictures():
    """benchmarks/docs_pictures.py: every picture of the documentation and its command."""
    import importlib.util

    if "docs_pictures" not in sys.modules:
        spec = importlib.util.spec_from_file_location("docs_pictures",
                                                      ROOT / "benchmarks" / "docs_pictures.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules["docs_pictures"] = module  # its dataclass looks its module up there
        spec.loader.exec_module(module)
    return sys.modules["docs_pictures"]


def test_every_picture_shown_is_listed_with_the_command_that_makes_it():
    """benchmarks/docs_pictures.py lists every picture under docs/, and every picture a page
    shows, each with its command; `make docs` makes them through it (one list, not two)."""
    pictures = _docs_pictures()
    listed = set(pictures.BY_NAME)
    assert {p.name for p in (ROOT / "docs").glob("*.png")} == listed
    shown = set()
    for page in PAGES:
        for target in re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", page.read_text()):
            path = (page.parent / target).resolve()
            if path.parent == ROOT / "docs":
                shown.add(path.name)
    assert shown == listed, f"shown but not listed: {shown - listed}; listed, not shown: " \
                            f"{listed - shown}"
    makefile = (ROOT / "Makefile").read_text()
    docs = makefile.split("\ndocs: ")[1].split("\n\n")[0]
    assert "benchmarks/docs_pictures.py --make" in docs
    assert not re.search(r"(-o|--plot|--screenshot-to) docs/", makefile), \
        "a picture made by the Makefile itself, not through benchmarks/docs_pictures.py"


def test_a_chart_and_a_stamped_screenshot_name_the_version_that_made_them(tmp_path):
    """save_figure writes the version into a chart's metadata (a PNG's "Software" text chunk,
    an SVG's or a PDF's Creator); stamp_png into a PNG another program made, its image
    untouched."""
    import zlib

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from coincli.files import picture_made_by, png_text, save_figure, stamp_png

    fig, ax = plt.subplots(figsize=(2, 2))
    ax.plot([0, 1], [1, 0])
    for suffix in ("png", "svg", "pdf"):
        save_figure(fig, tmp_path / f"chart.{suffix}", 50)
        assert f"coin {coincli.__version__}".encode() in (tmp_path / f"chart.{suffix}").read_bytes()
    plt.close(fig)
    assert picture_made_by(tmp_path / "chart.png") == coincli.__version__
    other = tmp_path / "other.png"  # as a viewer writes one: no text chunk
    other.write_bytes(_png(np.arange(12, dtype=np.uint8).reshape(2, 2, 3), zlib))
    assert picture_made_by(other) is None and png_text(other) == {}
    pixels = plt.imread(other)
    stamp_png(other)
    stamp_png(other)  # once more: still one Software chunk
    assert png_text(other) == {"Software": f"coin {coincli.__version__}"}
    assert picture_made_by(other) == coincli.__version__
    assert (plt.imread(other) == pixels).all()


def _png(rgb, zlib) -> bytes:
    """A plain RGB PNG file, without any text chunk."""
    def chunk(kind: bytes, body: bytes) -> bytes:
        return (len(body).to_bytes(4, "big") + kind + body
                + zlib.crc32(kind + body).to_bytes(4, "big"))

    height, width, _ = rgb.shape
    rows = b"".join(b"\0" + rgb[i].tobytes() for i in range(height))
    header = width.to_bytes(4, "big") + height.to_bytes(4, "big") + bytes([8, 2, 0, 0, 0])
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows))
            + chunk(b"IEND", b""))


def _minor(version: str) -> tuple[int, int]:
    major, minor = re.match(r"(\d+)\.(\d+)", version).groups()
    return int(major), int(minor)


def test_every_picture_was_made_by_this_minor_version():
    """Each picture says in its metadata which version made it (coincli.files.save_figure,
    stamp_png): one made by an older minor version than the package's, or naming none, is
    stale; the failure names it and the command that remakes it."""
    pictures = _docs_pictures()
    stale = []
    for picture in pictures.PICTURES:
        version = pictures.made_by(picture)
        if version is None or _minor(version) < _minor(coincli.__version__):
            made = f"made by coin {version}" if version else "no version in its metadata"
            stale.append(f"docs/{picture.name} ({made}): {picture.command()}")
    assert not stale, (f"pictures older than coin {coincli.__version__} (all of them: "
                       ".venv/bin/python benchmarks/docs_pictures.py --make):\n"
                       + "\n".join(stale))


def test_the_figures_shown_are_those_of_the_stored_benchmark():
    """The tables of current figures are generated (benchmarks/docs_tables.py) from
    benchmarks/bench.json and peers.json, never edited by hand: rendering them again changes
    nothing."""
    import importlib.util
    import json

    spec = importlib.util.spec_from_file_location("docs_tables",
                                                  ROOT / "benchmarks" / "docs_tables.py")
    tables = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tables)
    bench = json.loads(tables.BENCH.read_text())
    assert bench["measured"]["version"] and bench["measured"]["date"]
    performance = (ROOT / "docs" / "performance.md").read_text()
    assert tables.bench_table(bench) in performance
    assert tables.peers_table(json.loads(tables.PEERS.read_text())) in performance
    # the README links the page instead of copying figures that would outlive their version
    readme = (ROOT / "README.md").read_text()
    figures = readme.split("\n## Current figures\n")[1].split("\n## ")[0]
    assert "](docs/performance.md)" in figures and "|" not in figures, figures
    assert tables.provenance(bench["measured"]) not in readme
