#!/usr/bin/env bash
# Time one coin command under two checkouts of coincli, alternating, so that both see the same
# load on a shared machine; prints each run's wall seconds and the medians.
#
#   benchmarks/alternate.sh OLD_TREE NEW_TREE ROUNDS coin-arguments...
#   e.g. benchmarks/alternate.sh ../coin-0.6.0 . 5 basin S.zarr --res 512 -q
#
# Each tree is put first on PYTHONPATH and run as `python -m coincli` with this checkout's
# .venv (each tree's kernels compile once, on its first run: do one run of each before timing).
# PYTHONSAFEPATH keeps `-m` from putting the working directory first (run from a checkout, its
# own coincli/ would win over PYTHONPATH), and each tree is checked to import its own package.
# An argument ending in .zarr is removed before every run, so each run creates its store afresh.
set -euo pipefail
old=$(cd "$1" && pwd); new=$(cd "$2" && pwd); rounds=$3; shift 3
python=${PYTHON:-$(cd "$(dirname "$0")/.." && pwd)/.venv/bin/python}
export PYTHONSAFEPATH=1
for tree in "$old" "$new"; do
  package=$(PYTHONPATH=$tree "$python" -c 'import coincli; print(coincli.__path__[0])')
  [[ $package == "$tree/coincli" ]] || { echo "$tree runs $package, not its own" >&2; exit 2; }
done
declare -A times
for _ in $(seq "$rounds"); do
  for tree in "$old" "$new"; do
    for arg in "$@"; do [[ $arg == *.zarr ]] && rm -rf "$arg" "$arg.cost"; done
    start=$(date +%s.%N)
    PYTHONPATH=$tree "$python" -m coincli "$@" > /dev/null
    seconds=$("$python" -c "print($(date +%s.%N) - $start)")
    times[$tree]="${times[$tree]:-} $seconds"
    printf '%s %.2f\n' "$tree" "$seconds"
  done
done
for tree in "$old" "$new"; do
  median=$(tr ' ' '\n' <<< "${times[$tree]}" | grep . | sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}')
  printf 'median %s %.2f s\n' "$tree" "$median"
done
