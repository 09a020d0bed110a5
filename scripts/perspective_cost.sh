#!/usr/bin/env bash
# The perspective camera's cost against the orthographic one (issue 42; docs/performance.md,
# "The perspective eye pass"): scenes/bunny.toml as it is and seen in perspective (the eye 4 in
# front of the model, fov 33.4°, so that the look_at plane shows the orthographic 2.4-wide view),
# 512², 256 slabs, one thread, alternating; with two binaries, both alternate (same-build ratios
# and old-against-new). Prints each run's total seconds and the medians; checks that each
# binary's two renders keep their bits across binaries. Needs ../shared/models beside the checkout.
#   scripts/perspective_cost.sh BIN [OLD_BIN] [REPS]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
new="$1"; old="${2:-}"; reps="${3:-5}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
models="$(cd "$root/../shared/models" && pwd)" || { echo "../shared/models is missing" >&2; exit 2; }
sed -e 's|^direction = \[0.0, 0.0, 1.0\]$|projection = "perspective"\neye = [0.0, 0.0, -4.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_deg = 33.4|' \
    -e '/^view_width = 2.4/d' \
    -e "s|\"../../shared/models/|\"$models/|" "$root/scenes/bunny.toml" > "$tmp/bunny_perspective.toml"
grep -q 'projection = "perspective"' "$tmp/bunny_perspective.toml" || { echo "scenes/bunny.toml's camera moved" >&2; exit 2; }
bins=("$new"); [ -n "$old" ] && bins=("$old" "$new")
run() {  # run BIN SCENE OUT: prints total seconds
  "$1" render "$2" --size 512x512 --slabs 256 --threads 1 -o "$3" --stats-json "$tmp/s.json" -q >/dev/null
  python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['seconds_total'])" "$tmp/s.json"
}
declare -A times
for _ in $(seq "$reps"); do
  for i in "${!bins[@]}"; do
    times[$i-o]+=" $(run "${bins[$i]}" "$root/scenes/bunny.toml" "$tmp/o$i.png")"
    times[$i-p]+=" $(run "${bins[$i]}" "$tmp/bunny_perspective.toml" "$tmp/p$i.png")"
  done
done
if [ -n "$old" ]; then
  cmp -s "$tmp/o0.png" "$tmp/o1.png" && cmp -s "$tmp/p0.png" "$tmp/p1.png" \
    || { echo "the two binaries wrote different images" >&2; exit 1; }
fi
for i in "${!bins[@]}"; do
  python3 - "${bins[$i]}" "${times[$i-o]}" "${times[$i-p]}" <<'P'
import statistics, sys
o = [float(v) for v in sys.argv[2].split()]
p = [float(v) for v in sys.argv[3].split()]
print(f"{sys.argv[1]}: orthographic {o} median {statistics.median(o):.2f} s; "
      f"perspective {p} median {statistics.median(p):.2f} s; "
      f"ratio of medians {statistics.median(p) / statistics.median(o):.3f}")
P
done
