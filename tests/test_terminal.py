"""What a user sees in a terminal: at 80 and at 200 columns no table cell is cut short ("…"),
no line is wider than the terminal, and no number is split from its name or its unit."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

from coincli.cli.text import keep_whole

WIDTHS = (80, 200)
UNITS_ONLY = {"m", "mm", "um", "m/s", "rad", "rad/s", "deg", "ms", "mJ", "N/m", "kg", "MB"}
COMMANDS = {
    "presets": (["presets"], ["paper-method", "paper (default)", "undamped",
                              "rtol = 1e-06", "dt = 1e-06 s", "k = 120 N/m"]),
    "methods": (["methods"], ["symplectic_euler", "event (default)", "0.000329 s",
                              "omega = 5322 rad/s"]),
    "stability": (["stability"], ["154.9 N/m", "308.96 N/m", "84.289 deg", "0.30968 mJ",
                                  "181.4", "187.2"]),
    "stability soft": (["stability", "--k", "250"], ["k = 250 N/m", "k_cr = 308.96 N/m",
                                                     "0.000587 mJ", "k = 154.5 N/m"]),
    "simulate": (["simulate", "--vy", "1.197", "--vphi", "3.508", "--no-rrd"],
                 ["vy0 = 1.197 m/s", "vphi0 = 3.508 rad/s", "y0 = 0.0100499 m",
                  "n = 6 quarter turns", "rtol = 1e-06: n = 6"]),
    "accuracy": (["accuracy", "--quick", "--res", "2", "--methods", "symplectic_euler,event",
                  "-o", "a.png"], ["symplectic_euler", "h=3e-05", "rtol=1e-05", "h=1e-6, 2 s"]),
    "fractions": (["fractions", "--samples", "1024", "--batch", "512"],
                  ["1,024 samples", "rtol = 1e-06"]),
}


def run(args, width, cwd=None):
    """The command's stdout as a terminal of ``width`` columns shows it (FORCE_COLOR: rich
    takes the pipe for a terminal; NO_COLOR: without colour codes)."""
    env = {**os.environ, "COLUMNS": str(width), "NO_COLOR": "1", "FORCE_COLOR": "1"}
    env.pop("TERM", None)  # a "dumb" terminal is 80 columns to rich, whatever COLUMNS says
    done = subprocess.run([sys.executable, "-m", "coincli", *args], capture_output=True,
                          text=True, env=env, timeout=300, cwd=cwd)
    assert done.returncode == 0, done.stderr
    return ANSI.sub("", done.stdout)  # bold and italic: NO_COLOR leaves them


ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


def check_output(out: str, width: int, phrases) -> None:
    assert "…" not in out, out
    for line in out.splitlines():
        assert len(line) <= width, (width, line)
        words = line.split()
        if words:
            assert words[-1] not in ("=", "->"), ("a value split from its name", line)
            first = words[1] if words[0] in "│┃" and len(words) > 1 else words[0]
            assert first not in UNITS_ONLY, ("a unit split from its number", line)
    flat = out.replace("\n", " ")
    for phrase in phrases:
        assert any(phrase in line for line in out.splitlines()), (phrase, "not whole", flat)


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("name", COMMANDS)
def test_commands_fit_the_terminal(name, width, tmp_path):
    args, phrases = COMMANDS[name]
    check_output(run(args, width, cwd=tmp_path), width, phrases)


@pytest.mark.parametrize("width", WIDTHS)
def test_basin_run_and_stats_fit_the_terminal(width, tmp_path):
    out = run(["basin", "a store.zarr", "--res", "16", "--quiet"], width, cwd=tmp_path)
    check_output(out, width, ["coin basin stats 'a store.zarr'"])  # quoted, to copy
    out = run(["basin", "stats", "a store.zarr"], width, cwd=tmp_path)
    check_output(out, width, ["256 of 256 = 100 %", "0 not computed"])


@pytest.mark.parametrize("width", WIDTHS)
def test_basin_analyze_fits_the_terminal(width, tmp_path):
    run(["basin", "s.zarr", "--res", "32", "--quiet"], width, cwd=tmp_path)
    out = run(["basin", "analyze", "s.zarr", "--points", "400", "--quiet"], width, cwd=tmp_path)
    check_output(out, width, ["D = 2 - alpha", "S_bb > 0.693", "(Daza et al. 2016)",
                              "whole map"])
    assert "local alpha" in out and "ball test" in out  # both tables, every column


OVER = ["fractions", "--y0", "r:5r", "--phi0", "-pi:pi", "--vx", "-0.5:0.5", "--over",
        "thickness=0.0011:0.02:3", "--max-samples", "1024", "--batch", "512", "--precision",
        "0.001", "--yes"]  # stops at its budget (exit 1): every column of the table and the bar


@pytest.mark.parametrize("width", WIDTHS)
def test_fractions_over_and_its_progress_fit_the_terminal(width, tmp_path):
    """The table of a continuation, and its progress bars on stderr as a terminal shows them
    (FORCE_COLOR: rich draws them as on a terminal; what a refresh overwrites is on the last
    lines too)."""
    env = {**os.environ, "COLUMNS": str(width), "FORCE_COLOR": "1", "NO_COLOR": "1"}
    done = subprocess.run([sys.executable, "-m", "coincli", *OVER], capture_output=True,
                          text=True, env=env, timeout=300, cwd=tmp_path)
    assert done.returncode == 1, done.stderr  # the budget, spent before the precision
    out = ANSI.sub("", done.stdout)
    check_output(out, width, ["95 % interval", "uncertain", "stopped: budget (every value)"])
    shown = [ANSI.sub("", line) for line in re.split(r"[\r\n]", done.stderr)]
    assert not any("…" in line for line in shown), done.stderr
    assert all(len(line) <= width for line in shown), [line for line in shown
                                                       if len(line) > width]
    bars = [line for line in shown if line.startswith("thickness = ")]
    assert bars and all("1,024/1,024" in line and ":00" in line for line in bars[-3:]), bars


def test_keep_whole_breaks_only_between_phrases():
    text = ("final  t = 0.362181 s  x = 0.00978893 m  y = 0.00276037 m  phi = 9.60943 rad "
            "(550.58 deg) after eq. 13 and a [bold red]marked up[/] phrase over 512 x 512 cells")
    for width in range(20, 120, 7):
        lines = keep_whole(text, width).split("\n")
        assert " ".join(" ".join(lines).split()) == " ".join(text.split())  # nothing lost
        for line in lines:
            shown = re.sub(r"\[/?[a-z ]*\]", "", line)
            assert len(shown) <= width or " " not in shown.strip(), (width, line)
        for phrase in ("t = 0.362181 s", "phi = 9.60943 rad", "(550.58 deg)", "eq. 13",
                       "512 x 512 cells", "[bold red]marked"):
            assert any(phrase in line for line in lines), (width, phrase, lines)
