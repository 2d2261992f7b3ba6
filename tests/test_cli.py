"""The `coin` command line: machine-readable output, presets, and one-line errors (exit code 2,
no traceback) for every kind of bad input."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from coincli.cli import app

runner = CliRunner()
REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(autouse=True)
def in_tmp(tmp_path, monkeypatch):
    """Run every command in a scratch directory (simulate may write a recording by default)."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


def run(*args, env=None):
    return runner.invoke(app, [str(a) for a in args], env=env)


def assert_one_line_error(result, *fragments):
    assert result.exit_code == 2, (result.exit_code, result.stdout, result.stderr)
    # a typer.Exit/SystemExit, not an exception escaping the command
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        repr(result.exception)
    assert result.stdout == ""
    err = result.stderr.strip()
    assert err, "the error must be reported on stderr"
    assert len(err.splitlines()) == 1, err
    assert "Traceback" not in err
    assert err.startswith("error:"), err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    return err


# -- simulate --json ---------------------------------------------------------------------------

def test_simulate_json_fig2(in_tmp):
    result = run("simulate", "--vy", "1.197", "--vphi", "3.508", "--json", "--no-rrd")
    assert result.exit_code == 0, (result.stdout, result.stderr, result.exception)
    data = json.loads(result.stdout)  # one JSON object and nothing else on stdout
    assert isinstance(data, dict)
    for key in ("quarter_turns", "settled", "settle_time", "final_state", "method", "dt", "steps",
                "wall_time"):
        assert key in data, key
    assert set(data["final_state"]) == {"x", "y", "phi", "vx", "vy", "vphi"}
    assert isinstance(data["quarter_turns"], int)
    assert data["settled"] is True
    assert 0.0 < data["settle_time"] <= 2.0
    assert data["steps"] > 0 and data["wall_time"] >= 0.0
    assert data["parameters"]["initial"]["vy"] == 1.197
    assert data["parameters"]["initial"]["vphi"] == 3.508
    assert list(in_tmp.iterdir()) == [], "--no-rrd must write no file"


def test_simulate_json_with_a_recording_is_still_pure_json(in_tmp):
    result = run("simulate", "--vy", "0.3", "--vphi", "5", "--json", "--rrd", in_tmp / "t.rrd")
    assert result.exit_code == 0, (result.stdout, result.stderr, result.exception)
    assert json.loads(result.stdout)["settled"] is True
    assert (in_tmp / "t.rrd").stat().st_size > 0


def test_simulate_json_options_reach_the_scene():
    result = run("simulate", "--vy", "0.3", "--vphi", "-5", "--method", "rk4", "--dt", "2e-6",
                 "--t-end", "0.05", "--full", "--json", "--no-rrd", "--single-pass")
    assert result.exit_code == 0, (result.stdout, result.stderr, result.exception)
    data = json.loads(result.stdout)
    assert data["method"] == "rk4" and data["dt"] == 2e-6
    assert data["steps"] == 25_000
    assert data["t_final"] == pytest.approx(0.05)


def test_simulate_unsettled_json():
    result = run("simulate", "--vy", "1.5", "--vphi", "10", "--t-end", "0.05", "--json",
                 "--no-rrd")
    assert result.exit_code == 0, (result.stdout, result.stderr, result.exception)
    data = json.loads(result.stdout)
    assert data["settled"] is False and data["status"] == "unsettled"
    assert data["settle_time"] is None


# -- bad input: one line on stderr, exit code 2 ------------------------------------------------

@pytest.mark.parametrize("args,fragment", [
    (["--mass", "0"], "mass"),
    (["--mass", "-1"], "mass"),
    (["--diameter", "0"], "diameter"),
    (["--thickness", "-1"], "thickness"),
    (["--inertia", "0"], "inertia"),
    (["--k", "0"], "k must"),
    (["--k", "-3"], "k must"),
    (["--c", "-0.1"], "c must"),
    (["--vy", "nan"], "vy"),
    (["--vphi", "inf"], "vphi"),
    (["--dt", "0"], "dt"),
    (["--t-end", "-1"], "t_end"),
    (["--preset", "nope"], "nope"),
    (["--method", "nope"], "nope"),
])
def test_bad_values(args, fragment):
    assert_one_line_error(run("simulate", "--vy", "0.3", *args), fragment)


def test_step_beyond_stable_limit_names_it():
    err = assert_one_line_error(run("simulate", "--method", "symplectic_euler", "--dt", "1e-3"),
                                "stable step", "symplectic_euler")
    assert "0.000329" in err or "3.29e-04" in err  # the limit for the paper's parameters
    # --force runs it anyway (and says whether it went non-finite through its exit code)
    forced = run("simulate", "--method", "symplectic_euler", "--dt", "1e-3", "--force",
                 "--t-end", "0.2", "--json", "--no-rrd")
    assert forced.exit_code in (0, 1), (forced.stderr, forced.exception)
    assert json.loads(forced.stdout)["dt"] == 1e-3


@pytest.mark.parametrize("command", ["stability", "methods"])
def test_bad_values_other_commands(command):
    assert_one_line_error(run(command, "--mass", "0"), "mass")
    assert_one_line_error(run(command, "--preset", "nope"), "nope")


PRESET_FILES = {
    "syntax.toml": ('name = "x"\n[coin\nmass = 1\n', ["malformed"]),
    "unknown_key.toml": ('[coin]\nmas = 0.003\n', ["mas", "[coin]"]),
    "unknown_section.toml": ('[colour]\nred = 1\n', ["colour"]),
    "wrong_type.toml": ('[coin]\nmass = "heavy"\n', ["mass", "heavy"]),
    "wrong_type_table.toml": ('coin = 3\n', ["coin"]),
    "wrong_type_bool.toml": ('[coin]\nmass = true\n', ["mass"]),
    "negative.toml": ('[foundation]\nk = -5.0\n', ["k must"]),
    "stop_flag.toml": ('[integration]\nstop_on_settle = "false"\n', ["stop_on_settle"]),
}


@pytest.mark.parametrize("filename", list(PRESET_FILES))
def test_malformed_preset_file(in_tmp, filename):
    text, fragments = PRESET_FILES[filename]
    path = in_tmp / filename
    path.write_text(text)
    assert_one_line_error(run("simulate", "--preset", path, "--no-rrd"), filename, *fragments)


def test_missing_preset_file(in_tmp):
    assert_one_line_error(run("simulate", "--preset", in_tmp / "absent.toml"), "absent.toml")


@pytest.mark.parametrize("name", ["[bold]", "[/x]", "a[red]b"])
def test_error_messages_are_printed_verbatim(name):
    """User text inside an error message (a preset name, a path) is not rich markup: it must be
    printed as given, not swallowed or crash the error report."""
    err = assert_one_line_error(run("simulate", "--preset", name), name)
    assert name in err


def test_preset_file_with_overrides(in_tmp):
    path = in_tmp / "mine.toml"
    path.write_text('name = "mine"\n[foundation]\nk = 250.0\nc = 0.05\n[initial]\nvy = 0.3\n')
    result = run("stability", "--preset", path, "--json")
    assert result.exit_code == 0, (result.stderr, result.exception)
    data = json.loads(result.stdout)
    assert data["k"] == 250.0 and data["standing_static"] is False
    result = run("stability", "--preset", path, "--k", "400", "--json")
    assert json.loads(result.stdout)["k"] == 400.0


# -- presets, methods, module entry point --------------------------------------------------------

def test_presets_lists_the_shipped_presets():
    result = run("presets")
    assert result.exit_code == 0, (result.stderr, result.exception)
    for name in ("paper", "soft", "thick"):
        assert name in result.stdout
    data = json.loads(run("presets", "--json").stdout)
    assert {"paper", "soft", "thick"} <= set(data)
    assert data["paper"]["coin"]["mass"] == pytest.approx(3.14159e-3, rel=1e-5)
    assert data["soft"]["foundation"]["k"] < 308.96
    assert data["thick"]["coin"]["thickness"] > data["paper"]["coin"]["thickness"]


def test_methods_json():
    data = json.loads(run("methods", "--json").stdout)
    names = [m["name"] for m in data["methods"]]
    assert {"symplectic_euler", "verlet", "rk4", "dopri5", "event"} <= set(names)
    se = next(m for m in data["methods"] if m["name"] == "symplectic_euler")
    assert se["stable_step"] == pytest.approx(3.29e-4, rel=0.01)
    assert data["omega_max"] == pytest.approx(5322.4, rel=1e-4)


def test_python_m_coincli_help():
    proc = subprocess.run([sys.executable, "-m", "coincli", "--help"], capture_output=True,
                          text=True, cwd=REPO, timeout=120)
    assert proc.returncode == 0, proc.stderr
    for command in ("simulate", "stability", "presets", "methods"):
        assert command in proc.stdout


def test_installed_script_bad_input_has_no_traceback():
    """The real console script, not the test runner: one line on stderr, exit code 2."""
    coin = Path(sys.executable).parent / "coin"
    if not coin.exists():
        pytest.skip("console script not installed")
    proc = subprocess.run([str(coin), "simulate", "--mass", "-1", "--no-rrd"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "Traceback" not in proc.stderr and "mass" in proc.stderr


@pytest.mark.parametrize("args, fragment", [
    (["simulate", "--vy", "abc", "--no-rrd"], "Invalid value for '--vy'"),  # then typer's words
    (["methods", "--dt", "1"], "No such option: --dt"),
    (["basin", "sweep"], "Missing argument 'STORE'"),
    (["simulate", "extra"], "unexpected extra argument"),
    (["simulate", "--vy"], "requires an argument"),
])
def test_a_mistyped_command_line_is_one_error_line(args, fragment):
    """click's own usage errors too, not only ours: one line naming the help, exit code 2."""
    proc = subprocess.run([sys.executable, "-m", "coincli", *args], capture_output=True,
                          text=True, cwd=REPO, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0]
    assert "--help')" in lines[0]


def test_the_command_exits_after_its_exit_handlers_and_output(tmp_path):
    """main() ends the process with a normal exit: the atexit handlers run, the output is
    flushed (a large stdout arrives whole through a pipe), the exit code is the command's, and
    a non-daemon thread still running is waited for."""
    script = ("import atexit, pathlib, sys, threading, time, coincli.cli\n"
              "atexit.register(lambda: pathlib.Path('handler').write_text('ran'))\n"
              "if sys.argv[1] == 'thread':\n"
              "    threading.Thread(target=lambda: (time.sleep(0.5),\n"
              "                     pathlib.Path('thread').write_text('done'))).start()\n"
              "sys.argv = ['coin'] + sys.argv[2:]\n"
              "coincli.cli.main()\n")
    expected = run("methods", "--json").stdout
    for mode, args, code in (("plain", ["methods", "--json"], 0),
                             ("thread", ["methods", "--json"], 0),
                             ("plain", ["simulate", "--mass", "-1", "--no-rrd"], 2)):
        for name in ("handler", "thread"):
            (tmp_path / name).unlink(missing_ok=True)
        proc = subprocess.run([sys.executable, "-c", script, mode, *args], capture_output=True,
                              text=True, cwd=tmp_path, timeout=120)
        assert proc.returncode == code, proc.stderr
        assert (tmp_path / "handler").read_text() == "ran"
        if code == 0:
            assert proc.stdout == expected
        if mode == "thread":
            assert (tmp_path / "thread").read_text() == "done"


def test_an_unexpected_error_is_not_hidden_and_abort_is_exit_1():
    """A bug must surface as itself, not as an error of the usage-error handling."""
    import typer

    from coincli import cli

    @cli.app.command("boom-test", hidden=True)
    def boom(abort: bool = False) -> None:
        if abort:
            raise typer.Abort()
        raise RuntimeError("boom")

    try:
        with pytest.raises(RuntimeError, match="boom"):
            cli.run(["boom-test"])
        assert cli.run(["boom-test", "--abort"]) == 1
    finally:
        cli.app.registered_commands[:] = [c for c in cli.app.registered_commands
                                          if c.name != "boom-test"]


def test_an_empty_preset_file_is_refused(in_tmp):
    Path("empty.toml").write_text("")
    result = CliRunner().invoke(app, ["simulate", "--preset", "empty.toml", "--no-rrd"])
    assert result.exit_code == 2 and "is empty" in result.output


# -- coin --help, and the first compilation -----------------------------------------------------

def test_help_lists_the_main_commands_first_each_with_an_example():
    from coincli.cli.app import MAIN_COMMANDS

    result = runner.invoke(app, ["--help"], env={"COLUMNS": "100"})
    assert result.exit_code == 0, result.stdout
    listed = re.findall(r"^│ ([a-z]+) {2,}", result.stdout, re.MULTILINE)
    assert listed[:4] == ["simulate", "basin", "fractions", "stability"], listed
    assert {"accuracy", "bench", "compile", "methods", "presets"} <= set(listed[4:]), listed
    for example in MAIN_COMMANDS.values():
        assert f"e.g. {example}" in result.stdout, (example, result.stdout)


def command_paths(command, path=()):
    """The words of every command and group under ``command`` (a click command), itself first."""
    yield path
    for name, subcommand in getattr(command, "commands", {}).items():
        yield from command_paths(subcommand, (*path, name))


def test_no_help_shows_a_type_after_a_flag():
    """typer 0.29 shows '<bool>' after a flag without a metavar: ours have an empty one, and
    coincli.cli gives one to those typer adds itself (--help, the completion options), in the
    help of every command and group."""
    import typer

    paths = list(command_paths(typer.main.get_command(app)))
    assert {(), ("simulate",), ("basin",), ("basin", "stats"), ("basin", "sweep")} <= set(paths)
    for path in paths:
        result = runner.invoke(app, [*path, "--help"], env={"COLUMNS": "120"})
        assert result.exit_code == 0, (path, result.stdout)
        assert "--help" in result.stdout and "<bool>" not in result.stdout, (path, result.stdout)


def plain(out) -> str:
    """What a terminal shows of ``out`` (a StringIO), without its control codes."""
    return re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", out.getvalue())


@pytest.fixture
def uncompiled(monkeypatch):
    """coincli.cli.common.compile_first on a machine that has not compiled the kernels: the
    compilation is a fake that sleeps (or raises what the test gives it), its output a string."""
    import io

    from rich.console import Console

    import coincli.api as api
    import coincli.cli.common as common
    import coincli.jit as jit

    calls = []

    def setup(terminal: bool, compile_kernels=lambda: time.sleep(0.4)):
        out = io.StringIO()
        monkeypatch.setattr(common, "err_console",
                            Console(file=out, force_terminal=terminal, width=80))
        monkeypatch.setattr(jit, "kernels_cached", lambda *model: False)
        monkeypatch.setattr(api, "compile_kernels",
                            lambda **model: (calls.append(1), compile_kernels())[1])
        return out

    setup.calls = calls
    return setup


def test_the_first_compilation_shows_a_live_clock_against_the_expected_time(uncompiled):
    from coincli.cli.common import compile_first
    from coincli.jit import FIRST_COMPILE_SECONDS

    out = uncompiled(terminal=True, compile_kernels=lambda: time.sleep(1.3))
    compile_first()
    text = plain(out)
    expected = f"{FIRST_COMPILE_SECONDS // 60}:{FIRST_COMPILE_SECONDS % 60:02d}"
    for clock in ("0:00", "0:01"):  # the line counts the seconds as they pass
        assert f"compiling the numerical kernels {clock} of about {expected}" in text, text
    assert text.rstrip().endswith("compiled the numerical kernels in 1 s; later runs load them "
                                  "in a second"), text
    assert uncompiled.calls == [1]


@pytest.mark.parametrize("terminal,quiet", [(False, False), (True, True)])
def test_the_first_compilation_off_a_terminal_or_quiet_is_two_lines(uncompiled, terminal,
                                                                     quiet):
    from coincli.cli.common import compile_first
    from coincli.jit import FIRST_COMPILE_SECONDS

    out = uncompiled(terminal=terminal)
    compile_first(quiet=quiet)
    lines = plain(out).strip().splitlines()
    # on a terminal the first line is broken at its 80 columns; in a log it stays one line
    assert len(lines) == (3 if terminal else 2), lines
    assert lines[0].startswith("compiling the numerical kernels for this machine"), lines
    assert f"about {FIRST_COMPILE_SECONDS / 60:.0f} min" in lines[-2], lines
    assert lines[-1].startswith("compiled the numerical kernels in 0 s"), lines


def test_a_compilation_off_a_terminal_is_never_silent_for_long(uncompiled, monkeypatch):
    """In a log (make install, CI) a line comes every STILL_COMPILING_EVERY seconds."""
    from coincli.cli import common

    monkeypatch.setattr(common, "STILL_COMPILING_EVERY", 0.3)
    out = uncompiled(terminal=False, compile_kernels=lambda: time.sleep(1.1))
    common.compile_first()
    stills = [line for line in plain(out).splitlines() if line.startswith("still compiling: ")]
    assert 2 <= len(stills) <= 4, plain(out)
    assert plain(out).strip().splitlines()[-1].startswith("compiled the numerical kernels in 1 s")


def test_ctrl_c_during_the_first_compilation_is_one_line_and_exit_130(uncompiled):
    import typer

    from coincli.cli.common import compile_first

    def interrupted():
        raise KeyboardInterrupt

    out = uncompiled(terminal=True, compile_kernels=interrupted)
    with pytest.raises(typer.Exit) as stop:
        compile_first()
    assert stop.value.exit_code == 130
    assert plain(out).endswith("interrupted: while compiling the numerical kernels; nothing was "
                               "done\n"), plain(out)


def test_compiled_kernels_are_not_compiled_again(monkeypatch):
    import coincli.api as api
    import coincli.jit as jit
    from coincli.cli.common import compile_first

    monkeypatch.setattr(jit, "kernels_cached", lambda *model: True)
    monkeypatch.setattr(api, "compile_kernels", lambda **model: pytest.fail("compiled again"))
    compile_first()
    result = run("compile")
    assert result.exit_code == 0, result.stderr
    assert "compiled already" in result.stdout and result.stderr == ""


# -- outcome tables: the ten most frequent n, every n with --all or in JSON ---------------------

def outcome_rows(stdout: str) -> list[int]:
    """The n of each row of an outcome table."""
    return [int(m) for m in re.findall(r"^│\s+(-?\d+) │", stdout, re.MULTILINE)]


def listed_by_count(every: list, shown: list[int]) -> list:
    """The rows of ``every`` left out of a table that lists ``shown``, checked to be those of
    the lowest counts: every n listed has more than every n left out (ties go together), and
    about ten are listed."""
    counts = {row["n"]: row["count"] for row in every}
    hidden = [row for row in every if row["n"] not in shown]
    assert 5 <= len(shown) <= 15, shown
    assert min(counts[n] for n in shown) > max(row["count"] for row in hidden), (shown, every)
    return hidden


def test_basin_stats_lists_the_ten_most_frequent_n_unless_all(in_tmp):
    """By count, never one n of a tie without the other: the default map is mirrored (n and -n
    have as many cells), so the n listed are symmetric (issue 48: -10..8 and not +10)."""
    assert run("basin", "s.zarr", "--res", "48", "-q").exit_code == 0
    every = json.loads(run("basin", "stats", "s.zarr", "--json").stdout)["outcomes"]
    assert len(every) > 10  # the JSON lists every n
    top = run("basin", "stats", "s.zarr", env={"COLUMNS": "100"})
    shown = outcome_rows(top.stdout)
    assert sorted(shown) == shown, shown  # by n, as --all
    hidden = listed_by_count(every, shown)
    assert {-n for n in shown} == set(shown), shown
    rest = sum(row["fraction"] for row in hidden)
    assert f"... {len(hidden)} more n, " in top.stdout and \
        "of the labelled cells together (--all lists every n)" in top.stdout, top.stdout
    assert f"{100 * rest:.3g} %" in top.stdout, (rest, top.stdout)
    full = run("basin", "stats", "s.zarr", "--all", env={"COLUMNS": "100"})
    assert outcome_rows(full.stdout) == [row["n"] for row in every]
    assert "more n" not in full.stdout


def test_fractions_lists_the_ten_most_frequent_n_unless_all(in_tmp):
    args = ["fractions", "--samples", "1024", "--batch", "512", "--phi0", "-pi:pi", "-q"]
    every = json.loads(run(*args, "--json").stdout)["outcomes"]
    assert len(every) > 10
    top = run(*args, env={"COLUMNS": "100"})
    hidden = listed_by_count(every, outcome_rows(top.stdout))
    assert f"... {len(hidden)} more n, " in top.stdout and "of the certain labels" in \
        top.stdout, top.stdout
    full = run(*args, "--all", env={"COLUMNS": "100"})
    assert outcome_rows(full.stdout) == [row["n"] for row in every], full.stdout


def test_an_outcome_table_keeps_a_tie_together():
    """Rows of one count are listed or left out together; past half as many again, left
    out; all of one count: the earliest ten."""
    from coincli.cli.text import most_frequent

    def rows(*counts):
        return [{"n": n, "count": c} for n, c in enumerate(counts)]

    def listed(table):
        return [row["n"] for row in most_frequent(table)[0]]

    # a mirrored map: counts n = -5..5 symmetric, the 10th and 11th largest tied
    mirrored = [{"n": n, "count": 100 - 10 * abs(n)} for n in range(-6, 7)]
    assert listed(mirrored) == list(range(-5, 6))  # 11 rows: the tie at +-5 kept together
    assert listed(rows(*range(20, 0, -1))) == list(range(10))  # no tie: the ten largest
    many = rows(9, 8, 7, 6, 5, 4, 3, 2, 1, *[0] * 20)  # a tie of 20 at the cut: left out
    shown, hidden = most_frequent(many)
    assert [row["n"] for row in shown] == list(range(9)) and len(hidden) == 20
    assert listed(rows(*[3] * 30)) == list(range(10))  # every row tied: the earliest ten
    assert listed(rows(5, 4)) == [0, 1] and most_frequent(rows(5, 4))[1] == []


def test_an_option_of_another_basin_command_is_named(in_tmp, capsys, monkeypatch):
    """`coin basin x.zarr -o out.png` (issue 48): the answer names the command that takes -o,
    one that `coin basin --help` lists, and which command ran; nothing is created."""
    from coincli.cli import run as coin

    monkeypatch.setattr(sys, "argv", ["coin"])  # the program's name, as the script has it
    listed = run("basin", "--help").stdout
    for args, words, see in (
            (["basin", "x.zarr", "-o", "out.png"],
             "No such option: -o: coin basin STORE runs coin basin sweep STORE, which has none; "
             "-o is an option of coin basin render and coin basin analyze", "render"),
            (["basin", "x.zarr", "--bogus"], "coin basin STORE runs coin basin sweep STORE",
             "sweep"),
            (["basin", "stats", "x.zarr", "--res", "8"],
             "No such option: --res: --res is an option of coin basin sweep, not of coin basin "
             "stats", "sweep")):
        assert coin(args) == 2
        out, err = capsys.readouterr()
        lines = err.strip().splitlines()
        assert out == "" and len(lines) == 1 and "Traceback" not in err, err
        assert lines[0].startswith("error: ") and words in lines[0], lines[0]
        assert lines[0].endswith(f"(see 'coin basin {see} --help')"), lines[0]
        assert re.search(rf"^│ {see} ", listed, re.MULTILINE), listed  # in `coin basin --help`
    assert coin(["fractions", "-o", "x"]) == 2  # `coin`'s commands are tools apart
    assert capsys.readouterr().err.strip() == "error: No such option: -o (see 'coin fractions " \
                                              "--help')"
    assert not (in_tmp / "x.zarr").exists()


def test_the_next_step_of_a_sweep_writes_beside_the_store(in_tmp):
    """`make demo` sweeps into out/: the hint's picture goes there too, not into the current
    folder (issue 48)."""
    result = run("basin", "out/s.zarr", "--res", "16", "-q")
    assert result.exit_code == 0, (result.stdout, result.stderr)
    said = result.stdout.replace("\u00a0", " ")
    assert "Next: coin basin render out/s.zarr -o out/s.png; coin basin stats out/s.zarr" in \
        said, said
    assert run("basin", "render", "out/s.zarr", "-o", "out/s.png").exit_code == 0
    assert (in_tmp / "out" / "s.png").exists()


def test_a_store_of_other_samples_is_one_line(in_tmp):
    """Off a terminal the note on mass and inertia comes first; not before the refusal of a
    store of other samples, which is one line alone (issue 48)."""
    args = ["fractions", "--samples", "256", "--batch", "256", "--store", "o.zarr"]
    first = run(*args, "--over", "thickness=0.002,0.004")
    assert first.exit_code == 0, (first.stdout, first.stderr)
    assert "note: mass and inertia follow" in first.stderr, first.stderr
    for other in (["--over", "thickness=0.002,0.006"],
                  ["--over", "thickness=0.002,0.004", "--vx", "0.1"]):
        assert_one_line_error(run(*args, *other), "o.zarr holds other samples",
                              "or --overwrite to replace it")


@pytest.mark.skipif(shutil.which("make") is None, reason="no make")
def test_make_demo_compiles_the_kernels_as_a_step_before_the_demo():
    plan = subprocess.run(["make", "-n", "demo"], cwd=REPO, capture_output=True, text=True,
                          timeout=60)
    assert plan.returncode == 0, plan.stderr
    commands = [line.split()[1] for line in plan.stdout.splitlines()
                if line.split()[:1] and line.split()[0].endswith("/coin")]
    assert commands[0] == "compile" and "simulate" in commands and "basin" in commands, \
        plan.stdout
