#!/usr/bin/env python
"""Make tests/data/paper-map-16.npz: the paper's default map at 16 x 16 (vy0 0.05-2 m/s, vphi0
+-20 rad/s, verified), computed by the paper's model's kernels (PAPER.kernels(), the scene
having no friction), the arrays tests/test_friction.py::test_mu_0_map_is_unchanged compares
every later map with.

    python tests/data/make_paper_map.py                          # write it
    python tests/data/make_paper_map.py --against /path/to/coin-0.10.0
                                        # and check that 0.10.0's `coin basin` gives the same

It was made once, when friction came in (issue 47), and checked against 0.10.0 then; it is not
remade unless the paper's numbers are meant to change.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "paper-map-16.npz"
ARRAYS = ("quarter_turns", "status", "settle_time", "steps", "certainty", "rung")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--against", type=Path, help="a checkout of another version to compare")
    args = parser.parse_args()
    sys.path.insert(0, str(HERE.parents[1]))
    import coincli
    from coincli.labeller import Labeller
    from coincli.models import PAPER, model_of

    scene = coincli.load_preset("paper")
    assert model_of(scene) is PAPER and Labeller.of(scene).kernels is PAPER.kernels()
    ds = coincli.basin(scene, res=16)
    arrays = {name: ds[name].values for name in ARRAYS}
    np.savez_compressed(OUT, **arrays)
    print(f"wrote {OUT}")
    if args.against:
        import zarr

        with tempfile.TemporaryDirectory() as folder:
            store = Path(folder) / "map.zarr"
            subprocess.run([sys.executable, "-m", "coincli", "basin", str(store), "--res", "16"],
                           env={**os.environ, "PYTHONPATH": str(args.against)}, cwd="/",
                           check=True, capture_output=True)
            group = zarr.open_group(str(store), mode="r")
            differ = [name for name in ARRAYS
                      if not np.array_equal(np.asarray(group[name][...]), arrays[name],
                                            equal_nan=True)]
        print(f"against {args.against}: " + (f"{differ} differ" if differ else "the same"))
        sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
