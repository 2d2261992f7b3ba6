"""`coin simulate --csv FILE` (the sampled time series, names and units in the header) and
`coin simulate --gif FILE` (an animation drawn with matplotlib: .gif, or .mp4 with ffmpeg), and
the library functions behind them (coincli.charts.timeseries, coincli.charts.animation); outputs are
complete or absent, whatever fails."""

from __future__ import annotations

import errno
import json
import os
import stat
import sys
import textwrap

import numpy as np
import pytest
from typer.testing import CliRunner

import coincli
from coincli.charts import animation
from coincli.charts.timeseries import SERIES_NAMES, csv_header
from coincli.cli import app
from coincli.params import ParameterError
from coincli.throw import QUANTITIES

FIG2 = ["--vy", "1.197", "--vphi", "3.508", "--no-rrd"]
runner = CliRunner()


def invoke(*args):
    return runner.invoke(app, ["simulate", *FIG2, *args], env={"COLUMNS": "200"})


@pytest.fixture(scope="module")
def fig2():
    scene = coincli.load_preset("paper").with_overrides(vy=1.197, vphi=3.508)
    return coincli.simulate(scene, sample_dt=1e-3, record_events=True)


def leftovers(folder) -> list[str]:
    """Temporary files an interrupted writer left behind."""
    return [p.name for p in folder.iterdir() if ".tmp-" in p.name]


# -- --csv ---------------------------------------------------------------------------------------

def test_csv_has_named_columns_with_units_and_reads_back(tmp_path, fig2):
    out = tmp_path / "throw.csv"
    result = invoke("--csv", str(out))
    assert result.exit_code == 0, result.output
    assert f"{out}: {len(fig2.samples)} rows" in " ".join(result.output.split())  # any width
    header = out.read_text().splitlines()[0]
    assert header == csv_header()
    assert header.startswith("t [s],x [m],y [m],phi [rad],vx [m/s],vy [m/s],vphi [rad/s],")
    assert header.split(",")[-1] == "energy [J]"
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    assert table.shape == (len(fig2.samples), 1 + len(SERIES_NAMES))
    np.testing.assert_array_equal(table[:, :7], fig2.samples)  # to the last bit (%.17g)
    ds = fig2.to_dataset()
    for i, name in enumerate(SERIES_NAMES, start=1):
        np.testing.assert_array_equal(table[:, i], ds[name].values)
        assert f"{name} [{QUANTITIES[name][0]}]" in header


def test_csv_rows_follow_log_every(tmp_path):
    out = tmp_path / "coarse.csv"
    assert invoke("--csv", str(out), "--log-every", "0.01").exit_code == 0
    t = np.loadtxt(out, delimiter=",", skiprows=1)[:, 0]
    np.testing.assert_allclose(np.diff(t[:-1]), 0.01, rtol=1e-9)


def test_csv_path_is_checked_before_the_run(tmp_path):
    result = invoke("--csv", str(tmp_path / "missing" / "throw.csv"))
    assert result.exit_code == 2
    assert result.output.count("\n") == 1 and result.output.startswith("error: ")
    assert "does not exist" in result.output and "outcome" not in result.output


def test_csv_write_failure_after_the_run_leaves_nothing(tmp_path, monkeypatch):
    """A disk that fills while the CSV is written: the outcome is printed, the error said in
    one line, exit 2, and neither the file nor a temporary one is left."""
    def full(fname, *args, **kwargs):
        with open(fname, "w") as handle:
            handle.write("t [s],x [m]\n0,0\n")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(np, "savetxt", full)
    out = tmp_path / "throw.csv"
    result = invoke("--csv", str(out))
    assert result.exit_code == 2
    assert "n = 6 quarter turns" in result.output
    assert f"could not write {out}" in " ".join(result.output.split())
    assert not out.exists() and not leftovers(tmp_path)


def test_json_names_the_files_written(tmp_path):
    out = tmp_path / "throw.csv"
    result = invoke("--csv", str(out), "--json")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["csv"] == str(out)


# -- --gif ---------------------------------------------------------------------------------------

def frames_of(path):
    """(frames, total duration in ms, size, frames showing a corner in contact) of a GIF."""
    from PIL import Image

    red = np.array([0xEB, 0x32, 0x28])
    count, duration, touching = 0, 0, 0
    with Image.open(path) as gif:
        size = gif.size
        for index in range(gif.n_frames):
            gif.seek(index)
            count += 1
            duration += gif.info["duration"]
            rgb = np.asarray(gif.convert("RGB")).astype(int)
            touching += bool((np.abs(rgb - red).sum(axis=-1) < 30).sum() > 5)
    return count, duration, size, touching


def test_gif_is_an_animation_of_the_throw(tmp_path, fig2):
    out = tmp_path / "throw.gif"
    result = invoke("--gif", str(out))
    assert result.exit_code == 0, result.output
    assert f"{out}: 4 s at 25 frames a second" in " ".join(result.output.split())
    count, duration, size, touching = frames_of(out)
    # 100 frames of 40 ms; Pillow merges identical neighbours (the coin at rest) into one
    assert 50 <= count <= animation.DEFAULT_FPS * animation.DEFAULT_SECONDS
    assert duration == pytest.approx(1000 * animation.DEFAULT_SECONDS, abs=40)
    assert size[0] >= 400 and size[1] >= 200
    assert 0 < touching < count  # corners in contact are drawn red, and only then


def test_animate_api_frames_and_rate(tmp_path, fig2):
    out = fig2.animate(tmp_path / "short.gif", fps=10, seconds=1.5)
    count, duration, _, _ = frames_of(out)
    assert count <= 15 and duration == pytest.approx(1500, abs=100)
    for bad in (dict(fps=0), dict(fps=2.5), dict(fps=True), dict(seconds=0),
                dict(seconds=float("nan")), dict(fps=25, seconds=1e6)):
        with pytest.raises(ParameterError):
            fig2.animate(tmp_path / "bad.gif", **bad)
    assert not (tmp_path / "bad.gif").exists()


def test_animation_of_a_throw_that_kept_nothing(tmp_path):
    run = coincli.simulate(coincli.load_preset("paper").with_overrides(vy=1.197, vphi=3.508))
    assert run.samples is None
    out = run.animate(tmp_path / "again.gif", fps=5, seconds=1)
    assert frames_of(out)[0] >= 2


@pytest.mark.parametrize("name, words", [
    ("throw.png", "written as .gif or .mp4"),
    ("throw", "written as .gif or .mp4"),
])
def test_gif_name_is_checked_before_the_run(tmp_path, name, words):
    result = invoke("--gif", str(tmp_path / name))
    assert result.exit_code == 2
    assert result.output.startswith(f"error: --gif {tmp_path / name}: ")
    assert words in result.output and result.output.count("\n") == 1


def test_mp4_without_ffmpeg_names_the_fix(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))  # no ffmpeg on it
    result = invoke("--gif", str(tmp_path / "throw.mp4"))
    assert result.exit_code == 2
    assert result.output.count("\n") == 1
    assert "needs ffmpeg on PATH" in result.output and ".gif" in result.output
    assert not (tmp_path / "throw.mp4").exists()


def fake_ffmpeg(folder, body: str):
    """An `ffmpeg` on PATH that runs ``body`` (Python) with the command line as ``argv``."""
    script = folder / "ffmpeg"
    script.write_text(f"#!{sys.executable}\nimport sys\nargv = sys.argv\n"
                      + textwrap.dedent(body))
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    return script


def test_mp4_is_fed_to_ffmpeg_frame_by_frame(tmp_path, monkeypatch, fig2):
    """The frames go to ffmpeg as raw RGB of the size it is told; the video is its output."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    fake_ffmpeg(bin_dir, """
        size = argv[argv.index("-s") + 1]
        width, height = map(int, size.split("x"))
        data = sys.stdin.buffer.read()
        assert len(data) % (width * height * 3) == 0, len(data)
        with open(argv[-1], "w") as out:
            out.write(f"{len(data) // (width * height * 3)} frames of {size}")
        """)
    monkeypatch.setenv("PATH", f"{bin_dir}{os.pathsep}{os.environ['PATH']}")
    out = fig2.animate(tmp_path / "throw.mp4", fps=10, seconds=2)
    assert out.read_text().startswith("20 frames of ")
    assert not leftovers(tmp_path)


def test_mp4_ffmpeg_failure_is_one_line_and_leaves_nothing(tmp_path, monkeypatch, fig2):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    fake_ffmpeg(bin_dir, """
        sys.stdin.buffer.read(10)
        sys.stderr.write("frame=1\\nUnknown encoder 'libx264'\\n")
        sys.exit(1)
        """)
    monkeypatch.setenv("PATH", f"{bin_dir}{os.pathsep}{os.environ['PATH']}")
    with pytest.raises(RuntimeError, match="ffmpeg could not write the video: Unknown encoder"):
        fig2.animate(tmp_path / "throw.mp4", fps=10, seconds=2)
    assert not (tmp_path / "throw.mp4").exists() and not leftovers(tmp_path)


def test_gif_interrupted_while_drawn_leaves_nothing(tmp_path, monkeypatch, fig2):
    """Ctrl-C while the frames are drawn: no file, no temporary file, the interrupt goes on."""
    drawn = []
    original = animation._pictures

    def interrupted(*args):
        for index, picture in enumerate(original(*args)):
            if index == 5:
                raise KeyboardInterrupt
            drawn.append(index)
            yield picture

    monkeypatch.setattr(animation, "_pictures", interrupted)
    with pytest.raises(KeyboardInterrupt):
        fig2.animate(tmp_path / "throw.gif")
    assert drawn == [0, 1, 2, 3, 4]
    assert not (tmp_path / "throw.gif").exists() and not leftovers(tmp_path)


def test_cli_interrupted_while_writing_the_gif(tmp_path, monkeypatch):
    """Ctrl-C while the animation is drawn: the outcome is printed, the CSV written before it
    is whole, the animation absent, exit 130."""
    def interrupted(*args):
        raise KeyboardInterrupt
        yield

    monkeypatch.setattr(animation, "_pictures", interrupted)
    csv, gif = tmp_path / "throw.csv", tmp_path / "throw.gif"
    result = invoke("--csv", str(csv), "--gif", str(gif))
    assert result.exit_code == 130
    assert "n = 6 quarter turns" in result.output
    assert "interrupted while writing the outputs" in result.output
    assert len(np.loadtxt(csv, delimiter=",", skiprows=1)) > 300
    assert not gif.exists() and not leftovers(tmp_path)
