#!/usr/bin/env bash
# Runs every cargo-fuzz target in fuzz/ for SECONDS each (default 60), one after another, and
# prints a summary line per target: executions, and crashes (files in fuzz/artifacts/TARGET/).
#
#   scripts/fuzz.sh 600            # the issue's 10 minutes per target
#   JOBS=2 scripts/fuzz.sh 600     # libFuzzer workers per target (default 1)
#   TARGETS="scene_parse" scripts/fuzz.sh 60
#
# Needs cargo-fuzz (`cargo install cargo-fuzz`) and a nightly toolchain (`rustup toolchain
# install nightly`); without nightly it falls back to the stable compiler with RUSTC_BOOTSTRAP=1,
# which accepts the -Z flags cargo-fuzz passes. The fuzz crate has its own [workspace], so the
# project's `cargo build --workspace` never builds it. Seeds come from scenes/ and ../shared/models.
set -euo pipefail

SECONDS_PER_TARGET="${1:-60}"
JOBS="${JOBS:-1}"
TARGETS="${TARGETS:-scene_parse obj_load ldi_build shapes}"
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
cd "$ROOT/fuzz"

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "cargo-fuzz is not installed: cargo install cargo-fuzz" >&2
    exit 2
fi
if rustup run nightly rustc --version >/dev/null 2>&1; then
    TOOLCHAIN=(+nightly)
else
    echo "no nightly toolchain: using stable with RUSTC_BOOTSTRAP=1" >&2
    export RUSTC_BOOTSTRAP=1
    TOOLCHAIN=()
fi

# Seed corpora (kept out of git; see fuzz/.gitignore).
mkdir -p corpus/scene_parse corpus/obj_load corpus/ldi_build corpus/shapes
cp -n "$ROOT"/scenes/*.toml corpus/scene_parse/ 2>/dev/null || true
cp -n "$ROOT"/tests/data/bad/*.toml corpus/scene_parse/ 2>/dev/null || true
MODELS="$ROOT/../shared/models"
if [ -d "$MODELS" ]; then
    for f in "$MODELS"/bad/*.obj "$MODELS"/cube*.obj "$MODELS"/sphere.obj "$MODELS"/torus.obj; do
        [ -f "$f" ] && cp -n "$f" corpus/obj_load/ 2>/dev/null || true
    done
fi

mkdir -p logs
status=0
for t in $TARGETS; do
    log="logs/$t.log"
    echo "== $t: ${SECONDS_PER_TARGET}s, $JOBS job(s), log fuzz/$log"
    set +e
    parallel=()
    if [ "$JOBS" -gt 1 ]; then
        parallel=(-jobs="$JOBS" -workers="$JOBS")
    fi
    cargo "${TOOLCHAIN[@]}" fuzz run "$t" --release -- \
        -max_total_time="$SECONDS_PER_TARGET" -timeout=20 -rss_limit_mb=4096 \
        -max_len=65536 -print_final_stats=1 "${parallel[@]}" >"$log" 2>&1
    rc=$?
    set -e
    # With -jobs the workers log to fuzz-N.log; take their stats too.
    execs=$(cat "$log" $(find . -maxdepth 1 -name 'fuzz-*.log') \
        | awk '/stat::number_of_executed_units/ {s += $2} END {print s + 0}')
    crashes=$(find "artifacts/$t" -type f \( -name 'crash-*' -o -name 'oom-*' -o -name 'timeout-*' \) 2>/dev/null | wc -l)
    rm -f fuzz-*.log
    echo "$t: exit $rc, $execs executions, $crashes crash/oom/timeout artifact(s) in fuzz/artifacts/$t"
    if [ "$rc" -ne 0 ] || [ "$crashes" -ne 0 ]; then
        status=1
    fi
done
exit $status
