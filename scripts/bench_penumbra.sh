#!/usr/bin/env bash
# The distance penumbra's cost against the iterated mode, one binary alternating the two modes
# (docs/performance.md, "The distance penumbra"): the default scene three times each, then 256²
# at 128/256/512/1024 slabs twice each. Prints the plan and sweep seconds of every run; quote
# ratios from one run, not absolute times. Usage: scripts/bench_penumbra.sh [BINARY]
set -euo pipefail
bin=${1:-target/release/convshadow}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
seconds() {
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(d['seconds_plan'], d['seconds_sweep'])" "$tmp/s.json"
}
for _ in 1 2 3; do
  for mode in iterated distance; do
    "$bin" render --penumbra "$mode" -o "$tmp/b.png" --stats-json "$tmp/s.json" -q
    echo "default $mode $(seconds)"
  done
done
for _ in 1 2; do
  for n in 128 256 512 1024; do
    for mode in iterated distance; do
      "$bin" render --penumbra "$mode" --slabs "$n" --width 256 --height 256 \
        -o "$tmp/b.png" --stats-json "$tmp/s.json" -q
      echo "slabs $n $mode $(seconds)"
    done
  done
done
