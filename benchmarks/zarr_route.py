#!/usr/bin/env python
"""What writing a sweep's tiles through zarr-python would cost the default 512 x 512 map, side by
side with the one Zarr route of the package (coincli.stores.zarr_v3), and why the stores do not
use it.

    python benchmarks/zarr_route.py [--rounds 5] [--json] [--write]

The default map is computed once (``coincli.basin`` into a store); then, in interleaved rounds,
its tiles are written again into fresh stores: by ``BasinStore.write_tile`` (every chunk encoded
here, one file each, renamed into place) and by zarr-python (``array[tile] = block`` for each
array, ``write_empty_chunks`` on, the same codecs). Each round also times zarr-python's import in
a fresh interpreter. The figure that decides is the whole command's extra time through zarr,
against the whole command's time (``coin basin --res 512``, median of the rounds): the issue's
bar is 5 %. The result is kept in benchmarks/zarr-route.json; ``--write`` puts its line between
``<!-- zarr-route:start -->`` and ``:end -->`` of docs/performance.md.
"""

from __future__ import annotations

import argparse
import datetime
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--write", action="store_true",
                        help="put the figures in docs/performance.md too")
    args = parser.parse_args()

    import coincli
    from coincli.grid import TileResult
    from coincli.stores.basin_layout import ARRAY_NAMES
    from coincli.stores.basin_store import BasinStore

    work = Path(tempfile.mkdtemp(prefix="coin-zarr-route-"))
    try:
        source = work / "map.zarr"
        command = []
        for _ in range(args.rounds):  # the whole command, as users run it
            shutil.rmtree(source, ignore_errors=True)
            shutil.rmtree(f"{source}.cost", ignore_errors=True)
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "coincli", "basin", str(source), "--quiet"],
                           check=True, capture_output=True)
            command.append(time.perf_counter() - t0)
        store = BasinStore.open(source)
        basin = store.read()
        grid = store.grid
        tiles = [TileResult(tile, {name: basin.arrays[name][grid.tile_slices(tile)]
                                   for name in ARRAY_NAMES}, 0.0, 0.0)
                 for tile in grid.tiles()]
        ours, theirs, imports = [], [], []
        for r in range(args.rounds):
            target = BasinStore(work / f"ours-{r}.zarr")
            target.create_or_resume(store.attrs, grid)
            t0 = time.perf_counter()
            for tile in tiles:
                target.write_tile(tile)
            ours.append(time.perf_counter() - t0)

            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", "import zarr"], check=True)
            t1 = time.perf_counter()
            subprocess.run([sys.executable, "-c", "pass"], check=True)
            imports.append((t1 - t0) - (time.perf_counter() - t1))

            import zarr

            path = work / f"zarr-{r}.zarr"
            BasinStore(path).create_or_resume(store.attrs, grid)
            group = zarr.open_group(str(path), mode="r+")
            arrays = {name: group[name].with_config({"write_empty_chunks": True})
                      for name in (*ARRAY_NAMES, "done")}
            t0 = time.perf_counter()
            for tile in tiles:
                s0, s1 = grid.tile_slices(tile.tile)
                for name in ARRAY_NAMES:
                    arrays[name][s0, s1] = tile.arrays[name]
                arrays["done"][tile.tile] = np.uint32(1)
            theirs.append(time.perf_counter() - t0)
        result = {
            "tiles": len(tiles), "chunks_per_tile": len(ARRAY_NAMES) + 1,
            "command_seconds": statistics.median(command),
            "write_seconds_ours": statistics.median(ours),
            "write_seconds_zarr": statistics.median(theirs),
            "zarr_import_seconds": statistics.median(imports),
        }
        extra = (result["write_seconds_zarr"] - result["write_seconds_ours"]
                 + result["zarr_import_seconds"])
        result["command_through_zarr_ratio"] = 1 + extra / result["command_seconds"]
    finally:
        shutil.rmtree(work, ignore_errors=True)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from docs_tables import PERFORMANCE, machine, provenance, replace_between

    command = "python benchmarks/zarr_route.py" + (
        f" --rounds {args.rounds}" if args.rounds != 5 else "")
    result["measured"] = {"version": coincli.__version__, "machine": machine(),
                          "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d"),
                          "command": command}
    Path(__file__).with_name("zarr-route.json").write_text(json.dumps(result, indent=1) + "\n")
    if args.json:
        print(json.dumps(result, indent=2))
        return
    text = (f"{provenance(result['measured'])}\n\n"
            f"The default 512 x 512 map ({result['tiles']} tiles of {result['chunks_per_tile']} "
            f"chunks), medians of {args.rounds} rounds: the whole command "
            f"{result['command_seconds']:.2f} s; its tiles written through "
            f"`coincli.stores.zarr_v3` {result['write_seconds_ours']:.3f} s (one thread), through "
            f"zarr-python {result['write_seconds_zarr']:.3f} s, and importing zarr-python "
            f"{result['zarr_import_seconds']:.2f} s: the command would take "
            f"{result['command_through_zarr_ratio']:.2f} times as long through zarr-python.")
    print(text)
    if args.write:
        replace_between(PERFORMANCE, "zarr-route", text)


if __name__ == "__main__":
    main()
