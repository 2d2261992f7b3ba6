"""`coin basin`: grid parsing, the Zarr store, resume after kill -9 and Ctrl-C, parameter checks,
rendering and statistics of partial stores, mirror symmetry, and verified labels.

Grids are tiny (the default method costs ~0.1 ms a trajectory once numba's cache is warm)."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import default_signals, local_cluster, store_files
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.engines.basin import run_tile_task
from coincli.engines.basin_plan import sweep_attrs
from coincli.grid import compute_tile, make_grid, make_spec, parse_pair, parse_range
from coincli.integrators import NO_LABEL, info
from coincli.params import ParameterError, Scene
from coincli.stats import basin_stats, wilson
from coincli.stores.basin_store import BasinStore

runner = CliRunner()
SMALL = ["--res", "8", "--chunk", "4", "-q"]


def coin(*args: str):
    return runner.invoke(app, ["basin", *args])


def coin_ok(*args: str):
    result = coin(*args)
    assert result.exit_code == 0, result.output
    return result


# -- comparing stores ----------------------------------------------------------------------------
def _chunk_files(path: Path) -> dict[str, bytes]:
    """Every file of the store, metadata included, but its records (measured costs and runs,
    in out.zarr/.coin/): the rest must be bit-identical however the store was computed."""
    return store_files(path)


def assert_same_store(a: Path, b: Path) -> None:
    import zarr

    ga, gb = zarr.open_group(str(a), mode="r"), zarr.open_group(str(b), mode="r")
    names = sorted(ga.array_keys())
    assert names == sorted(gb.array_keys())
    for name in names:
        x, y = ga[name][:], gb[name][:]
        assert x.dtype == y.dtype, name
        assert x.tobytes() == y.tobytes(), f"array {name} differs"
    fa, fb = _chunk_files(a), _chunk_files(b)
    assert sorted(fa) == sorted(fb)
    for rel in fa:
        assert fa[rel] == fb[rel], f"file {rel} differs"
    assert dict(ga.attrs) == dict(gb.attrs)


def done_tiles(path: Path) -> int:
    root = path / "done" / "c"
    return sum(len(files) for _, _, files in os.walk(root)) if root.exists() else 0


def start_sweep(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "coincli", "basin", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=default_signals, cwd=Path(__file__).parent.parent)


def wait_for_tiles(proc: subprocess.Popen, path: Path, n: int, timeout: float = 60) -> None:
    end = time.monotonic() + timeout
    while done_tiles(path) < n:
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"sweep ended before {n} tiles were done: {err.decode()[-2000:]}")
        if time.monotonic() > end:
            proc.kill()
            pytest.fail("no tile was written in time")
        time.sleep(0.002)


# -- parsing and validation ----------------------------------------------------------------------
def test_parse_range_and_pairs():
    assert parse_range("vy", "0:2") == (0.0, 2.0)
    assert parse_range("vphi", " -20 : 20 ") == (-20.0, 20.0)
    assert parse_range("vx", "1.5") == 1.5
    assert parse_pair("res", "512") == (512, 512)
    assert parse_pair("res", "512x256") == (512, 256)
    for bad in ("2:1", "1:1", "nan:2", "0:inf", "a:b", "1:2:3", ":2", "nan"):
        with pytest.raises(ParameterError):
            parse_range("vy", bad)
    for bad in ("0", "8x", "axb", "1x2x3"):
        with pytest.raises(ParameterError):
            parse_pair("res", bad)


def test_grid_cell_centres_and_tiles():
    scene = Scene()
    grid = make_grid(scene, {"vy": (0.0, 1.0), "vphi": (-2.0, 2.0)}, (5, 3), (2, 2))
    assert grid.dims == ("vy", "vphi")
    np.testing.assert_array_equal(grid.axes[0].coords, np.linspace(0, 1, 5))
    assert grid.tile_grid == (3, 2)
    assert sum(grid.tile_cells(t) for t in grid.tiles()) == 15
    states = grid.tile_states((2, 1))  # the corner tile: vy = 1, vphi = 2
    assert states.shape == (1, 6)
    np.testing.assert_array_equal(states[0], [0, scene.coin.r, 0, 0, 1.0, 2.0])


@pytest.mark.parametrize("args, message", [
    (["--vy", "2:1"], "empty range"),
    (["--vy", "nan:1"], "finite"),
    (["--vy", "nan"], "finite"),
    (["--vx", "0:1"], "exactly two"),
    (["--vy", "1.0"], "exactly two"),
    (["--method", "euler"], "unknown method"),
    (["--preset", "nope"], "unknown preset"),
    (["--method", "symplectic_euler", "--dt", "1e-3"], "stable step"),
    (["--res", "1"], "--res"),
    (["--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "not both"),
    (["--k", "-1"], "k must be positive"),
])
def test_bad_input_one_line_exit_2(tmp_path, args, message):
    result = coin(str(tmp_path / "s.zarr"), *SMALL, *args)
    assert result.exit_code == 2, result.output
    assert message in result.output
    assert "Traceback" not in result.output
    assert not (tmp_path / "s.zarr").exists()


# -- the store -----------------------------------------------------------------------------------
def test_store_layout_and_xarray(tmp_path):
    import xarray as xr
    import zarr

    path = tmp_path / "s.zarr"
    coin_ok(str(path), "--vy", "0.1:0.7", "--res", "8x6", "--chunk", "4", "-q")
    group = zarr.open_group(str(path), mode="r")
    assert group["quarter_turns"].dtype == np.int16
    assert group["quarter_turns"].fill_value == NO_LABEL
    assert group["status"].dtype == np.uint8 and group["status"].fill_value == 255
    assert group["settle_time"].dtype == np.float32
    assert group["quarter_turns"].chunks == (4, 4) and group["done"].chunks == (1, 1)
    assert group["done"].dtype == np.uint32 and (group["done"][:] != 0).all()  # digests
    assert BasinStore.open(path).check().intact
    attrs = dict(group.attrs)
    assert attrs["sweep"]["dims"] == ["vy", "vphi"]
    assert attrs["parameters"]["foundation"]["k"] == 1e4
    assert attrs["parameters"]["initial"]["vy"] is None  # swept
    assert attrs["method"]["name"] == "event" and attrs["version"]
    assert "runs" not in attrs and len(BasinStore.open(path).read().runs) == 1
    assert np.isfinite(BasinStore.open(path).read().tile_seconds).all()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no consolidated-metadata fallback warning
        ds = xr.open_zarr(path)
    assert ds["quarter_turns"].dims == ("vy", "vphi")
    np.testing.assert_allclose(ds["vy"].values, np.linspace(0.1, 0.7, 8))
    np.testing.assert_allclose(ds["vphi"].values, np.linspace(-20, 20, 6))
    assert ds["vphi"].attrs["units"] == "rad/s"
    assert int(ds["status"].max()) == 0  # all settled
    n = float(ds["quarter_turns"].sel(vy=0.1, vphi=-20.0).values)
    assert n == group["quarter_turns"][0, 0]
    assert ds.attrs["parameters"]["coin"]["diameter"] == 0.02


def test_tile_equal_to_fill_value_is_written(tmp_path):
    # every cell non-finite would equal the fill values; simulate it through the writer
    path = tmp_path / "s.zarr"
    grid = make_grid(Scene(), {"vy": (0.1, 0.2), "vphi": (0.0, 1.0)}, (4, 4), (2, 2))
    spec = make_spec(Scene(), grid)
    store = BasinStore(path)
    store.create_or_resume({"coin_basin": {}, "version": "t"}, spec.grid)
    result = compute_tile(spec, (0, 0))
    result.arrays["quarter_turns"][:] = NO_LABEL
    result.arrays["status"][:] = 255
    result.arrays["settle_time"][:] = np.nan
    result.arrays["steps"][:] = -1
    store.write_tile(result)
    for name in ("quarter_turns", "status", "settle_time", "steps", "done"):
        assert (path / name / "c" / "0" / "0").is_file(), name


def test_parameter_mismatch_is_refused(tmp_path):
    path = str(tmp_path / "s.zarr")
    coin_ok(path, *SMALL)
    result = coin(path, *SMALL, "--k", "5000")
    assert result.exit_code == 2
    assert "k = 10000 in the store, 5000 here" in result.output
    result = coin(path, *SMALL, "--vphi", "-10:20")
    assert result.exit_code == 2 and "--vphi LO = -20 in the store, -10 here" in result.output
    result = coin(path, "--res", "16", "--chunk", "4", "-q")
    assert result.exit_code == 2 and "--res (vy cells) = 8 in the store, 16 here" in \
        " ".join(result.output.split())
    result = coin(path, *SMALL, "--single-pass")
    assert result.exit_code == 2 and "verification" in result.output
    # the same command resumes (nothing left to do); --overwrite replaces
    assert "done already" in coin_ok(path, *SMALL).output
    coin_ok(path, *SMALL, "--k", "5000", "--overwrite")
    assert BasinStore.open(path).read().attrs["parameters"]["foundation"]["k"] == 5000
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "keep.txt").write_text("x")
    result = coin(str(tmp_path / "other"), *SMALL, "--overwrite")
    assert result.exit_code == 2 and "not a Zarr store" in result.output
    assert (tmp_path / "other" / "keep.txt").exists()


def test_sweep_subcommand_alias_and_help(tmp_path):
    a, b = tmp_path / "a.zarr", tmp_path / "b.zarr"
    coin_ok(str(a), *SMALL)
    coin_ok("sweep", str(b), *SMALL, "--threads", "1")
    assert_same_store(a, b)
    assert "render" in coin_ok("--help").output
    assert "--single-pass" in coin_ok("sweep", "--help").output


# -- resuming ------------------------------------------------------------------------------------
KILL_ARGS = ["--res", "48", "--chunk", "4", "--threads", "1", "-q"]


def test_resume_after_kill9_is_bit_identical(tmp_path):
    killed = tmp_path / "killed.zarr"
    proc = start_sweep(str(killed), *KILL_ARGS)
    wait_for_tiles(proc, killed, 5)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n = done_tiles(killed)
    assert 5 <= n < 144, f"{n} tiles done when killed: not mid-sweep"
    coin_ok(str(killed), *KILL_ARGS)  # resume
    assert done_tiles(killed) == 144
    clean = tmp_path / "clean.zarr"
    coin_ok(str(clean), "--res", "48", "--chunk", "4", "--threads", "2", "-q")
    assert_same_store(killed, clean)


def test_ctrl_c_stops_cleanly_and_resumes(tmp_path):
    path = tmp_path / "s.zarr"
    proc = start_sweep(str(path), *KILL_ARGS)
    wait_for_tiles(proc, path, 3)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err.decode()
    assert b"Traceback" not in err and b"resume" in err
    basin = BasinStore.open(path).read()
    assert 3 <= basin.done.sum() < basin.done.size
    # every flagged tile is complete
    assert (basin.arrays["status"][basin.computed] != 255).all()
    runs = basin.runs
    assert runs[-1]["interrupted"] is True
    coin_ok(str(path), *KILL_ARGS)
    assert BasinStore.open(path).read().done.all()


# -- distributed ---------------------------------------------------------------------------------
def test_dask_runs_give_the_same_store(tmp_path):
    args = ["--vy", "0.05:2", "--res", "16", "--chunk", "8", "-q"]
    local = tmp_path / "local.zarr"
    coin_ok(str(local), *args)
    workers = tmp_path / "workers.zarr"
    coin_ok(str(workers), *args, "--workers", "2")  # a 2-process LocalCluster
    assert_same_store(local, workers)
    assert BasinStore.open(workers).read().runs[0]["mode"] == "dask"
    with local_cluster(2) as cluster:
        remote = tmp_path / "remote.zarr"
        coin_ok(str(remote), *args, "--scheduler", cluster.scheduler_address)
    assert_same_store(local, remote)


def test_task_function_is_importable_and_writes_its_tile(tmp_path):
    path = tmp_path / "s.zarr"
    grid = make_grid(Scene(), {"vy": (0.1, 0.5), "vphi": (-5.0, 5.0)}, (4, 4), (2, 2))
    spec = make_spec(Scene(), grid)
    BasinStore(path).create_or_resume(sweep_attrs(Scene(), info("event"), spec), spec.grid)
    store = BasinStore.open(path)
    done = run_tile_task(store, spec, store.parameters, (1, 0))
    assert done.tile == (1, 0) and done.cpu_seconds >= 0 and done.written
    assert done.compute_seconds > 0 and done.write_seconds > 0
    # vphi sweeps -5:5 in whole tiles: the task writes tile (1, 0) and its mirror image (1, 1)
    assert done.tiles == 2 and done.cells == 8
    done_flags = BasinStore.open(path).check().done.astype(np.uint8)
    assert (done_flags[0] == 0).all() and (done_flags[1] != 0).all()


# -- pictures and statistics ---------------------------------------------------------------------
def _partial_store(tmp_path, verify=True) -> Path:
    """A 8 x 8 sweep with 2 of its 4 tiles computed."""
    path = tmp_path / "partial.zarr"
    scene = Scene().with_overrides(verify=verify)
    grid = make_grid(scene, {"vy": (0.3, 1.9), "vphi": (-15.0, 15.0)}, (8, 8), (4, 4),
                     use_mirror=False)
    spec = make_spec(scene, grid)
    attrs = sweep_attrs(scene, info("event"), spec)
    BasinStore(path).create_or_resume(attrs, spec.grid)
    store = BasinStore.open(path)
    for tile in ((0, 0), (1, 1)):
        run_tile_task(store, spec, store.parameters, tile)
    return path


@pytest.mark.parametrize("verify", [False, True])
def test_render_and_stats_on_a_partial_store(tmp_path, verify):
    path = _partial_store(tmp_path, verify)
    png = tmp_path / "basin.png"
    coin_ok("render", str(path), "-o", str(png), "--dpi", "60", "--n-max", "40")
    assert png.stat().st_size > 5000
    from matplotlib.image import imread

    image = imread(png)
    assert image.shape[0] > 200 and image.shape[2] in (3, 4)
    stats = json.loads(coin_ok("stats", str(path), "--json").output)
    assert stats["cells"] == 64 and stats["computed"] == 32 and stats["not_computed"] == 32
    assert stats["tiles_done"] == 2 and stats["tiles"] == 4
    assert sum(r["count"] for r in stats["outcomes"]) == stats["labelled"] == 32
    assert stats["cost"]["cpu_seconds"] > 0
    assert stats["verified"] is verify
    text = coin_ok("stats", str(path)).output
    assert "not computed" in text and "standing" in text
    basin = BasinStore.open(path).read()
    assert (basin.arrays["status"][~basin.computed] == 255).all()


def test_render_rerun_recording(tmp_path):
    path = _partial_store(tmp_path)
    rrd = tmp_path / "basin.rrd"
    coin_ok("render", str(path), "-o", str(tmp_path / "b.png"), "--dpi", "50", "--rrd", str(rrd))
    assert rrd.stat().st_size > 1000


def test_render_and_stats_errors(tmp_path):
    result = coin("render", str(tmp_path / "missing.zarr"))
    assert result.exit_code == 2 and "missing.zarr does not exist" in result.output
    result = coin("stats", str(tmp_path / "missing.zarr"))
    assert result.exit_code == 2 and "does not exist" in result.output
    (tmp_path / "folder").mkdir()
    result = coin("stats", str(tmp_path / "folder"))
    assert result.exit_code == 2 and "not a Zarr store (it has no zarr.json)" in result.output


def test_render_and_stats_of_an_empty_store(tmp_path):
    path = tmp_path / "empty.zarr"
    grid = make_grid(Scene(), {"vy": (0.1, 0.5), "vphi": (-5.0, 5.0)}, (4, 4), (2, 2))
    spec = make_spec(Scene(), grid)
    BasinStore(path).create_or_resume(sweep_attrs(Scene(), info("event"), spec), spec.grid)
    coin_ok("render", str(path), "-o", str(tmp_path / "e.png"), "--dpi", "40")
    stats = json.loads(coin_ok("stats", str(path), "--json").output)  # valid JSON: no NaN
    assert stats["computed"] == 0 and stats["standing"]["probability"] is None
    assert "nothing computed yet" in coin_ok("stats", str(path)).output


def test_wilson_and_stats_pure():
    lo, hi = wilson(635, 262144)  # the paper's count
    assert lo < 635 / 262144 < hi
    assert math.isclose(lo, 0.002240, rel_tol=2e-3) and math.isclose(hi, 0.002620, rel_tol=2e-3)
    assert wilson(0, 10)[0] == 0.0 and wilson(10, 10)[1] == 1.0
    q = np.array([[0, 1, 2, NO_LABEL], [-1, 0, 0, NO_LABEL]], dtype=np.int16)
    st = np.array([[0, 0, 1, 2], [0, 0, 0, 255]], dtype=np.uint8)
    certainty = np.array([[1, 0, 0, 0], [1, 1, 1, 255]], dtype=np.uint8)  # 1 certain
    s = basin_stats(q, st, certainty)
    assert (s["computed"], s["not_computed"]) == (7, 1)
    assert (s["status"]["non-finite"], s["status"]["unsettled"]) == (1, 1)
    assert s["labelled"] == 6 and s["standing"]["count"] == 2
    assert s["verified"] and s["certain"]["count"] == 4
    assert s["uncertain"]["count"] == 3 and s["uncertain"]["standing"] == 1
    assert s["standing_certain"]["count"] == 1 and s["standing_certain"]["of"] == 4
    assert {r["n"]: r["count"] for r in s["outcomes"]} == {-1: 1, 0: 3, 1: 1, 2: 1}
    assert {r["n"]: r["count"] for r in s["outcomes_certain"]} == {-1: 1, 0: 3}


# -- physics -------------------------------------------------------------------------------------
def test_mirror_symmetry_vphi_to_minus_vphi():
    """Reflecting x -> -x maps (vphi0, n) to (-vphi0, -n) at low vy0, where labels are robust."""
    scene = Scene()
    grid = make_grid(scene, {"vy": (0.1, 0.75), "vphi": (-20.0, 20.0)}, (8, 9), (8, 9))
    result = compute_tile(make_spec(scene, grid), (0, 0))
    q = result.arrays["quarter_turns"].astype(int)
    assert (result.arrays["status"] == 0).all()
    np.testing.assert_array_equal(q, -q[:, ::-1])
    assert np.abs(q).max() >= 2  # not trivially all zero


def test_verified_labels_of_the_thick_coin_are_those_of_tight_runs(tmp_path):
    """On a small thick-preset grid, every cell the default calls certain has the label of a
    run at rtol 1e-10, or, if it converged only on a deeper rung (1e-11, 1e-12, where 1e-10 is
    itself not converged), of a run at rtol 1e-12; the uncertain cells are drawn and counted."""
    import coincli

    path = tmp_path / "thick.zarr"
    coin_ok(str(path), "--preset", "thick", "--vy", "0.8:2", "--res", "12", "--chunk", "6", "-q")
    basin = BasinStore.open(path).read()
    certain = basin.arrays["certainty"] == 1
    assert certain.mean() > 0.5  # a hard region: vy0 up to 2 m/s on the thick coin
    deep = basin.arrays["rung"] > 3  # rung 3 is rtol 1e-10 (1e-6, 1e-8, 1e-9, 1e-10, ... 1e-12)
    for rtol, cells in ((1e-10, certain & ~deep), (1e-12, certain & deep)):
        tight = coincli.load_preset("thick").with_overrides(verify=False, rtol=rtol)
        reference = coincli.basin(tight, vy=(0.8, 2.0), res=12)["quarter_turns"].values
        np.testing.assert_array_equal(basin.arrays["quarter_turns"][cells], reference[cells])
    stats = json.loads(coin_ok("stats", str(path), "--json").output)
    assert stats["verified"] and stats["certain"]["count"] == int(certain.sum())
    assert stats["uncertain"]["count"] + stats["certain"]["count"] == stats["labelled"]
    coin_ok("render", str(path), "-o", str(tmp_path / "t.png"), "--dpi", "50")


# -- mirror symmetry -----------------------------------------------------------------------------
def _flips(ranges, res=(8, 8), chunk=(4, 4), use_mirror=True, **fixed):
    return make_grid(Scene().with_overrides(**fixed), ranges, res, chunk,
                     use_mirror=use_mirror).mirror_flips


def test_which_sweeps_are_their_own_mirror_image():
    assert _flips({"vy": (0.1, 1.0), "vphi": (-5.0, 5.0)}) == (False, True)
    assert _flips({"vx": (-1.0, 1.0), "vphi": (-5.0, 5.0)}) == (True, True)
    assert _flips({"phi0": (-1.0, 1.0), "vy": (0.1, 1.0)}) == (True, False)
    assert _flips({"vy": (0.1, 1.0), "vphi": (-5.0, 6.0)}) is None  # not symmetric
    assert _flips({"vy": (0.1, 1.0), "vphi": (-5.0, 5.0)}, res=(8, 10)) is None  # part tiles
    assert _flips({"vy": (0.1, 1.0), "vphi": (-5.0, 5.0)}, phi0=0.1) is None  # moved by it
    assert _flips({"vy": (0.1, 1.0), "vphi": (-5.0, 5.0)}, vx=0.2) is None
    assert _flips({"vy": (0.1, 1.0), "vphi": (-5.0, 5.0)}, x0=0.3) == (False, True)  # any x0
    assert _flips({"y0": (0.011, 0.02), "vy": (0.1, 1.0)}) is None  # nothing it reverses
    assert _flips({"vy": (0.1, 1.0), "vphi": (-5.0, 5.0)}, use_mirror=False) is None


def test_tiles_are_computed_most_energetic_first():
    """The work tiles in order of falling energy at their middle cells (the costly ones first,
    so that the sweep's last tiles are cheap), each once."""
    scene = coincli.load_preset("paper")
    grid = make_grid(scene, {"vy": (0.05, 2.0), "vphi": (-20.0, 20.0)}, (16, 16), (4, 4))
    spec = make_spec(scene, grid)
    order = spec.work_order()
    assert sorted(order) == sorted(grid.work_tiles()) and len(order) == 8  # mirrored: half
    assert order[0] == (3, 0) and order[-1] == (0, 1)  # fastest throw first, slowest last
    middle = [grid.tile_states(t)[len(grid.tile_states(t)) // 2] for t in order]
    p = spec.labeller.params
    kinetic = [s[4] ** 2 + p.inertia / p.mass * s[5] ** 2 for s in middle]
    assert kinetic == sorted(kinetic, reverse=True)


@pytest.mark.parametrize("ranges", [dict(vy=(0.3, 1.9), vphi=(-15.0, 15.0)),
                                    dict(vx=(-0.4, 0.4), vphi=(-15.0, 15.0), vy=1.2)])
def test_a_mirrored_map_is_the_full_map(ranges):
    """Each mirror pair computed once (a reflection in vphi, or through the centre in (vx,
    vphi)) gives the labels of computing every cell."""
    scene = Scene()
    half = coincli.basin(scene, res=8, chunk=2, threads=1, **ranges)
    full = coincli.basin(scene, res=8, chunk=2, threads=1, mirror=False, **ranges)
    assert coincli.basin_attrs(half)["sweep"]["mirror"] == [d for d in ("vx", "vphi")
                                                           if d in ranges]
    assert coincli.basin_attrs(full)["sweep"]["mirror"] is None
    for name in ("quarter_turns", "status", "certainty", "rung"):
        np.testing.assert_array_equal(half[name].values, full[name].values, err_msg=name)
    turns = half["quarter_turns"].values
    assert np.array_equal(turns[::-1, ::-1] if "vx" in ranges else turns[:, ::-1], -turns)


def test_a_resumed_sweep_says_so_and_counts_only_mirrored_cells_as_mirrored(tmp_path):
    import threading

    path = str(tmp_path / "r.zarr")
    ranges = dict(vy=(0.3, 1.0), vphi=(-15.0, 15.0))
    plan = coincli.plan_sweep(coincli.load_preset("paper"), res=16, chunk=8, **ranges)
    stop = threading.Event()  # after the first work tile (and its mirror image)
    report = coincli.sweep(plan, path, threads=1, progress=lambda u: stop.set(), stop=stop)
    assert report.interrupted and report.tiles_done == 2 and report.mirrored_cells == 64
    result = coin(path, "--vy", "0.3:1", "--vphi", "-15:15", "--res", "16", "--chunk", "8")
    text = " ".join(result.output.split())
    assert result.exit_code == 0
    assert "resuming " in text and "2 of 4 tiles done already, 2 tiles to compute" in text
    assert "half of them as the mirror images" in text
    # one tile that is its own mirror image: every cell computed, none said to be mirrored
    one = coin(str(tmp_path / "one.zarr"), "--vy", "0.3:1", "--vphi", "-15:15", "--res", "8")
    assert one.exit_code == 0 and "mirror" not in one.output
