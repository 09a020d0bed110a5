#!/usr/bin/env bash
# The cost of the automatic guard band: renders each example scene with `--guard-band auto` and
# `--guard-band 0`, alternating run by run so that a shared machine's load affects both alike,
# and prints per scene the band chosen, the grid (light-buffer) pixels of each, their ratio, the
# median sweep seconds (`seconds_sweep` of --stats-json) of each and their ratio.
#
#   scripts/guard_band_cost.sh BIN                  # 3 alternations, every scene in scenes/
#   REPS=5 THREADS=1 SCENES="default edge" scripts/guard_band_cost.sh BIN
#
# Every run uses --threads $THREADS (default 2; the SIMD path, quiet-chunk skipping on).
# Output: a Markdown table.
set -euo pipefail

if [ $# -ne 1 ]; then
    sed -n '2,11p' "$0" >&2
    exit 2
fi
BIN="$1"
REPS="${REPS:-3}"
THREADS="${THREADS:-2}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
SCENES="${SCENES:-$(cd "$ROOT/scenes" && ls ./*.toml | sed 's|^\./||; s|\.toml$||' | tr '\n' ' ')}"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

# run SCENE BAND N: one render, its stats in $TMP/SCENE-BAND-N.json.
run() {
    "$BIN" render "$ROOT/scenes/$1.toml" -o "$TMP/out.exr" --quiet --threads "$THREADS" \
        --guard-band "$2" --stats-json "$TMP/$1-$2-$3.json"
}

median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }

echo "| scene | image | auto band (l/r/t/b px) | grid px, 0 | grid px, auto | ratio | sweep s, 0 | sweep s, auto | ratio |"
echo "|---|---|---|---|---|---|---|---|---|"
for s in $SCENES; do
    for i in $(seq "$REPS"); do
        run "$s" 0 "$i"
        run "$s" auto "$i"
    done
    j() { jq -r "$1" "$TMP/$s-$2-1.json"; }
    band="$(j '.guard_band_px | "\(.left)/\(.right)/\(.top)/\(.bottom)"' auto)"
    g0="$(j '.grid_width * .grid_height' 0)"
    ga="$(j '.grid_width * .grid_height' auto)"
    t0="$(for i in $(seq "$REPS"); do jq .seconds_sweep "$TMP/$s-0-$i.json"; done | median)"
    ta="$(for i in $(seq "$REPS"); do jq .seconds_sweep "$TMP/$s-auto-$i.json"; done | median)"
    size="$(j '"\(.width)×\(.height), \(.slabs) slabs"' 0)"
    awk -v s="$s" -v size="$size" -v b="$band" -v g0="$g0" -v ga="$ga" -v t0="$t0" -v ta="$ta" \
        'BEGIN { printf "| %s | %s | %s | %d | %d | %.2f | %.2f | %.2f | %.2f |\n", s, size, b, g0, ga, ga / g0, t0, ta, ta / t0 }'
done
