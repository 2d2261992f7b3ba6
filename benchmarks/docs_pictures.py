#!/usr/bin/env python
"""Every picture of the documentation (README.md and docs/: every docs/*.png), each with the
one command that makes it from the current version. A picture says in its PNG metadata which
version made it ("Software: coin 0.11.0": coincli.files.save_figure writes it for coin's charts,
coincli.files.stamp_png for the screenshots of Rerun's viewer), and tests/test_docs.py fails when
one was made by an older minor version than the package's, naming the command that remakes it.

    python benchmarks/docs_pictures.py --list          # each picture, the version that made
                                                       # it and its command
    python benchmarks/docs_pictures.py --make          # remakes every picture
    python benchmarks/docs_pictures.py --make basin.png simulate-fig2.png    # only these

Run it with the project's environment (`make docs` runs `--make`; `coin`, `rerun` and `python` below
are that environment's). The stores and recordings the pictures are drawn from go to out/ (`--out`);
a store is made again for each run (`--overwrite`), so that no picture is drawn from the labels of
an older version. All of them take about three hours on 2 cores, most of it the thickness-damping
grid (an hour), the friction study's maps and curves and the accuracy charts; the screenshots of
Rerun's viewer need a display or xvfb-run (Debian: xvfb and mesa-vulkan-drivers).
"""

from __future__ import annotations

import argparse
import os
import shlex
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
BIN = Path(sys.executable).parent  # coin and rerun of this environment
# the thickness-damping grid of docs/thickness-damping.md (benchmarks/thickness_damping.py's)
THICKNESS = ",".join(f"{0.02 * q:g}" for q in [0.05 * i for i in range(1, 10)]
                     + [0.5 + 0.025 * i for i in range(21)])
DAMPING = "0.05,0.1,0.2,0.5,1,2,4,8,16,32,64,128"
SCREEN = "xvfb-run -a -s '-screen 0 1600x1000x24' rerun --window-size 1600x1000"

# What several pictures are drawn from, made once for each run of this script ({out}: --out).
STEPS = {
    "the default map": ("coin basin {out}/docs-basin.zarr --overwrite",),
    "the fig. 2 throw": ("coin simulate --vy 1.197 --vphi 3.508 --rrd {out}/fig2.rrd",),
    "the thickness-damping grid": (
        "coin fractions --y0 r:5r --phi0 -pi:pi --vx -0.5:0.5 "
        f"--over thickness={THICKNESS} --over c={DAMPING} --samples 16k "
        "--store {out}/thickness-damping.zarr --overwrite --yes "
        "--plot docs/thickness-damping.png",),
}


@dataclass(frozen=True)
class Picture:
    """A picture under docs/: what it is drawn from (``needs``: names of :data:`STEPS`), the
    commands that draw it, run in the repository in order; ``recording``: it is a screenshot of
    this recording by Rerun's viewer (taken after the commands, then stamped with the version);
    ``stop_at``: the first command is a sweep (`coin basin STORE ...`), stopped (SIGTERM, as a
    batch scheduler stops one) once this many of its tiles are done."""

    name: str
    commands: tuple[str, ...] = ()
    needs: tuple[str, ...] = ()
    recording: str | None = None
    stop_at: int = 0

    @property
    def path(self) -> Path:
        return DOCS / self.name

    def steps(self, out: str) -> list[str]:
        """Every command that makes the picture, in order, as a shell runs them."""
        lines = [c.format(out=out) for need in self.needs for c in STEPS[need]]
        for i, command in enumerate(self.commands):
            line = command.format(out=out)
            if i == 0 and self.stop_at:
                line += f"   # stopped (SIGTERM) once {self.stop_at} tiles are done"
            lines.append(line)
        if self.recording:
            lines.append(f"{SCREEN} --screenshot-to docs/{self.name} "
                         f"{self.recording.format(out=out)}")
            lines.append(f"python -c 'from coincli.files import stamp_png; "
                         f"stamp_png(\"docs/{self.name}\")'")
        return lines

    def command(self) -> str:
        """The one command that makes it: this script's (with the project's environment)."""
        return f".venv/bin/python benchmarks/docs_pictures.py --make {self.name}"


PICTURES = (
    Picture("basin.png", ("coin basin render {out}/docs-basin.zarr -o docs/basin.png",),
            needs=("the default map",)),
    Picture("basin-settle-time.png", ("coin basin render {out}/docs-basin.zarr --field "
                                      "settle_time -o docs/basin-settle-time.png",),
            needs=("the default map",)),
    Picture("basin-analysis.png", ("coin basin analyze {out}/docs-basin.zarr -o "
                                   "docs/basin-analysis.png",), needs=("the default map",)),
    Picture("basin-live.png", ("coin basin {out}/basin-live.zarr --overwrite --rrd "
                               "{out}/basin-live.rrd",),
            recording="{out}/basin-live.rrd", stop_at=26),
    Picture("basin-show.png", ("coin basin show {out}/docs-basin.zarr --rrd "
                               "{out}/basin-show.rrd",),
            needs=("the default map",), recording="{out}/basin-show.rrd"),
    Picture("analysis-live.png", ("coin basin analyze {out}/docs-basin.zarr --rrd "
                                  "{out}/analysis-live.rrd",),
            needs=("the default map",), recording="{out}/analysis-live.rrd"),
    Picture("notebook-live.png", ("coin basin {out}/notebook-live.zarr --res 1024 --overwrite "
                                  "--yes --rrd {out}/notebook-live.rrd",),
            recording="{out}/notebook-live.rrd", stop_at=128),
    Picture("simulate-fig2.png", needs=("the fig. 2 throw",), recording="{out}/fig2.rrd"),
    Picture("fractions-live.png", ("coin fractions --samples 40k --rrd "
                                   "{out}/fractions-live.rrd",),
            recording="{out}/fractions-live.rrd"),
    Picture("fractions-thickness.png", (
        "coin fractions --y0 r:5r --phi0 -pi:pi --vx -0.5:0.5 --over thickness=0.001:0.02:20 "
        "--samples 64k --store {out}/docs-thickness.zarr --overwrite --yes "
        "--plot docs/fractions-thickness.png",)),
    Picture("thickness-damping.png", needs=("the thickness-damping grid",)),
    Picture("thickness-damping-crossing.png", (
        "python benchmarks/thickness_damping.py {out}/thickness-damping.zarr --landing 2000",),
        needs=("the thickness-damping grid",)),
    Picture("friction-maps.png", ("python benchmarks/friction.py --maps --out {out}/friction",)),
    Picture("friction-pstanding.png", ("python benchmarks/friction.py --curves --out "
                                       "{out}/friction",)),
    Picture("accuracy.png", ("coin accuracy --res 32 -o docs/accuracy.png "
                             "--table docs/accuracy.json",)),
    Picture("accuracy-thick.png", ("coin accuracy --preset thick --res 24 -o "
                                   "docs/accuracy-thick.png --table docs/accuracy-thick.json",)),
)
BY_NAME = {p.name: p for p in PICTURES}


def made_by(picture: Picture) -> str | None:
    """The version of coin its metadata name (None: none, or no such file)."""
    sys.path.insert(0, str(ROOT))
    from coincli.files import picture_made_by

    return picture_made_by(picture.path) if picture.path.is_file() else None


def listing(out: str) -> str:
    lines = []
    for picture in PICTURES:
        version = made_by(picture)
        said = (f"coin {version}" if version else "no version in its metadata"
                if picture.path.is_file() else "missing")
        lines.append(f"docs/{picture.name}: {said}")
        lines += [f"    {step}" for step in picture.steps(out)]
    lines.append("remake one: python benchmarks/docs_pictures.py --make NAME; all of them: "
                 "python benchmarks/docs_pictures.py --make")
    return "\n".join(lines)


def argv(line: str) -> list[str]:
    """A command line of :meth:`Picture.steps` as arguments, with this environment's coin, rerun
    and python."""
    words = shlex.split(line, comments=True)
    for i, word in enumerate(words):
        if word in ("coin", "rerun"):
            words[i] = str(BIN / word)
        elif word == "python":
            words[i] = sys.executable
    return words


def run(line: str) -> None:
    print(f"$ {line}", flush=True)
    subprocess.run(argv(line), cwd=ROOT, check=True)


def run_until_tiles(line: str, tiles: int) -> None:
    """A sweep (`coin basin STORE ...`) stopped by SIGTERM once ``tiles`` of its tiles are
    done: its recording ends with the map of what the store holds then."""
    print(f"$ {line}   # stopped once {tiles} tiles are done", flush=True)
    words = argv(line)
    done = ROOT / words[2] / "done" / "c"
    proc = subprocess.Popen(words, cwd=ROOT)
    while proc.poll() is None:
        if done.is_dir() and sum(1 for _ in done.glob("*/*")) >= tiles:
            proc.send_signal(signal.SIGTERM)
            break
        time.sleep(0.01)
    if proc.wait() not in (0, 128 + signal.SIGTERM):
        raise subprocess.CalledProcessError(proc.returncode, words)


def make(pictures: list[Picture], out: str) -> None:
    from coincli.files import stamp_png

    (ROOT / out).mkdir(parents=True, exist_ok=True)
    made: set[str] = set()
    for picture in pictures:
        for need in picture.needs:
            if need not in made:
                for command in STEPS[need]:
                    run(command.format(out=out))
                made.add(need)
        for i, command in enumerate(picture.commands):
            if i == 0 and picture.stop_at:
                run_until_tiles(command.format(out=out), picture.stop_at)
            else:
                run(command.format(out=out))
        if picture.recording:
            picture.path.unlink(missing_ok=True)  # the viewer's screenshot, or nothing
            run(f"{SCREEN} --screenshot-to docs/{picture.name} "
                f"{picture.recording.format(out=out)}")
            stamp_png(picture.path)
        print(f"docs/{picture.name}: coin {made_by(picture)}", flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    action = parser.add_mutually_exclusive_group(required=True)
    action.add_argument("--list", action="store_true",
                        help="each picture, the version its metadata name, its command")
    action.add_argument("--make", nargs="*", metavar="NAME",
                        help="remake these pictures (docs/NAME.png; all if none given)")
    parser.add_argument("--out", default=os.environ.get("OUT", "out"),
                        help="the folder of the stores and recordings (default: out)")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    if args.list:
        print(listing(args.out))
        return 0
    names = [Path(n).name for n in args.make] or list(BY_NAME)
    unknown = [n for n in names if n not in BY_NAME]
    if unknown:
        parser.error(f"no picture {', '.join(unknown)}; the pictures: {', '.join(BY_NAME)}")
    make([BY_NAME[n] for n in names], args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
