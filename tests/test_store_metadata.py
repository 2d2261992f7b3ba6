"""The basin store's metadata under damage and under users' edits (issues 28.2, 29.5, 28.9):

- every tile's digest binds the parameters it was computed with, and the sweep's attributes are
  kept in three copies (the group's, and the ``done`` array's in the consolidated metadata and
  in done/zarr.json), each with its digest. A value changed in any metadata file is found by
  `coin basin verify` and `coin basin stats`, and a resume rebuilds it from the copy the tiles
  prove, ending bit-identical to an uninterrupted run; a resume with the changed value as its
  parameters is refused, never served the old tiles; what nothing proves is refused in one line;
- what a user adds with zarr-python (an attribute, an array) is theirs: kept, never damage;
- `coin basin stats` on a partial store says its fractions are of the tiles computed so far;
- a read-only store is a one-line error naming it.
"""

from __future__ import annotations

import errno
import json
import warnings
from pathlib import Path

import pytest
from test_store import (
    ARGS,
    Disk,
    assert_identical,
    coin,
    coin_ok,
    copy_store,
    files_of,
    one_line_error,
)

import coincli
from coincli import api
from coincli.stores import basin_schema as schema
from coincli.stores.basin_layout import tile_digest
from coincli.stores.basin_store import BasinStore


@pytest.fixture(scope="module")
def clean(tmp_path_factory) -> Path:
    """An uninterrupted 8 x 8 store (4 tiles), computed once (test_store's, for this module)."""
    path = tmp_path_factory.mktemp("clean") / "clean.zarr"
    coin_ok(path, *ARGS)
    return path


def said(result) -> str:
    """A command's output as one line, however the terminal wrapped it."""
    return " ".join(result.output.split())


def edit(path: Path, key: str, change) -> None:
    """Change the parsed metadata file ``key`` of a store with ``change(document)``."""
    f = path / key
    document = json.loads(f.read_text())
    change(document)
    f.write_text(json.dumps(document, indent=2))


def sweep_attrs(document: dict, where: str) -> dict:
    """The copy of the sweep attributes in a parsed metadata file: the group's ('group'), or the
    done array's in the consolidated metadata ('consolidated') or in done/zarr.json ('done')."""
    if where == "group":
        return document["attributes"]
    if where == "consolidated":
        return document["consolidated_metadata"]["metadata"]["done"]["attributes"][schema.COPY]
    return document["attributes"][schema.COPY]


def set_c(where: str, value: float = 0.4):
    def change(document):
        sweep_attrs(document, where)["parameters"]["foundation"]["c"] = value
    return change


def set_k(document):  # a text edit of zarr.json: the group's attributes and the consolidated copy
    for where in ("group", "consolidated"):
        sweep_attrs(document, where)["parameters"]["foundation"]["k"] = 5000.0


def set_vy_hi(document):
    document["attributes"]["sweep"]["axes"][0]["hi"] = 3.0


def set_shape(document):
    document["shape"] = [8, 9]


def set_consolidated_shape(document):
    document["consolidated_metadata"]["metadata"]["status"]["shape"] = [8, 9]


FAULTS = {  # kind -> (file, change, what verify says)
    "c in the group's attributes": ("zarr.json", set_c("group"),
                                    "the group's attributes (zarr.json): c = 0.4 there, 0.5 "
                                    "proven by its computed tiles"),
    "k in zarr.json, both copies": ("zarr.json", set_k, "k = 5000 there, 10000 proven"),
    "an axis's hi": ("zarr.json", set_vy_hi, "--vy HI = 3 there, 2 proven"),
    "c in the copy in done/zarr.json": ("done/zarr.json", set_c("done"),
                                        "done/zarr.json: c = 0.4 there, 0.5 proven"),
    "an array's shape": ("status/zarr.json", set_shape, "metadata status/zarr.json"),
    "a shape in the consolidated metadata": ("zarr.json", set_consolidated_shape,
                                             "metadata zarr.json"),
}


@pytest.mark.parametrize("kind", list(FAULTS))
def test_changed_metadata_is_found_and_rebuilt_from_what_the_tiles_prove(tmp_path, clean, kind):
    key, change, what = FAULTS[kind]
    path = copy_store(clean, tmp_path / "s.zarr")
    edit(path, key, change)
    result = coin("verify", path)
    assert result.exit_code == 1 and "DAMAGED" in result.output, result.output
    assert what in said(result) and "0 tiles" not in said(result)
    assert "vy/c/0" not in said(result)  # the coordinates are what the tiles prove
    report = json.loads(coin("verify", path, "--json").stdout)
    assert report["intact"] is False and report["damaged"] == [] and report["metadata"]
    assert bool(report["parameters_changed"]) == (key != "status/zarr.json" and "shape" not in
                                                  kind)
    # stats: the numbers of the tiles, and a warning naming the damage
    stats = json.loads(coin_ok("stats", path, "--json").stdout)
    assert stats["tiles_done"] == 4 and stats["metadata_damaged"] == report["metadata"]
    assert stats["warnings"] and key.split("/")[0] in said(coin_ok("stats", path))
    # resume: the metadata rebuilt from the copy its tiles prove, nothing recomputed
    out = said(coin_ok(path, *ARGS))
    assert "repaired" in out and "every tile is done already (4 tiles" in out
    assert coin("verify", path).exit_code == 0
    assert_identical(path, clean)


def test_xarray_opens_a_store_whose_consolidated_shape_was_repaired(tmp_path, clean):
    import xarray as xr

    path = copy_store(clean, tmp_path / "s.zarr")
    edit(path, "zarr.json", set_consolidated_shape)
    coin_ok(path, *ARGS)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no fallback to unconsolidated metadata
        ds = xr.open_zarr(path)
    assert ds["status"].shape == (8, 8)


@pytest.mark.parametrize("change, args", [
    (set_k, ["--k", "5000"]),
    (set_vy_hi, ["--vy", "0.05:3"]),
    (set_c("group"), ["--c", "0.4"]),
])
def test_a_resume_with_the_changed_value_is_never_served_the_old_tiles(tmp_path, clean,
                                                                       change, args):
    path = copy_store(clean, tmp_path / "s.zarr")
    edit(path, "zarr.json", change)
    before = files_of(path)
    err = one_line_error(coin(path, *ARGS, *args))
    assert "changed after its tiles were computed" in err and "--overwrite" in err
    assert files_of(path) == before  # coordinates and data untouched


def test_parameters_changed_in_every_copy_are_not_recovered_but_proven_by_a_resume(tmp_path,
                                                                                   clean):
    path = copy_store(clean, tmp_path / "s.zarr")
    edit(path, "zarr.json", lambda d: (set_c("group")(d), set_c("consolidated")(d)))
    edit(path, "done/zarr.json", set_c("done"))
    result = coin("verify", path)
    assert result.exit_code == 1 and "cannot be recovered" in result.output
    assert "cannot be recovered" in one_line_error(coin("stats", path))
    # the changed value as parameters: its tiles do not verify under it, so it is refused
    err = one_line_error(coin(path, *ARGS, "--c", "0.4"))
    assert "cannot be recovered" in err and "--overwrite" in err
    # the same from Python, in the API's words: overwrite, no option of the command line
    import coincli

    with pytest.raises(coincli.ParameterError) as caught:
        coincli.verify_basin(path)
    assert "cannot be recovered" in str(caught.value) and "--" not in str(caught.value)
    assert "overwrite" in str(caught.value) and caught.value.parameters == ("overwrite",)
    # the parameters the tiles were computed with: they prove them, the metadata is rebuilt
    assert "repaired" in coin_ok(path, *ARGS).output
    assert_identical(path, clean)


def test_copies_that_disagree_before_any_tile_are_refused_in_one_line(tmp_path, clean):
    path = copy_store(clean, tmp_path / "s.zarr")
    for tile in ("0/0", "0/1", "1/0", "1/1"):
        (path / "done" / "c" / tile).unlink()  # nothing done
    edit(path, "zarr.json", set_c("group"))  # the group's copy no longer matches its digest
    assert "repaired" in coin_ok(path, *ARGS).output  # ... the others do: rebuilt from them
    assert coin("verify", path).exit_code == 0
    for tile in ("0/0", "0/1", "1/0", "1/1"):
        (path / "done" / "c" / tile).unlink()
    edit(path, "zarr.json", set_c("group"))
    edit(path, "done/zarr.json", lambda d: sweep_attrs(d, "done").update(version="0"))
    edit(path, "zarr.json", lambda d: sweep_attrs(d, "consolidated").update(version="0"))
    before = files_of(path)
    result = coin("verify", path)
    assert result.exit_code == 1 and "Traceback" not in result.output
    for err in (said(result), one_line_error(coin("stats", path)),
                one_line_error(coin(path, *ARGS))):
        assert "cannot be recovered" in err and "c = 0.4" in err and "--overwrite" in err
    assert files_of(path) == before
    coin_ok(path, *ARGS, "--overwrite")
    assert_identical(path, clean)


def annotate(path: Path) -> None:
    """What a user may add with zarr-python: a group attribute, an array attribute, an array
    (consolidated)."""
    import zarr

    group = zarr.open_group(str(path), mode="r+")
    group.attrs["note"] = "run on the cluster"
    group["quarter_turns"].attrs["checked_by"] = "me"
    mask = group.create_array("mask", shape=(8, 8), dtype="uint8", fill_value=0,
                              dimension_names=("vy", "vphi"))
    mask[:] = 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "consolidated metadata is not part of the v3 spec"
        zarr.consolidate_metadata(str(path))


def annotations(path: Path) -> tuple:
    import zarr

    group = zarr.open_group(str(path), mode="r")  # through the consolidated metadata
    return (group.attrs.get("note"), group["quarter_turns"].attrs.get("checked_by"),
            int(group["mask"][:].sum()))


def test_what_a_user_adds_with_zarr_is_kept_and_no_damage(tmp_path, clean):
    path = copy_store(clean, tmp_path / "s.zarr")
    annotate(path)
    assert coin_ok("verify", path).output.split(":")[1].strip() == "intact"
    stats = json.loads(coin_ok("stats", path, "--json").stdout)
    assert stats["warnings"] == [] and stats["tiles_done"] == 4
    before = files_of(path)
    out = said(coin_ok(path, *ARGS))
    assert "every tile is done already" in out and "repaired" not in out
    assert files_of(path) == before
    assert annotations(path) == ("run on the cluster", "me", 64)
    # damage beside them: repaired, and what the user added kept
    edit(path, "zarr.json", set_c("group"))
    assert "repaired" in coin_ok(path, *ARGS).output
    assert coin("verify", path).exit_code == 0
    assert annotations(path) == ("run on the cluster", "me", 64)
    assert api.open_basin(path).attrs["note"] == "run on the cluster"


def test_a_tile_verifies_only_under_the_parameters_it_was_computed_with(clean):
    view = BasinStore.open(clean)
    data, _ = view.read_tile((0, 1))
    flag = int(view.read_chunk("done", (0, 1))[0, 0])
    assert tile_digest((0, 1), data, view.parameters) == flag
    other = json.loads(json.dumps(view.attrs))
    other["parameters"]["foundation"]["c"] = 0.4
    assert tile_digest((0, 1), data, schema.parameters_digest(other)) != flag


def test_stats_on_a_partial_store_warns_with_the_fraction_computed(tmp_path, clean):
    path = copy_store(clean, tmp_path / "s.zarr")
    (path / "done" / "c" / "1" / "1").unlink()
    out = said(coin_ok("stats", path))
    assert "partial store: 3 of 4 tiles computed (75.0 %)" in out and "no random sample" in out
    stats = json.loads(coin_ok("stats", path, "--json").stdout)
    assert len(stats["warnings"]) == 1 and "3 of 4 tiles" in stats["warnings"][0]
    assert json.loads(coin_ok("stats", clean, "--json").stdout)["warnings"] == []
    # the same from Python, for a store and for the Dataset of one
    assert coincli.basin_stats(path)["warnings"] == stats["warnings"]
    assert coincli.basin_stats(coincli.open_basin(path))["warnings"] == stats["warnings"]
    assert coincli.basin_stats(clean)["warnings"] == []


def test_a_read_only_store_is_named_in_one_line(tmp_path, clean, monkeypatch):
    folder = tmp_path / "ro"
    folder.mkdir()
    path = copy_store(clean, folder / "s.zarr")
    (path / "done" / "c" / "1" / "1").unlink()
    Disk(monkeypatch, folder, errno.EROFS)
    err = one_line_error(coin(path, *ARGS))
    assert f"the store {path} is read-only (read-only file system)" in err
    err = one_line_error(coin(folder / "new.zarr", *ARGS))
    assert f"cannot create the store {folder / 'new.zarr'}: its folder is read-only" in err
