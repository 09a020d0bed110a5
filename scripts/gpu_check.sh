#!/usr/bin/env bash
# The GPU port on a real GPU (issue 45): prepared here, run there in one command.
#
#   scripts/gpu_check.sh bundle        # on the build machine: binaries, models, Vulkan loader
#   scripts/gpu_check.sh run [OUT]     # on the GPU machine (or here, on lavapipe): the checks
#
# `bundle` builds what `run` needs so that the GPU machine needs no compiler: the release
# `convshadow` binary and the GPU test binary (`tests/gpu`), stripped, into `.gpu_bundle/`, with
# the meshes of `../shared/models` the example scenes and GPU tests read, and the Vulkan loader
# packages (libvulkan1 and the GL/EGL vendor-neutral libraries) into `.gl/` as the device
# README says. Both folders are listed in `.git/info/exclude`; carry them to the device:
#
#   run(command="bash scripts/gpu_check.sh run $OUT", carry=[".gpu_bundle", ".gl"])
#
# `run` unpacks the loader where none is installed, points Vulkan at the NVIDIA driver where
# its ICD file is, then
#   1. runs the GPU tests against the adapter the port picks (a hardware one first), one thread,
#      with CI set (a skipped test would be a failure);
#   2. renders the default scene and the paper's case (768², 600 slabs, one light, ellipse2:
#      scripts/gpu/paper768.toml) on `--backend gpu` (3 runs, for the frame time) and
#      `--backend cpu`, keeping each run's `--stats-json`;
#   3. diffs each CPU/GPU pair (`convshadow diff --json`: ULP histogram, max abs error, FLIP);
#   4. writes OUT/gpu_check.json (adapter, the tests' result, per scene: image hashes, bits
#      equal or not, the diff's numbers, wall and stage times) and OUT/gpu_check.log.
# Exit 0 when the tests passed (equal bits are reported, not required: on hardware they are
# what is being measured).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUNDLE="$ROOT/.gpu_bundle"
GL="$ROOT/.gl"

bundle() {
  cd "$ROOT"
  grep -qx '/.gpu_bundle/' .git/info/exclude 2>/dev/null || echo '/.gpu_bundle/' >>.git/info/exclude
  grep -qx '/.gl/' .git/info/exclude 2>/dev/null || echo '/.gl/' >>.git/info/exclude
  rm -rf "$BUNDLE"
  mkdir -p "$BUNDLE/models"
  # The test binary as `cargo test --release --workspace` builds it (same features).
  local tests
  tests=$(cargo test --release --test gpu --no-run --message-format=json 2>/dev/null |
    python3 -c 'import json,sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == "gpu" and m.get("executable"):
        print(m["executable"])')
  [ -x "$tests" ] || { echo "gpu_check: no GPU test binary built" >&2; exit 1; }
  cargo build --release --quiet --bin convshadow
  local target="${CARGO_TARGET_DIR:-$ROOT/target}"
  strip -o "$BUNDLE/convshadow" "$target/release/convshadow"
  strip -o "$BUNDLE/gpu-tests" "$tests"
  # The tests find scenes and models through the path they were built in.
  echo "$ROOT" >"$BUNDLE/manifest_dir"
  if [ -d "$ROOT/../shared/models" ]; then
    cp "$ROOT"/../shared/models/*.obj "$BUNDLE/models/"
  else
    echo "gpu_check: ../shared/models not found: the model tests will fail on the device" >&2
  fi
  # The Vulkan loader, as .debs to unpack on the device (device README).
  mkdir -p "$GL" /tmp/amd64/partial
  local o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
  apt-get "${o[@]}" update -qq
  (cd "$GL" && apt-get "${o[@]}" download -qq libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
  du -sh "$BUNDLE" "$GL"
}

run() {
  local out="${1:-$ROOT/gpu_check_out}"
  mkdir -p "$out"
  local log="$out/gpu_check.log"
  : >"$log"
  say() { echo "$*" | tee -a "$log"; }
  [ -x "$BUNDLE/convshadow" ] || { say "gpu_check: no bundle (run 'scripts/gpu_check.sh bundle' first)"; exit 1; }
  # The Vulkan loader: unpacked from .gl where the machine has none.
  if ! ldconfig -p | grep -q 'libvulkan.so.1'; then
    for f in "$GL"/*.deb; do dpkg -x "$f" /; done
    ldconfig
  fi
  # Keeps the Vulkan loader quiet about a missing runtime folder (the tests' in-process devices).
  export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
  chmod 700 "$XDG_RUNTIME_DIR"
  local icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
  if [ -f "$icd" ] && [ -z "${VK_DRIVER_FILES:-}" ]; then
    export VK_DRIVER_FILES="$icd"
    export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  fi
  if command -v nvidia-smi >/dev/null; then
    nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | tee -a "$log" || true
  fi
  # The tests' compile-time paths: the build's repository (scenes) and ../shared/models beside it.
  local built
  built=$(cat "$BUNDLE/manifest_dir")
  if [ ! -e "$built" ]; then
    mkdir -p "$(dirname "$built")"
    ln -s "$ROOT" "$built"
  fi
  if [ ! -e "$built/../shared/models" ]; then
    mkdir -p "$built/../shared"
    ln -s "$BUNDLE/models" "$built/../shared/models"
  fi
  local bin="$BUNDLE/convshadow"

  say "== 1. GPU tests (tests/gpu) on the adapter the port picks"
  local tests_rc=0
  (cd "$built" && CI=true "$BUNDLE/gpu-tests" --test-threads=1 2>&1) | tee -a "$log" || tests_rc=$?

  say "== 2. renders, CPU and GPU"
  local scenes=("default:" "paper768:$ROOT/scripts/gpu/paper768.toml")
  for entry in "${scenes[@]}"; do
    local name=${entry%%:*} path=${entry#*:}
    local args=()
    [ -n "$path" ] && args=("$path")
    "$bin" render "${args[@]}" --backend cpu -q -o "$out/$name.cpu.exr" \
      --stats-json "$out/$name.cpu.json" 2>&1 | tee -a "$log"
    for k in 1 2 3; do
      "$bin" render "${args[@]}" --backend gpu -q -o "$out/$name.gpu.exr" \
        --stats-json "$out/$name.gpu$k.json" 2>&1 | tee -a "$log"
    done
    say "== 3. diff $name: cpu vs gpu"
    "$bin" diff "$out/$name.cpu.exr" "$out/$name.gpu.exr" --json "$out/$name.diff.json" 2>&1 |
      tee -a "$log" || true
  done

  python3 - "$out" "$tests_rc" <<'EOF' | tee -a "$log"
import json, sys, os
out, tests_rc = sys.argv[1], int(sys.argv[2])
def load(name):
    with open(os.path.join(out, name)) as f:
        return json.load(f)
summary = {"tests_exit_code": tests_rc, "scenes": {}}
for name in ["default", "paper768"]:
    cpu = load(f"{name}.cpu.json")
    gpus = [load(f"{name}.gpu{k}.json") for k in (1, 2, 3)]
    diff = load(f"{name}.diff.json")
    summary["adapter"] = gpus[0].get("adapter")
    best = min(gpus, key=lambda g: g["seconds_total"])
    summary["scenes"][name] = {
        "size": [cpu["width"], cpu["height"]], "slabs": cpu["slabs"], "lights": cpu["lights"],
        "cpu_image_hash": cpu["image_hash"], "gpu_image_hash": gpus[0]["image_hash"],
        "bits_equal": cpu["image_hash"] == gpus[0]["image_hash"],
        "ldi_hash_equal": cpu["ldi_hash"] == gpus[0]["ldi_hash"],
        "gpu_runs_agree": len({g["image_hash"] for g in gpus}) == 1,
        "cpu_seconds_total": cpu["seconds_total"], "cpu_threads": cpu["threads"],
        "gpu_seconds_total": [g["seconds_total"] for g in gpus],
        "gpu_best": {k: best[k] for k in ("seconds_ldi", "seconds_plan", "seconds_sweep", "seconds_total")},
        "gpu_frames_per_second": 1.0 / best["seconds_total"],
        "gpu_pixel_slab_lights_per_second": best["pixel_slab_lights_per_second"],
        "diff": diff,
    }
with open(os.path.join(out, "gpu_check.json"), "w") as f:
    json.dump(summary, f, indent=2)
for name, s in summary["scenes"].items():
    print(f"{name}: bits equal {s['bits_equal']}, GPU {s['gpu_best']['seconds_total']:.3f} s "
          f"({s['gpu_frames_per_second']:.1f} frames/s), CPU {s['cpu_seconds_total']:.3f} s")
print(f"adapter: {summary['adapter']}; GPU tests exit code {tests_rc}")
EOF
  return "$tests_rc"
}

case "${1:-}" in
  bundle) bundle ;;
  run) shift; run "$@" ;;
  *) sed -n '2,6p' "$0"; exit 2 ;;
esac
