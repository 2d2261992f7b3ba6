"""Kernels of another checkout against this one's, side by side in one process: the single pass
and the verified default on the same throws, alternating round by round, thread time. On a
shared machine two processes timed one after the other see different loads; here every round
times both within a second or two, and the ratio of each round's pair is what is reported.

    python benchmarks/side_by_side.py ../coin-0.6.1                      # paper box, 16,384 throws
    python benchmarks/side_by_side.py ../coin-0.6.1 --preset thick --samples 4096 --rounds 5

The other checkout's package is copied to a temporary directory as ``coinold`` (every
``coincli`` in its sources renamed), so both import at once; its kernels compile on the first
run (a few minutes, cached afterwards under its copy's path). Either checkout may have either
API: the old one (``integrators.batch.label_states`` and ``verified_labels`` on
``params.model_params`` and ``run_settings``, up to 0.10.0) or the new one (``labeller.Labeller``,
one per scene); each is run through its own (:func:`runners`). The throws are the first N of
the README's five-dimensional box (``fractions_labels.box_throws``). Prints the medians, the
median and range of the per-round ratios, and how the labels compare (count, certainty, rung).
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))


def copy_as_coinold(tree: Path) -> Path:
    """The checkout's package as ``coinold`` in a directory named after its sources (so that a
    second run finds the same copy and its compiled kernels)."""
    sources = sorted((tree / "coincli").rglob("*.py"))
    digest = hashlib.sha256(b"".join(p.read_bytes() for p in sources)).hexdigest()[:12]
    root = Path(tempfile.gettempdir()) / f"coin-side-by-side-{digest}"
    if not (root / "coinold").is_dir():
        staging = Path(tempfile.mkdtemp(prefix="coin-side-by-side-"))
        shutil.copytree(tree / "coincli", staging / "coinold",
                        ignore=shutil.ignore_patterns("__pycache__"))
        for path in (staging / "coinold").rglob("*.py"):
            path.write_text(path.read_text().replace("coincli", "coinold"))
        shutil.copytree(tree / "presets", staging / "presets")
        staging.rename(root)
    return root


def runners(package: str, preset: str, states: np.ndarray):
    """(single pass, verified) of ``package`` on ``states``, each already loaded once, through
    the package's own API: the labeller where it has one, else the old batch functions."""
    __import__(package)
    if importlib.util.find_spec(f"{package}.labeller") is not None:
        return labeller_runners(package, preset, states)
    return batch_runners(package, preset, states)


def labeller_runners(package: str, preset: str, states: np.ndarray):
    """(single pass, verified) through the new API: a Labeller per scene, the single pass that
    of the scene without verification (one rung, the scene's first)."""
    pkg = __import__(package)
    labeller = __import__(f"{package}.labeller", fromlist=["_"])
    scene = pkg.load_preset(preset)
    single = labeller.Labeller.of(scene.with_overrides(verify=False, stop_on_settle=True))
    verified = labeller.Labeller.of(scene)
    single.label(states[:2])
    verified.label(states[:2])
    return (lambda: single.label(states), lambda: verified.label(states))


def batch_runners(package: str, preset: str, states: np.ndarray):
    """(single pass, verified) through the old API (up to 0.10.0): the batch functions on the
    kernels' parameters and run settings."""
    pkg = __import__(package)
    batch = __import__(f"{package}.integrators.batch", fromlist=["_"])
    ladder = __import__(f"{package}.integrators.ladder", fromlist=["_"])
    params = __import__(f"{package}.params", fromlist=["_"])
    scene = pkg.load_preset(preset)
    p, base = params.model_params(scene), params.run_settings(scene.integration)
    single = base._replace(stop_on_settle=True)
    rungs = ladder.ladder_of(scene.integration)
    batch.label_states(p, single, states[:2])
    batch.verified_labels(p, base, rungs, states[:2])
    return (lambda: batch.label_states(p, single, states),
            lambda: batch.verified_labels(p, base, rungs, states))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("old", type=Path, help="the other checkout (a directory with coincli/)")
    parser.add_argument("--preset", default="paper")
    parser.add_argument("--samples", type=int, default=16_384)
    parser.add_argument("--rounds", type=int, default=10)
    args = parser.parse_args()

    sys.path.insert(0, str(copy_as_coinold(args.old.resolve())))
    from fractions_labels import box_throws

    import coincli
    from coincli.enums import Certainty

    states = box_throws(coincli.load_preset(args.preset), args.samples)
    run = {name: runners(name, args.preset, states) for name in ("coinold", "coincli")}
    seconds = {(name, k): [] for name in run for k in (0, 1)}
    last = {}
    for r in range(args.rounds):
        for k in (0, 1):
            for name in ("coinold", "coincli") if r % 2 == 0 else ("coincli", "coinold"):
                start = time.thread_time()
                last[name, k] = run[name][k]()
                seconds[name, k].append(time.thread_time() - start)
    n = len(states)
    print(f"{args.preset}, {n:,} box throws, {args.rounds} rounds, thread time "
          f"(old: {args.old})")
    for k, what in ((0, "single pass"), (1, "verified")):
        old, new = np.array(seconds["coinold", k]), np.array(seconds["coincli", k])
        ratio = new / old
        a, b = last["coinold", k], last["coincli", k]
        print(f"{what:11s}  old {1e6 * np.median(old) / n:7.2f} us  new "
              f"{1e6 * np.median(new) / n:7.2f} us  new/old {np.median(ratio):.3f} "
              f"({ratio.min():.3f}-{ratio.max():.3f})  labels differ: "
              f"{int((a.quarter_turns != b.quarter_turns).sum())}")
        if k == 1:
            certain = int(Certainty.CERTAIN)
            both = (a.certainty == certain) & (b.certainty == certain)
            print(f"{'':11s}  certain in both {int(both.sum()):,}, with another n "
                  f"{int((both & (a.quarter_turns != b.quarter_turns)).sum())}; certain in old "
                  f"only {int(((a.certainty == certain) & ~both).sum())}, in new only "
                  f"{int(((b.certainty == certain) & ~both).sum())}; rungs differ "
                  f"{int((a.rung != b.rung).sum())}")


if __name__ == "__main__":
    main()
