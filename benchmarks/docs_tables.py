#!/usr/bin/env python
"""The documentation's tables of current figures, generated from `coin bench --json` and from
benchmarks/peers.json, each with the version, the machine and the date in one line.

    python benchmarks/docs_tables.py               # runs `coin bench --json` (several minutes),
                                                   # keeps it in benchmarks/bench.json, writes
    python benchmarks/docs_tables.py --from F.json # takes a saved `coin bench --json` instead
    python benchmarks/docs_tables.py --render      # rewrites the tables from bench.json only

The tables go between marker comments (``<!-- bench-table:start -->`` ... ``:end -->``) in
docs/performance.md, so that the page holds no figure typed by hand; the README links the page
rather than copying figures that would outlive their version. `make docs` runs the first form.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
BENCH = HERE / "bench.json"
PEERS = HERE / "peers.json"
PERFORMANCE = REPO / "docs" / "performance.md"


def machine() -> str:
    """The machine in a few words: CPU model, cores usable, architecture."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return f"{cores} cores of {model} ({platform.machine()}, {platform.system()})"


def run_bench(saved: Path | None) -> dict:
    """`coin bench --json` (or a saved output of it) with when, where and which version."""
    if saved is None:
        coin = Path(sys.executable).with_name("coin")
        out = subprocess.run([str(coin), "bench", "--json"], check=True, capture_output=True,
                             text=True).stdout
        bench = json.loads(out)
        date = datetime.datetime.now(datetime.UTC)
    else:
        bench = json.loads(saved.read_text())
        date = datetime.datetime.fromtimestamp(saved.stat().st_mtime, datetime.UTC)
    sys.path.insert(0, str(REPO))
    from coincli import __version__

    bench["measured"] = {"version": __version__, "machine": machine(),
                         "date": date.strftime("%Y-%m-%d"), "command": "coin bench --json"}
    return bench


def provenance(measured: dict) -> str:
    return (f"coincli {measured['version']}, {measured['machine']}, {measured['date']}: "
            f"`{measured['command']}`.")


def bench_table(bench: dict) -> str:
    """Every setting of `coin bench`, side by side on the same cells, and the whole commands."""
    rows = ["| setting | ms a trajectory (one thread) | x faster than the paper's | right on "
            f"the {bench['robust_cells']} robust cells | uncertain |",
            "|---|---:|---:|---:|---:|"]
    for r in bench["rows"]:
        uncertain = f"{100 * r['uncertain_robust']:.1f} %" if r["verified"] else "-"
        rows.append(f"| {r['name']} | {r['ms_per_trajectory']:.3g} | "
                    f"{r['speedup_vs_paper']:,.0f} | {100 * r['label_agreement_robust']:.2f} % "
                    f"| {uncertain} |")
    startup, basin = bench["startup"], bench["basin"]
    lines = [provenance(bench["measured"]), "", *rows, "",
             f"Start-up (median of {len(startup['help_runs'])}): `coin --help` "
             f"{startup['help_seconds']:.2f} s, a warm `coin simulate --no-rrd` "
             f"{startup['simulate_seconds']:.2f} s; the imports alone that every command running "
             f"kernels needs (Python, numpy, typer, rich, numba) "
             f"{startup['import_floor_seconds']:.2f} s."]
    if basin:
        lines[-1] += (f" The default {basin['res']} x {basin['res']} `coin basin`, the whole "
                      f"command on {basin['threads']} threads: {basin['wall_seconds']:.2f} s "
                      f"({100 * basin['outside_kernels']:.0f} % outside the kernels), peak "
                      f"memory {basin['peak_rss_mb']:.0f} MB.")
    return "\n".join(lines)


def peers_table(peers: dict) -> str:
    """benchmarks/peers.py's results: the same throws with scipy and diffrax."""
    versions, machine_info = peers["versions"], peers["machine"]
    where = (f"{machine_info.get('cpus_usable', machine_info['cpu_count'])} cores of "
             f"{machine_info.get('cpu_model', machine_info['processor'])}")
    commit = f" ({versions['coincli_git'][:7]})" if versions.get("coincli_git") else ""
    rows = [f"coincli {versions['coincli']}{commit}, scipy {versions['scipy']}, diffrax "
            f"{versions['diffrax']} (jax {versions['jax']}), {where}, {peers['date'][:10]}: "
            "`python benchmarks/peers.py`.", "",
            f"| method | ms a trajectory | times slower than ours | robust cells right (of "
            f"{peers['robust_cells']}) |",
            "|---|---:|---:|---:|"]
    for r in peers["results"]:
        a = r["agreement"]
        rows.append(f"| {r['method']} | {r['seconds_per_trajectory'] * 1e3:.3g} | "
                    f"{r['x_slower_than_ours']:,.0f} | {a['agree']} "
                    f"({100 * a['fraction']:.1f} %) |")
    return "\n".join(rows)


def replace_between(path: Path, name: str, text: str) -> None:
    """Put ``text`` between the markers ``<!-- NAME:start -->`` and ``<!-- NAME:end -->``."""
    page = path.read_text()
    pattern = re.compile(rf"(<!-- {name}:start -->\n).*?(<!-- {name}:end -->)", re.S)
    if not pattern.search(page):
        raise SystemExit(f"{path}: no <!-- {name}:start --> ... <!-- {name}:end --> markers")
    path.write_text(pattern.sub(lambda m: m.group(1) + text + "\n" + m.group(2), page))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--from", dest="saved", type=Path,
                        help="a saved output of `coin bench --json`")
    source.add_argument("--render", action="store_true",
                        help="only rewrite the tables from benchmarks/bench.json")
    args = parser.parse_args(argv)
    if args.render:
        bench = json.loads(BENCH.read_text())
    else:
        bench = run_bench(args.saved)
        BENCH.write_text(json.dumps(bench, indent=1) + "\n")
    replace_between(PERFORMANCE, "bench-table", bench_table(bench))
    replace_between(PERFORMANCE, "peers-table", peers_table(json.loads(PEERS.read_text())))
    print(f"wrote the tables of {PERFORMANCE.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
