"""The basin store under damage, concurrency, interrupts, long sweeps and failing disks (issue 12):

- every kind of damage to a chunk file is found (`coin basin verify`), never crashes or invents
  a label in `stats` and `render`, and a resume recomputes the tile and says so, leaving a
  store bit-identical to an uninterrupted one;
- processes started together on one store all succeed, compute disjoint tiles and leave the
  same store as one process; stale claims are taken over;
- a second Ctrl-C stops a stuck sweep at once, nothing half-written;
- a sweep is estimated before it starts, and refused over 12 hours without --yes;
- a read-only or full disk is a one-line error, found before work, leaving nothing behind.

Grids are tiny (a few tiles of the default method, ~0.1 ms a cell once numba's cache is warm).
"""

from __future__ import annotations

import errno
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import default_signals, sigint_raises, store_files
from typer.testing import CliRunner

import coincli
from coincli import api
from coincli.cli import app
from coincli.engines import basin as engine
from coincli.engines import claims as claims_io
from coincli.engines.basin_plan import pilot_cells
from coincli.integrators import NO_LABEL
from coincli.stores import basin_layout, zarr_v3
from coincli.stores import basin_schema as schema
from coincli.stores.basin_layout import RECORDS, records_dir
from coincli.stores.basin_store import BasinStore

runner = CliRunner()
# 4 tiles of 16 cells, each computed (these tests are about tiles; mirrored sweeps: see the end)
ARGS = ["--res", "8", "--chunk", "4", "--no-mirror", "-q"]
ROOT = Path(__file__).parent.parent


def coin(*args: str):
    return runner.invoke(app, ["basin", *map(str, args)])


def coin_ok(*args: str):
    result = coin(*args)
    assert result.exit_code == 0, result.output
    return result


def one_line_error(result, code: int = 2) -> str:
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.output
    err = result.stderr.strip()
    assert err.startswith("error:") and len(err.splitlines()) == 1, err
    return err


def read_basin(path: Path):
    return BasinStore.open(path).read()


def files_of(path: Path) -> dict[str, bytes]:
    """The files of a store but its records (conftest.store_files), or of a folder of stores
    (their records included)."""
    return store_files(path)


def assert_identical(a: Path, b: Path) -> None:
    """Every file of the two stores, byte for byte (metadata included), but their records."""
    fa, fb = files_of(a), files_of(b)
    assert sorted(fa) == sorted(fb)
    assert [k for k in fa if fa[k] != fb[k]] == []


def leftovers(folder: Path) -> list[str]:
    """Temporary files or folders anywhere under ``folder``."""
    return sorted(p.name for p in folder.rglob("*")
                  if ".creating-" in p.name or p.name.endswith((".partial", ".lock"))
                  or ".tmp-" in p.name or p.name.startswith(".coin-probe"))


@pytest.fixture(scope="module")
def clean(tmp_path_factory) -> Path:
    """An uninterrupted 8 x 8 store (4 tiles), computed once."""
    path = tmp_path_factory.mktemp("clean") / "clean.zarr"
    coin_ok(path, *ARGS)
    return path


def copy_store(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)  # its records with it: they are in its folder
    return dst


# -- integrity -----------------------------------------------------------------------------------
def _random_bytes(f: Path, other: Path) -> None:
    data = bytearray(f.read_bytes())
    data[4:20] = np.random.default_rng(1).integers(0, 256, 16, dtype=np.uint8).tobytes()
    f.write_bytes(bytes(data))


def _truncate(f: Path, other: Path) -> None:
    f.write_bytes(f.read_bytes()[:-7])


def _flip_bit(f: Path, other: Path) -> None:
    data = bytearray(f.read_bytes())
    data[len(data) // 2] ^= 0x10
    f.write_bytes(bytes(data))


def _swap(f: Path, other: Path) -> None:
    a, b = f.read_bytes(), other.read_bytes()
    f.write_bytes(b)
    other.write_bytes(a)


def _delete(f: Path, other: Path) -> None:
    f.unlink()


def _empty(f: Path, other: Path) -> None:
    f.write_bytes(b"")


DAMAGE = {  # kind -> (how, array damaged in tile (0, 1))
    "random bytes": (_random_bytes, "status"),
    "truncation": (_truncate, "settle_time"),
    "flipped bit": (_flip_bit, "quarter_turns"),
    "swapped chunk": (_swap, "quarter_turns"),
    "deleted chunk": (_delete, "quarter_turns"),
    "0-byte chunk": (_empty, "certainty"),
    "flipped bit in the digest": (_flip_bit, "done"),
}


@pytest.mark.parametrize("kind", list(DAMAGE))
def test_damaged_chunk_is_found_shown_and_repaired_bit_identically(tmp_path, clean, kind):
    how, name = DAMAGE[kind]
    path = copy_store(clean, tmp_path / "s.zarr")
    how(path / name / "c" / "0" / "1", path / name / "c" / "1" / "0")
    damaged = [[0, 1], [1, 0]] if kind == "swapped chunk" else [[0, 1]]

    # verify: exit 1, the tiles listed, no traceback
    result = coin("verify", path)
    assert result.exit_code == 1 and "Traceback" not in result.output, result.output
    assert "DAMAGED" in result.output and "tile (0, 1)" in result.output
    report = json.loads(coin("verify", path, "--json").stdout)
    assert report["intact"] is False and [d["tile"] for d in report["damaged"]] == damaged

    # stats: damaged tiles count as not computed, no invented label, and it says so
    stats = json.loads(coin_ok("stats", path, "--json").stdout)
    assert stats["tiles_damaged"] == damaged and stats["tiles_done"] == 4 - len(damaged)
    assert stats["not_computed"] == 16 * len(damaged) and stats["computed"] == 64 - stats[
        "not_computed"]
    assert all(row["n"] != NO_LABEL for row in stats["outcomes"])
    assert sum(row["count"] for row in stats["outcomes"]) == stats["labelled"]
    assert "damaged" in coin_ok("stats", path).output

    # render: a picture, and a note
    result = coin_ok("render", path, "-o", tmp_path / "s.png", "--dpi", "30")
    assert (tmp_path / "s.png").stat().st_size > 1000 and "damaged" in result.output

    # resume: recomputes those tiles, says which, and the store is the uninterrupted one
    said = " ".join(coin_ok(path, *ARGS).output.split())  # as wrapped to the terminal
    assert "damaged" in said and "(0, 1)" in said
    assert f"this run computed {len(damaged)} tile" in said
    assert coin("verify", path).exit_code == 0
    assert_identical(path, clean)


def test_metadata_damage_is_found_and_rewritten(tmp_path, clean):
    path = copy_store(clean, tmp_path / "s.zarr")
    (path / "vy" / "c" / "0").write_bytes(b"nonsense")  # a coordinate chunk
    meta = path / "status" / "zarr.json"
    meta.write_text(meta.read_text().replace("run status", "run state"))
    result = coin("verify", path)
    assert result.exit_code == 1 and "metadata vy/c/0" in result.output
    said = " ".join(coin_ok(path, *ARGS).output.split())  # as wrapped to the terminal
    assert "repaired" in said and "every tile is done already (4 tiles" in said
    assert_identical(path, clean)
    # a root that cannot be read: rebuilt from the copy of the parameters its tiles prove
    (path / "zarr.json").write_text("{ not json")
    result = coin("verify", path)
    assert result.exit_code == 1 and "zarr.json cannot be read" in result.output
    assert "Traceback" not in result.output
    assert "zarr.json" in coin_ok("stats", path).output
    coin_ok("render", path, "-o", tmp_path / "x.png", "--dpi", "30")
    assert "repaired" in coin_ok(path, *ARGS).output
    assert_identical(path, clean)
    # ... and with that copy gone too, no guessing: no traceback anywhere
    (path / "zarr.json").write_text("{ not json")
    (path / "done" / "zarr.json").write_text("{ not json")
    result = coin("verify", path)
    assert result.exit_code == 1 and "damaged" in result.output
    assert "Traceback" not in result.output
    for args in (["stats", path], ["render", path, "-o", tmp_path / "x.png"], [path, *ARGS]):
        assert "--overwrite" in one_line_error(coin(*args))


def test_tiles_are_written_as_zarr_writes_them(tmp_path):
    """Our chunk encoder against Zarr's own writing: every chunk file of a sweep with tiles cut
    by the grid's edge (5 x 3 cells in tiles of 4 x 2), rewritten through ``zarr`` from the
    values it reads back, is byte for byte the same file."""
    path = tmp_path / "edge.zarr"
    coin_ok(path, "--res", "5x3", "--chunk", "4x2", "--no-mirror", "-q")
    ours = files_of(path)
    import zarr

    group = zarr.open_group(str(path), mode="r+")
    for name in (*basin_layout.ARRAY_NAMES, "done"):
        arr = group[name].with_config({"write_empty_chunks": True})
        values = arr[:]
        shutil.rmtree(path / name / "c")
        arr[:] = values
    theirs = files_of(path)
    assert sorted(ours) == sorted(theirs) and any("/c/1/1" in k for k in ours)
    assert [k for k in ours if ours[k] != theirs[k]] == []


def test_a_partial_store_verifies_and_a_dead_writers_partial_file_goes(tmp_path, clean):
    path = copy_store(clean, tmp_path / "s.zarr")
    for name in (*basin_layout.ARRAY_NAMES, "done"):  # tile (1, 1) never finished ...
        (path / name / "c" / "1" / "1").unlink()
    orphan = path / "steps" / "c" / "1" / "1.0123abcd.partial"  # ... its writer killed
    orphan.write_bytes(b"half a chunk")
    said = " ".join(coin_ok("verify", path).output.split())  # as wrapped to the terminal
    assert "intact: 3 of 4 tiles" in said and "1 not computed" in said and "temporary" in said
    coin_ok(path, *ARGS)
    assert not orphan.exists()
    assert_identical(path, clean)


def test_stats_read_a_store_tile_by_tile(tmp_path, clean, monkeypatch):
    whole = coincli.basin_stats(coincli.open_basin(clean))
    reads = []
    real = BasinStore.read_tile

    def spy(self, tile):
        reads.append(tile)
        return real(self, tile)

    monkeypatch.setattr(BasinStore, "read_tile", spy)
    monkeypatch.setattr(BasinStore, "read", lambda *_: pytest.fail("whole arrays read"))
    streamed = coincli.basin_stats(clean)
    assert sorted(reads) == [(0, 0), (0, 1), (1, 0), (1, 1)]
    assert {**streamed, "cost": None} == {**whole, "cost": None}
    assert streamed["cost"]["cpu_seconds"] == whole["cost"]["cpu_seconds"]


def _zarr_template(attrs: dict, grid, folder: Path) -> dict[str, bytes]:
    """What Zarr itself writes for an empty store of ``grid`` (the reference for ours), read back
    from the files it wrote in ``folder``."""
    import warnings

    import zarr
    from zarr.codecs import Crc32cCodec, ZstdCodec

    def compressors():
        return [ZstdCodec(level=zarr_v3.ZSTD_LEVEL, checksum=False), Crc32cCodec()]

    mem = str(folder)
    group = zarr.open_group(mem, mode="w-", zarr_format=3, attributes=schema.root_attrs(attrs))
    for axis in grid.axes:
        arr = group.create_array(axis.name, shape=(axis.n,), chunks=(axis.n,), dtype="float64",
                                 fill_value=0.0, dimension_names=(axis.name,),
                                 compressors=compressors(),
                                 attributes={"units": axis.units, "long_name": axis.long_name,
                                             "cell_centres": schema.COORD_NOTE})
        arr[:] = axis.coords
    for name in basin_layout.ARRAY_NAMES:
        dtype, fill, array_attrs = schema.VARIABLES[name]
        group.create_array(name, shape=grid.shape, chunks=grid.chunk, dtype=dtype,
                           fill_value=fill, dimension_names=grid.dims, attributes=array_attrs,
                           compressors=compressors())
    group.create_array("done", shape=grid.tile_grid, chunks=(1, 1), dtype=basin_layout.DONE_DTYPE,
                       fill_value=0, dimension_names=schema.tile_dims(grid),
                       attributes=schema.done_attrs(attrs), compressors=compressors())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "consolidated metadata is not part of the v3 spec"
        zarr.consolidate_metadata(mem)
    return {f.relative_to(folder).as_posix(): f.read_bytes()
            for f in sorted(folder.rglob("*")) if f.is_file()}


@pytest.mark.parametrize("res", ["8", "5x3"])
def test_the_template_is_what_zarr_writes(tmp_path, res):
    """The store's metadata and coordinate chunks, made without Zarr, against Zarr's own:
    every file byte for byte (a grid cut by its tiles, and one that is not)."""
    path = tmp_path / "s.zarr"
    coin_ok(path, "--res", res, "--chunk", "4x2", "--no-mirror", "-q")
    view = BasinStore.open(path)
    ours = basin_layout.template(view.attrs, view.grid)
    theirs = _zarr_template(view.attrs, view.grid, tmp_path / "zarr.zarr")
    assert sorted(ours) == sorted(theirs)
    assert [k for k in ours if ours[k] != theirs[k]] == []


def test_reads_are_what_zarr_reads(clean):
    """Every array as this module reads it (tile by tile, through decode_chunk) against Zarr's
    reading of the same store, value for value and dtype for dtype."""
    import zarr

    group = zarr.open_group(str(clean), mode="r")
    basin = BasinStore.open(clean).read()
    assert basin.done.all()
    for name in basin_layout.ARRAY_NAMES:
        theirs = group[name][:]
        assert basin.arrays[name].dtype == theirs.dtype, name
        assert basin.arrays[name].tobytes() == theirs.tobytes(), name
    view = BasinStore.open(clean)
    flags, unreadable = view.digests()
    assert not unreadable and (flags == group["done"][:]).all()
    assert dict(group.attrs) == view.attrs


def test_a_store_is_one_folder_that_zarr_and_xarray_open_as_before(tmp_path, clean):
    """Everything a store owns is in its folder: its records (each tile's cost, the runs) in
    out.zarr/.coin/, nothing beside it once made; moved, it keeps them. Zarr and xarray open
    it through its consolidated metadata, which list its arrays only; verify is silent on
    them."""
    import warnings

    import xarray as xr
    import zarr

    assert sorted(p.name for p in clean.parent.iterdir()) == [clean.name]
    assert sorted(p.name for p in (clean / RECORDS).iterdir()) == [
        "runs.jsonl", "tile_0_0.json", "tile_0_1.json", "tile_1_0.json", "tile_1_1.json"]
    moved = tmp_path / "elsewhere" / "moved.zarr"
    moved.parent.mkdir()
    shutil.copytree(clean, tmp_path / "copy.zarr")
    (tmp_path / "copy.zarr").rename(moved)
    assert BasinStore(moved).runs() == BasinStore(clean).runs() != []
    assert np.isfinite(BasinStore.open(moved).costs()[0]).all()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        group = zarr.open_group(str(moved), mode="r")
        assert RECORDS not in group and sorted(group.array_keys()) == sorted(
            [*basin_layout.ARRAY_NAMES, "done", "vy", "vphi"])
        assert xr.open_zarr(moved)["quarter_turns"].shape == (8, 8)
    assert f"{moved}: intact: 4 of 4 tiles done" in coin_ok("verify", moved).output


def test_a_store_of_0_10_keeps_its_records_beside_it_and_resumes_to_the_same_store(tmp_path,
                                                                                  clean):
    """coincli 0.10.0 kept a store's records beside it (out.zarr.cost/): they are read and
    written there while they are (so processes of both versions claim in one place), the store
    resumes to the uninterrupted one; replaced (--overwrite), its new records are in it and the
    old ones gone."""
    path = copy_store(clean, tmp_path / "s.zarr")
    legacy = tmp_path / "s.zarr.cost"
    (path / RECORDS).rename(legacy)  # as 0.10.0 left it
    (path / "done" / "c" / "1" / "1").unlink()
    assert records_dir(path) == legacy and len(BasinStore(path).runs()) == 1
    coin_ok(path, *ARGS)
    assert not (path / RECORDS).exists()
    assert len(BasinStore(path).runs()) == 2 and len((legacy / "runs.jsonl").read_text()
                                                      .splitlines()) == 2
    assert np.isfinite(BasinStore.open(path).costs()[0]).all()
    assert_identical(path, clean)
    coin_ok(path, *ARGS, "--overwrite")
    assert not legacy.exists() and records_dir(path) == path / RECORDS
    assert len(BasinStore(path).runs()) == 1
    assert_identical(path, clean)


def test_a_sweep_does_not_import_zarr(tmp_path):
    """`coin basin` writes and checks its store without Zarr (a quarter of a second to import),
    with numcodecs' own Zstd codec; Zarr reads the store."""
    code = ("import sys; from coincli.cli import run\n"
            "assert run(['basin', sys.argv[1], '--res', '8', '--chunk', '4', '-q']) == 0\n"
            "assert 'zarr' not in sys.modules, 'zarr imported'\n"
            "import numcodecs, zarr\n"
            "assert 'numcodecs.zstd' in sys.modules\n"
            "assert zarr.open_group(sys.argv[1], mode='r')['quarter_turns'][:].shape == (8, 8)\n")
    done = subprocess.run([sys.executable, "-c", code, str(tmp_path / "s.zarr")], cwd=ROOT,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]


# -- several processes ---------------------------------------------------------------------------
def start(*args) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "coincli", "basin", *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=default_signals, cwd=ROOT)


def computed(output: str) -> int:
    if "done already" in output:
        return 0
    return int(output.split("this run computed ")[1].split(" tile")[0])


def test_two_processes_started_together_share_a_new_store(tmp_path):
    args = ["--res", "24", "--chunk", "4", "--threads", "1", "-q"]  # 36 tiles
    one = tmp_path / "one.zarr"
    reference = threading.Thread(target=lambda: coin_ok(one, *args))
    reference.start()  # one process's store, meanwhile
    path = tmp_path / "s.zarr"
    procs = [start(path, *args) for _ in range(2)]
    outs = [p.communicate(timeout=120) for p in procs]
    reference.join()
    for p, (_, err) in zip(procs, outs, strict=True):
        assert p.returncode == 0, err
        assert "Traceback" not in err
    counts = [computed(out) for out, _ in outs]
    assert sum(counts) == 36, counts  # every tile computed once: none twice
    runs = BasinStore.open(path).costs()[1]
    assert sorted(r["tiles"] for r in runs if r["tiles"]) == sorted(c for c in counts if c)
    assert leftovers(tmp_path) == [] and not BasinStore(path).claims_dir.exists()
    assert_identical(path, one)


def test_racing_creations_end_in_one_store(tmp_path):
    plan = coincli.plan_sweep(coincli.load_preset("paper"), res=8, chunk=4, mirror=False)
    path = tmp_path / "s.zarr"
    barrier = threading.Barrier(4)
    errors = []

    def create():
        barrier.wait()
        try:
            BasinStore(path).create_or_resume(plan.attrs, plan.grid)
        except Exception as exc:  # noqa: BLE001
            errors.append(exc)

    threads = [threading.Thread(target=create) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert BasinStore.open(path).check().intact and leftovers(tmp_path) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.zarr"]  # its records in it
    assert (path / RECORDS).is_dir()


def _claim(path: Path, tile, pid: int, age: float = 0.0) -> Path:
    folder = BasinStore(path).claims_dir
    folder.mkdir(parents=True, exist_ok=True)
    f = folder / claims_io.claim_name(tile)
    f.write_text(json.dumps({"host": claims_io.HOST, "pid": pid, "token": "x"}))
    if age:
        os.utime(f, (time.time() - age, time.time() - age))
    return f


def test_stale_claims_are_taken_over_and_live_ones_waited_for(tmp_path, clean):
    plan = coincli.plan_sweep(coincli.load_preset("paper"), res=8, chunk=4, mirror=False)
    path = tmp_path / "s.zarr"
    BasinStore(path).create_or_resume(plan.attrs, plan.grid)
    dead = subprocess.Popen(["true"])
    dead.wait()
    alive = subprocess.Popen(["sleep", "60"])
    try:
        _claim(path, (0, 0), dead.pid)  # its owner is gone: taken over at once
        _claim(path, (0, 1), alive.pid, age=claims_io.STALE + 5)  # no heartbeat for too long
        held = _claim(path, (1, 1), alive.pid)  # a live owner: waited for
        seen = []

        def owner_lets_go(update):
            seen.append(update.tiles_done)
            if update.tiles_done == 3:
                assert held.exists()  # nobody took a live claim
                held.unlink()  # its owner stops without finishing: the tile is ours

        report = coincli.sweep(plan, path, threads=1, progress=owner_lets_go)
    finally:
        alive.kill()
        alive.wait()
    assert report.complete and report.tiles_computed == 4 and seen == [1, 2, 3, 4]
    assert not BasinStore(path).claims_dir.exists()
    assert_identical(path, clean)


def test_a_tile_finished_elsewhere_is_not_computed_again(tmp_path, clean):
    plan = coincli.plan_sweep(coincli.load_preset("paper"), res=8, chunk=4, mirror=False)
    path = copy_store(clean, tmp_path / "s.zarr")
    (path / "done" / "c" / "1" / "1").rename(tmp_path / "digest")  # (1, 1) looks unfinished
    held = _claim(path, (1, 1), os.getppid())  # ... and a live process holds it

    def finish_it():  # that process finishes it and lets go
        time.sleep(0.6)
        (tmp_path / "digest").rename(path / "done" / "c" / "1" / "1")
        held.unlink()

    threading.Thread(target=finish_it).start()
    report = coincli.sweep(plan, path, threads=1)
    assert report.complete and report.tiles_computed == 0 and report.tiles_elsewhere == 1
    assert_identical(path, clean)


# -- interrupts ----------------------------------------------------------------------------------
# tile (0, 0) is quick (low vy settles at once), tile (1, 0) takes seconds (paper's method,
# little damping)
STUCK = ["--preset", "paper-method", "--stop-on-settle", "--t-end", "20", "--c", "0.02",
         "--res", "2", "--chunk", "1x2", "--vy", "0.05:2", "--vphi", "-1:1", "--threads", "2",
         "-q"]


def test_second_ctrl_c_stops_a_stuck_sweep_at_once(tmp_path):
    reference = tmp_path / "reference.zarr"
    done_ref = threading.Thread(target=lambda: coin_ok(reference, *STUCK))
    done_ref.start()  # the uninterrupted store, meanwhile
    path = tmp_path / "s.zarr"
    proc = start(path, *STUCK)
    claim = BasinStore(path).claims_dir / "tile_1_0"
    end = time.monotonic() + 60
    # the slow tile is being computed, and the quick one, beside it, is done
    while not (claim.exists() and BasinStore.open(path).has_digest((0, 0))):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < end, "the slow tile never started"
        time.sleep(0.005)
    lines = []  # (arrival, line) of its stderr

    def read():
        for line in proc.stderr:
            lines.append((time.monotonic(), line))

    reader = threading.Thread(target=read)
    reader.start()
    time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    second = time.monotonic()
    proc.wait(timeout=60)
    exited_after = time.monotonic() - second
    reader.join()
    err = "".join(line for _, line in lines)
    assert proc.returncode == 130, err
    stopped_after = next(t for t, line in lines if line.startswith("stopped:")) - second
    # the sweep stops at once; the interpreter's exit after it (LLVM's teardown) is not ours,
    # and takes up to a second or so on a loaded machine
    assert stopped_after < 2.0, f"took {stopped_after:.1f} s to stop"
    assert exited_after < 5.0, f"took {exited_after:.1f} s to exit"
    assert "Traceback" not in err
    # the quick tile is kept, the stuck one left no trace
    assert BasinStore.open(path).check().done.astype(int).tolist() == [[1], [0]]
    assert [p for p in path.rglob("*") if p.match("*/c/1/0*")] == []
    assert leftovers(tmp_path) == [] and not BasinStore(path).claims_dir.exists()
    done_ref.join()
    coin_ok(path, *STUCK)  # resume
    assert_identical(path, reference)


def test_keyboard_interrupt_in_the_api_stops_the_tiles_in_flight(tmp_path):
    scene = coincli.load_preset("paper-method").with_overrides(stop_on_settle=True, t_end=20.0,
                                                              c=0.02)
    plan = coincli.plan_sweep(scene, res=2, chunk=(1, 2), vy=(0.05, 2.0), vphi=(-1.0, 1.0))
    path = tmp_path / "s.zarr"

    sent = []

    def send():
        sent.append(time.monotonic())
        signal.raise_signal(signal.SIGINT)

    def interrupt(update):  # as a notebook's interrupt arrives in the main thread
        threading.Timer(0.3, send).start()

    with sigint_raises():
        # two threads: the slow tile (more energy, so first) and the quick one side by side
        report = coincli.sweep(plan, path, threads=2, progress=interrupt)
    # timed from the interrupt, not from the start (loading the kernels varies with the load)
    assert time.monotonic() - sent[0] < 1.5  # not the seconds the slow tile takes
    assert report.interrupted and report.tiles_done == 1
    assert BasinStore.open(path).check().done.astype(int).tolist() == [[1], [0]]
    assert [p for p in path.rglob("*") if p.match("*/c/1/0*")] == []


# -- estimates -----------------------------------------------------------------------------------
def test_estimate_comes_from_a_fixed_pilot():
    plan = coincli.plan_sweep(coincli.load_preset("paper"), res=512)
    cells = pilot_cells(plan.grid)
    assert cells == pilot_cells(plan.grid) and len(set(cells)) == 24
    rows = np.array([i for i, _ in cells])
    assert (rows < 256).any() and (rows >= 256).any()  # spread over the grid
    est = coincli.estimate_sweep(plan, threads=2)
    # vphi sweeps -20:20 in whole tiles: half the cells are mirror images, computed for free
    assert est.cells == 512 * 512 // 2 and est.pilot_cells == 24 and not est.at_least
    assert est.seconds == pytest.approx(est.cpu_per_cell * est.cells / est.workers)
    assert 1e-6 < est.cpu_per_cell < 0.05
    half = coincli.estimate_sweep(plan, threads=1, cells=1000, budget=0.0)  # one cell timed
    assert half.pilot_cells == 1 and half.cells == 1000


def test_a_sweep_of_weeks_is_refused_without_yes(tmp_path, monkeypatch):
    from coincli.cli.basin import sweep as basin_cmd

    # the real pilot on a real grid; the limit lowered from 12 h so that no machine is fast
    # enough to start this sweep (4.3e9 cells: 10 h on 2 fast cores)
    monkeypatch.setattr(basin_cmd, "MAX_SECONDS", 600.0)
    path = tmp_path / "huge.zarr"
    err = one_line_error(coin(path, "--res", "65536", "-q"))
    for words in ("would take", "--yes", "--res", "machines"):
        assert words in err, err
    assert list(tmp_path.iterdir()) == []  # nothing created


def test_estimates_are_printed_and_the_limit_lifted_by_yes(tmp_path, monkeypatch):
    def fake(plan, threads=None, *, workers=None, scheduler=None, cells=None, budget=1.0):
        n = plan.grid.n_cells if cells is None else cells
        return coincli.SweepEstimate(seconds, n, 0.01, 2, 24, False)

    monkeypatch.setattr(engine, "estimate_sweep", fake)
    seconds = 300.0
    said = " ".join(coin_ok(tmp_path / "a.zarr", *ARGS).output.split())
    assert "estimate: about 5 min on 2 cores for 64 cells" in said
    seconds = 2e5
    assert "would take about 2.3 days" in one_line_error(coin(tmp_path / "b.zarr", *ARGS))
    coin_ok(tmp_path / "b.zarr", *ARGS, "--yes")
    seconds = 10.0
    assert "estimate:" not in coin_ok(tmp_path / "c.zarr", *ARGS).output


# -- failing disks -------------------------------------------------------------------------------
class Disk:
    """Make writes under ``folder`` fail with ``code``, as a read-only mount (EROFS), a full
    disk (ENOSPC) or a folder we may not write (EACCES) does, from the ``after``-th write on."""

    def __init__(self, monkeypatch, folder: Path, code: int, after: int = 0, match: str = ""):
        self.folder, self.code, self.after, self.match = str(folder), code, after, match
        self.count = 0
        real_open, real_os_open = io.open, os.open

        def hit(path, writing: bool) -> bool:
            p = os.fspath(path) if isinstance(path, str | os.PathLike) else ""
            if writing and p.startswith(self.folder) and self.match in p:
                self.count += 1
                return self.count > self.after
            return False

        def fail(path):
            raise OSError(self.code, os.strerror(self.code), os.fspath(path))

        def fake_open(file, mode="r", *args, **kwargs):
            if hit(file, any(c in mode for c in "wax+")):
                fail(file)
            return real_open(file, mode, *args, **kwargs)

        def fake_os_open(path, flags, *args, **kwargs):
            if hit(path, bool(flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT))):
                fail(path)
            return real_os_open(path, flags, *args, **kwargs)

        def guard(real):
            def fake(src, *args, **kwargs):
                if hit(src, True):
                    fail(src)
                return real(src, *args, **kwargs)
            return fake

        monkeypatch.setattr(io, "open", fake_open)
        monkeypatch.setattr("builtins.open", fake_open)
        monkeypatch.setattr(os, "open", fake_os_open)
        for name in ("mkdir", "replace", "rename"):
            monkeypatch.setattr(os, name, guard(getattr(os, name)))


@pytest.mark.parametrize("code", [errno.EROFS, errno.EACCES])
def test_outputs_that_cannot_be_written_fail_in_one_line_before_work(tmp_path, clean,
                                                                     monkeypatch, code):
    ro = tmp_path / "ro"
    ro.mkdir()
    partial = copy_store(clean, ro / "partial.zarr")
    (partial / "done" / "c" / "1" / "1").unlink()
    before = files_of(partial)
    monkeypatch.setattr(engine, "load_kernels",
                        lambda *_: pytest.fail("work started on a disk it cannot write"))
    Disk(monkeypatch, ro, code)
    reason = os.strerror(code).lower()
    assert reason in one_line_error(coin(ro / "new.zarr", *ARGS)).lower()  # a new store
    assert reason in one_line_error(coin(partial, *ARGS)).lower()  # resuming one
    assert files_of(partial) == before
    assert "cannot write" in one_line_error(coin("render", clean, "-o", ro / "b.png"))
    assert "cannot write" in one_line_error(coin("stats", clean, "--csv", ro / "b.csv"))
    monkeypatch.setattr("coincli.accuracy.run_study",
                        lambda *a, **k: pytest.fail("computed before checking its outputs"))
    result = runner.invoke(app, ["accuracy", "--quick", "--res", "2", "-o", str(ro / "a.png")])
    assert "cannot write" in one_line_error(result)
    assert sorted(p.name for p in ro.iterdir()) == ["partial.zarr"]
    assert leftovers(tmp_path) == []


def test_disk_full_while_a_store_is_created(tmp_path, monkeypatch):
    Disk(monkeypatch, tmp_path, errno.ENOSPC, match=".creating-")
    err = one_line_error(coin(tmp_path / "s.zarr", *ARGS))
    assert "no space left on device" in err
    assert list(tmp_path.iterdir()) == []  # no store, no temporary store, no lock


def test_disk_full_in_the_middle_of_a_sweep(tmp_path, clean, monkeypatch):
    path = tmp_path / "s.zarr"
    with monkeypatch.context() as m:
        Disk(m, tmp_path, errno.ENOSPC, after=10, match=".partial")  # chunk writes
        err = one_line_error(coin(path, *ARGS, "--threads", "1"))
    assert "no space left on device" in err
    assert leftovers(tmp_path) == [] and not BasinStore(path).claims_dir.exists()
    assert BasinStore.open(path).check().intact  # what was written is whole
    coin_ok(path, *ARGS)  # space again: resume
    assert_identical(path, clean)


# -- mirrored sweeps -----------------------------------------------------------------------------
# vphi over -20:20 in whole tiles: tiles (i, 0) are computed, tiles (i, 1) are their mirror images
MIRRORED = ["--res", "8", "--chunk", "4", "-q"]


@pytest.fixture(scope="module")
def mirrored(tmp_path_factory) -> Path:
    """The store of `clean`, made with the mirror: 2 tiles computed, 2 mirrored."""
    path = tmp_path_factory.mktemp("mirrored") / "m.zarr"
    coin_ok(path, *MIRRORED)
    return path


def test_a_mirrored_store_has_the_labels_of_the_full_one(mirrored, clean):
    half, full = read_basin(mirrored), read_basin(clean)
    for name in ("quarter_turns", "status", "certainty", "rung", "steps"):
        np.testing.assert_array_equal(half.arrays[name], full.arrays[name], err_msg=name)
    np.testing.assert_allclose(half.arrays["settle_time"], full.arrays["settle_time"], rtol=1e-5)
    assert half.attrs["sweep"]["mirror"] == ["vphi"] and full.attrs["sweep"]["mirror"] is None
    costs = {t: json.loads((records_dir(mirrored) / f"tile_{t}.json").read_text())
             for t in ("0_0", "0_1", "1_0", "1_1")}
    assert costs["0_1"]["mirror_of"] == [0, 0] and costs["1_1"]["mirror_of"] == [1, 0]
    assert costs["0_1"]["cpu_seconds"] == 0.0 < costs["0_0"]["cpu_seconds"]
    assert "mirror_of" not in costs["0_0"]


def test_a_damaged_or_lost_tile_is_recomputed_with_its_mirror(tmp_path, mirrored):
    path = copy_store(mirrored, tmp_path / "m.zarr")
    (path / "done" / "c" / "1" / "1").unlink()  # mirror tile (1, 1) looks unfinished
    _flip_bit(path / "quarter_turns" / "c" / "0" / "0", None)  # computed tile (0, 0) damaged
    said = " ".join(coin_ok(path, *MIRRORED).output.split())  # as one line, however wrapped
    assert "this run computed 4 tiles" in said and "mirror images" in said
    assert_identical(path, mirrored)


def test_a_store_is_not_resumed_with_the_other_mirror_setting(tmp_path, clean, mirrored):
    for source, args in ((clean, MIRRORED), (mirrored, ARGS)):
        path = copy_store(source, tmp_path / f"{source.stem}.zarr")
        assert "mirror" in one_line_error(coin(path, *args))
        assert files_of(path) == files_of(source)


def test_a_tile_binds_the_parameters_it_was_computed_with(tmp_path, monkeypatch):
    """Another process overwrites the store with other parameters while this sweep computes
    (here: just before its first tile is written). This sweep's tiles bind the parameters
    they were computed with, not those the store says when they are written: under the new
    parameters they do not verify, and are computed again, never taken for theirs."""
    path = tmp_path / "s.zarr"
    base = coincli.load_preset("paper")
    mine = api.plan_sweep(base, res=16, chunk=8)
    theirs = api.plan_sweep(base.with_overrides(k=400.0), res=16, chunk=8)
    write = BasinStore.write_tile
    overwritten = []

    def overwrite_first(*args, **kwargs):
        if not overwritten:
            BasinStore(path).create_or_resume(theirs.attrs, theirs.grid, overwrite=True)
            overwritten.append(True)
        return write(*args, **kwargs)

    monkeypatch.setattr(BasinStore, "write_tile", overwrite_first)
    api.sweep(mine, path, threads=1)
    assert overwritten
    # the store is theirs now
    assert BasinStore.open(path).check().attrs["parameters"]["foundation"]["k"] == 400.0
    # and holds none of this sweep's tiles as theirs
    assert not BasinStore.open(path).check().done.any()
    monkeypatch.setattr(BasinStore, "write_tile", write)
    api.sweep(theirs, path, threads=1)  # the resume computes every tile again
    assert BasinStore.open(path).check().done.all()
    reference = tmp_path / "r.zarr"
    api.sweep(theirs, reference, threads=1)
    assert np.array_equal(read_basin(path).arrays["quarter_turns"],
                          read_basin(reference).arrays["quarter_turns"])


def test_a_number_written_as_an_int_or_a_float_is_one_sweep(tmp_path):
    """k=400 and k=400.0 are the same scene: a store swept with the one is complete for the
    other (one parameters digest), not damaged tile by tile."""
    path = tmp_path / "s.zarr"
    base = coincli.load_preset("paper")
    api.sweep(api.plan_sweep(base.with_overrides(k=400), res=16, chunk=8), path, threads=1)
    report = api.sweep(api.plan_sweep(base.with_overrides(k=400.0), res=16, chunk=8), path,
                       threads=1)
    assert report.tiles_before == report.tiles_total and not report.damaged


def test_a_store_of_an_earlier_version_with_the_same_labels_resumes_as_its_own(tmp_path):
    """A store written by 0.9.0 (the kernels, the ladder and the layout unchanged since:
    schema.RESUMES) is resumed in its own version: its tiles and the new ones verify, and the
    store is the one 0.9.0 would have finished; a store of a version not in RESUMES is another
    sweep."""
    import dataclasses

    plan = coincli.plan_sweep(coincli.load_preset("paper"), res=8, chunk=4, mirror=False)
    old = dataclasses.replace(plan, attrs=schema.root_attrs({**plan.attrs, "version": "0.9.0"}))
    whole, part = tmp_path / "whole.zarr", tmp_path / "part.zarr"
    coincli.sweep(old, whole, threads=1)
    stop = threading.Event()
    coincli.sweep(old, part, threads=1, progress=lambda _: stop.set(), stop=stop)
    assert 0 < BasinStore.open(part).check().tiles_done < 4
    report = coincli.sweep(plan, part, threads=1)  # this version resumes it
    assert report.complete and BasinStore.open(part).check().intact
    assert BasinStore.open(part).attrs["version"] == "0.9.0"
    assert_identical(part, whole)
    older = dataclasses.replace(plan, attrs=schema.root_attrs({**plan.attrs, "version": "0.8.0"}))
    coincli.sweep(older, tmp_path / "older.zarr", threads=1)
    with pytest.raises(coincli.ParameterError, match="coincli version = 0.8.0 in the store"):
        coincli.sweep(plan, tmp_path / "older.zarr", threads=1)
