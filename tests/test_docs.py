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
