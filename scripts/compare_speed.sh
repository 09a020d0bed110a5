#!/usr/bin/env bash
# Compares the user CPU time of two convshadow binaries, alternating them run by run so that a
# shared machine's load affects both alike, and checks that both write the same image bits.
#
#   scripts/compare_speed.sh OLD_BIN NEW_BIN            # 3 alternations per case
#   REPS=5 scripts/compare_speed.sh OLD_BIN NEW_BIN
#   CASES="default:simd bunny:scalar" scripts/compare_speed.sh OLD_BIN NEW_BIN
#   EXTRA="--penumbra iterated" scripts/compare_speed.sh OLD_BIN NEW_BIN   # more render options
#
# Cases are SCENE:PATH; SCENE `default` is `render` without a scene file, any other name is
# scenes/SCENE.toml. Every run uses --threads 1. Prints per case the user seconds of each run and
# the ratio NEW/OLD of the medians (below 1: the new binary is faster).
set -euo pipefail

if [ $# -ne 2 ]; then
    sed -n '2,11p' "$0" >&2
    exit 2
fi
OLD="$1"
NEW="$2"
REPS="${REPS:-3}"
CASES="${CASES:-default:scalar default:simd bunny:scalar bunny:simd}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

# user_seconds BIN OUT SCENE PATH: runs one render, prints its user CPU time.
user_seconds() {
    local bin="$1" out="$2" scene="$3" path="$4" args=()
    [ "$scene" != default ] && args+=("$ROOT/scenes/$scene.toml")
    /usr/bin/time -f %U -o "$TMP/time" "$bin" render "${args[@]}" -o "$out" --quiet \
        --threads 1 --path "$path" ${EXTRA:-} >/dev/null
    cat "$TMP/time"
}

median() {
    sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'
}

printf '%-16s %-28s %-28s %s\n' case "old user s" "new user s" "new/old"
status=0
for case in $CASES; do
    scene="${case%%:*}"
    path="${case##*:}"
    old_times=()
    new_times=()
    for ((i = 0; i < REPS; i++)); do
        # Alternate which binary goes first, so neither always runs on a warmer cache.
        if ((i % 2 == 0)); then
            old_times+=("$(user_seconds "$OLD" "$TMP/old.exr" "$scene" "$path")")
            new_times+=("$(user_seconds "$NEW" "$TMP/new.exr" "$scene" "$path")")
        else
            new_times+=("$(user_seconds "$NEW" "$TMP/new.exr" "$scene" "$path")")
            old_times+=("$(user_seconds "$OLD" "$TMP/old.exr" "$scene" "$path")")
        fi
    done
    if ! cmp -s "$TMP/old.exr" "$TMP/new.exr"; then
        echo "$case: the two binaries wrote different images" >&2
        status=1
    fi
    old_med="$(printf '%s\n' "${old_times[@]}" | median)"
    new_med="$(printf '%s\n' "${new_times[@]}" | median)"
    ratio="$(awk -v a="$new_med" -v b="$old_med" 'BEGIN {printf "%.3f", a / b}')"
    printf '%-16s %-28s %-28s %s\n' "$case" "${old_times[*]}" "${new_times[*]}" "$ratio"
done
exit "$status"
