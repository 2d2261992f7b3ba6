"""From a cell of a basin back to its throw: `coin basin inspect` replays a cell to its stored
label, the nearest cell and --cell, one-line errors, `coin basin render --mark` and
coincli.cell_scene."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import coincli
from coincli.cli import app
from coincli.enums import Certainty
from coincli.params import ParameterError, state_array
from coincli.stores.cells import cell_state, mirror_source

runner = CliRunner()
RES, CHUNK = 16, 8


def coin(*args: str):
    return runner.invoke(app, ["basin", *map(str, args)])


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    """Three small stores: the paper's default sweep, the thick coin's, a phi0-vy sweep (its
    mirror over phi0: half its cells are mirror images)."""
    root = tmp_path_factory.mktemp("inspect")
    paper = coincli.load_preset("paper")
    made = {
        "paper": coincli.basin(paper, res=RES, chunk=CHUNK, store=root / "paper.zarr"),
        "thick": coincli.basin(coincli.load_preset("thick"), res=RES, chunk=CHUNK,
                               store=root / "thick.zarr"),
        "phi0-vy": coincli.basin(paper, phi0=(-np.pi, np.pi), vy=(0.05, 2.0), vphi=0.0,
                                 res=RES, chunk=CHUNK, store=root / "phi.zarr"),
    }
    return {name: (root / f"{'phi' if name == 'phi0-vy' else name}.zarr", ds)
            for name, ds in made.items()}


def certain_cells(ds, count: int = 20) -> list[tuple[int, int]]:
    """``count`` certain cells spread over the map (always the same ones)."""
    cells = np.argwhere(ds.certainty.values == Certainty.CERTAIN)
    assert len(cells) >= count
    picks = np.linspace(0, len(cells) - 1, count).round().astype(int)
    return [tuple(map(int, cells[k])) for k in picks]


@pytest.mark.parametrize("name", ["paper", "thick", "phi0-vy"])
def test_inspect_json_replays_twenty_certain_cells_to_their_stored_label(stores, name):
    path, ds = stores[name]
    for i, j in certain_cells(ds):
        result = coin("inspect", path, "--cell", f"{i},{j}", "--json")
        assert result.exit_code == 0, result.output
        out = json.loads(result.stdout)
        stored = int(ds.quarter_turns.values[i, j])
        assert out["cell"] == [i, j]
        assert out["stored"]["quarter_turns"] == stored
        assert out["replayed"]["quarter_turns"] == stored
        assert out["stored"]["certainty"] == out["replayed"]["certainty"] == "certain"
        assert out["stored"]["rung"] == int(ds.rung.values[i, j])
        assert out["matches"] is True and out["ladder_matches"] is True
        # the exact initial state of the cell: the coordinates, bit for bit
        for d in ds.quarter_turns.dims:
            k = (i, j)[ds.quarter_turns.dims.index(d)]
            if mirror_source(coincli.basin_attrs(ds), (i, j)) is None:
                assert out["values"][d] == float(ds[d].values[k])


def test_the_printed_command_reproduces_the_label(stores):
    path, ds = stores["thick"]
    i, j = certain_cells(ds, 3)[1]
    out = json.loads(coin("inspect", path, "--cell", f"{i},{j}", "--json").stdout)
    words = out["command"].split()
    assert words[:4] == ["coin", "simulate", "--preset", "thick"]
    again = runner.invoke(app, [*words[1:], "--no-rrd", "--json"])
    assert again.exit_code == 0, again.output
    assert json.loads(again.stdout)["quarter_turns"] == out["stored"]["quarter_turns"]


def test_nearest_cell_by_value_and_the_text_output(stores):
    path, ds = stores["paper"]
    vy, vphi = ds.vy.values, ds.vphi.values
    # a point a third of a cell away from cell (5, 11): that cell is the nearest
    result = coin("inspect", path, "--vy", vy[5] + (vy[1] - vy[0]) / 3,
                  "--vphi", vphi[11] - (vphi[1] - vphi[0]) / 3)
    assert result.exit_code == 0, result.output
    assert "cell (5, 11)" in result.stdout
    assert "the same" in result.stdout and "coin simulate --vy" in result.stdout
    by_index = json.loads(coin("inspect", path, "--cell", "5,11", "--json").stdout)
    by_value = json.loads(coin("inspect", path, "--vy", vy[5], "--vphi", vphi[11],
                               "--json").stdout)
    assert by_index["cell"] == by_value["cell"] == [5, 11]


@pytest.mark.parametrize(("args", "message"), [
    (["--vy", "1"], "give both swept axes (vy and vphi)"),
    (["--phi0", "1", "--vy", "1"], "phi0 is not swept in this basin"),
    (["--vy", "5", "--vphi", "0"], "vy = 5 is outside the swept range 0.05 to 2"),
    (["--vy", "1", "--vphi", "-20.5"], "vphi = -20.5 is outside the swept range"),
    (["--cell", "3,16"], "cell index 16 along vphi is outside the grid: 0 to 15"),
    (["--cell", "3"], "a cell index is I,J"),
    (["--cell", "1,1", "--vy", "1"], "by its index or by its values, not both"),
    (["--vy", "abc", "--vphi", "1"], "'abc' is not a number"),
])
def test_bad_cells_are_one_line_errors(stores, args, message):
    path, _ = stores["paper"]
    result = coin("inspect", path, *args)
    assert result.exit_code == 2
    assert message in result.output
    assert "Traceback" not in result.output and len(result.output.strip().splitlines()) == 1


def test_a_cell_not_computed_is_replayed_but_not_claimed(stores, tmp_path):
    path, _ = stores["paper"]
    import shutil

    partial = tmp_path / "partial.zarr"
    shutil.copytree(path, partial)
    for done in (partial / "done" / "c" / "1").rglob("*"):  # the tiles (1, 0) and (1, 1)
        if done.is_file():
            done.unlink()
    result = coin("inspect", partial, "--cell", "12,3", "--json")
    assert result.exit_code == 1
    out = json.loads(result.stdout)
    assert out["stored"]["computed"] is False and out["matches"] is False
    assert out["replayed"]["quarter_turns"] is not None


def test_a_replay_that_differs_exits_1(stores, monkeypatch):
    """Fault injection: the replay gives another label."""
    from coincli.stores import cells

    path, ds = stores["paper"]
    real = cells.replay

    def off_by_two(scene, **kw):
        run = real(scene, **kw)
        run.quarter_turns += 2
        return run

    monkeypatch.setattr(cells, "replay", off_by_two)
    i, j = certain_cells(ds, 1)[0]
    result = coin("inspect", path, "--cell", f"{i},{j}")
    assert result.exit_code == 1
    assert "mismatch" in result.output


def test_spawn_without_a_display_still_replays_and_exits_1(stores, tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    path, ds = stores["paper"]
    rrd = tmp_path / "cell.rrd"
    result = coin("inspect", path, "--cell", "4,4", "--spawn", "--rrd", rrd)
    assert result.exit_code == 1
    assert "no display" in result.output and "the same" in result.output
    assert rrd.is_file() and rrd.stat().st_size > 0


def test_cell_scene_from_a_dataset_and_from_a_path(stores):
    path, ds = stores["phi0-vy"]
    scene = coincli.cell_scene(ds, phi0=0.5, vy=1.0)
    i = int(np.argmin(np.abs(ds.phi0.values - 0.5)))
    j = int(np.argmin(np.abs(ds.vy.values - 1.0)))
    assert np.array_equal(state_array(scene), cell_state(coincli.basin_attrs(ds), (i, j)))
    assert scene == coincli.cell_scene(path, cell=(i, j))
    run = coincli.simulate(scene, engine="numba")
    assert run.quarter_turns == int(ds.quarter_turns.values[i, j])
    # a cell computed itself starts exactly at its coordinates
    k = next(c for c in range(RES) if mirror_source(coincli.basin_attrs(ds), (c, j)) is None)
    assert coincli.cell_scene(ds, cell=(k, j)).initial.phi0 == float(ds.phi0.values[k])
    with pytest.raises(ParameterError, match="vphi is not swept"):
        coincli.cell_scene(ds, vphi=1.0, vy=1.0)
    with pytest.raises(ParameterError, match="outside the swept range"):
        coincli.cell_scene(ds, phi0=4.0, vy=1.0)


def test_render_mark_draws_a_circle_where_the_throw_is(stores, tmp_path):
    from PIL import Image

    path, ds = stores["paper"]
    plain, marked = tmp_path / "plain.png", tmp_path / "marked.png"
    assert coin("render", path, "-o", plain).exit_code == 0
    result = coin("render", path, "-o", marked, "--mark", "1.0,-10")
    assert result.exit_code == 0, result.output
    a = np.asarray(Image.open(plain).convert("RGB"), dtype=int)
    b = np.asarray(Image.open(marked).convert("RGB"), dtype=int)
    rows, cols = np.nonzero(np.abs(a - b).sum(axis=2))
    assert rows.size  # the mark is drawn ...
    # ... in one small place: where vy = 1 (about half-way across), vphi = -10 (a quarter up)
    h, w = a.shape[:2]
    assert rows.max() - rows.min() < h / 15 and cols.max() - cols.min() < w / 15
    assert 0.35 < cols.mean() / w < 0.55 and 0.55 < rows.mean() / h < 0.8
    assert (b[rows, cols] > 240).all(axis=1).any() and (b[rows, cols] < 40).all(axis=1).any()
    for bad, message in ((["--mark", "3,0"], "vy = 3 is outside the swept range"),
                         (["--mark", "1"], "is not V,W")):
        result = coin("render", path, "-o", tmp_path / "x.png", *bad)
        assert result.exit_code == 2 and message in result.output
    # the API: marks=
    out = tmp_path / "api.png"
    coincli.render_basin(ds, out, marks=[(1.0, -10.0)])
    assert np.array_equal(np.asarray(Image.open(out).convert("RGB"), dtype=int), b)
