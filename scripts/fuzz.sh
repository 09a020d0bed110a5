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
# project's `cargo build --workspace` never builds it. Seeds come from scenes/, ../shared/models
# and, for PLY, STL and glTF, a tetrahedron in each encoding written below; for OpenVDB,
# scenes/cloud.vdb.
set -euo pipefail

SECONDS_PER_TARGET="${1:-60}"
JOBS="${JOBS:-1}"
TARGETS="${TARGETS:-scene_parse obj_load ply_load stl_load gltf_load ldi_build shapes vdb_load}"
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
mkdir -p corpus/scene_parse corpus/obj_load corpus/ply_load corpus/stl_load corpus/gltf_load \
    corpus/ldi_build corpus/shapes corpus/vdb_load
# OpenVDB: the gallery's cloud, written by OpenVDB itself (scripts/cloud_vdb.py).
cp -n "$ROOT"/scenes/*.vdb corpus/vdb_load/ 2>/dev/null || true
cp -n "$ROOT"/scenes/*.toml corpus/scene_parse/ 2>/dev/null || true
cp -n "$ROOT"/tests/data/bad/*.toml corpus/scene_parse/ 2>/dev/null || true
MODELS="$ROOT/../shared/models"
if [ -d "$MODELS" ]; then
    for f in "$MODELS"/bad/*.obj "$MODELS"/cube*.obj "$MODELS"/sphere.obj "$MODELS"/torus.obj; do
        [ -f "$f" ] && cp -n "$f" corpus/obj_load/ 2>/dev/null || true
    done
fi
# PLY, STL and glTF seeds: a tetrahedron in each encoding (text here, binary through python3
# when it is there); the fuzzer mutates from them.
[ -f corpus/ply_load/tetra_ascii.ply ] || printf '%s\n' ply 'format ascii 1.0' \
    'element vertex 4' 'property float x' 'property float y' 'property float z' \
    'element face 4' 'property list uchar int vertex_indices' end_header \
    '0 0 0' '1 0 0' '0 1 0' '0 0 1' '3 0 2 1' '3 0 1 3' '3 0 3 2' '3 1 2 3' \
    >corpus/ply_load/tetra_ascii.ply
if [ ! -f corpus/stl_load/tetra_ascii.stl ]; then
    {
        echo "solid t"
        for f in "0 0 0;0 1 0;1 0 0" "0 0 0;1 0 0;0 0 1" "0 0 0;0 0 1;0 1 0" "1 0 0;0 1 0;0 0 1"; do
            echo "facet normal 0 0 0"; echo "outer loop"
            IFS=';' read -r a b c <<<"$f"; echo "vertex $a"; echo "vertex $b"; echo "vertex $c"
            echo "endloop"; echo "endfacet"
        done
        echo "endsolid t"
    } >corpus/stl_load/tetra_ascii.stl
fi
if command -v python3 >/dev/null && [ ! -f corpus/gltf_load/tetra.glb ]; then
    python3 - "$ROOT/fuzz/corpus" <<'PY'
import base64, json, struct, sys
out = sys.argv[1]
P = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
T = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
ply += b"".join(struct.pack("<3f", *p) for p in P) + b"".join(struct.pack("<B3i", 3, *t) for t in T)
open(f"{out}/ply_load/tetra_le.ply", "wb").write(ply)
stl = b"solid binary".ljust(80, b" ") + struct.pack("<I", 4)
stl += b"".join(struct.pack("<12fH", 0, 0, 0, *P[a], *P[b], *P[c], 0) for a, b, c in T)
open(f"{out}/stl_load/tetra_bin.stl", "wb").write(stl)
b = b"".join(struct.pack("<3f", *p) for p in P) + b"".join(struct.pack("<3I", *t) for t in T)
def doc(uri):
    buf = {"byteLength": len(b)}
    if uri: buf["uri"] = uri
    return {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "matrix": [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 1, 2, 3, 1]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 1]},
                          {"bufferView": 1, "componentType": 5125, "count": 12, "type": "SCALAR"}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                            {"buffer": 0, "byteOffset": 48, "byteLength": 48}],
            "buffers": [buf]}
open(f"{out}/gltf_load/tetra_embedded.gltf", "w").write(json.dumps(
    doc("data:application/octet-stream;base64," + base64.b64encode(b).decode())))
j = json.dumps(doc(None)).encode()
j += b" " * (-len(j) % 4)
glb = b"glTF" + struct.pack("<II", 2, 12 + 8 + len(j) + 8 + len(b))
glb += struct.pack("<I", len(j)) + b"JSON" + j + struct.pack("<I", len(b)) + b"BIN\0" + b
open(f"{out}/gltf_load/tetra.glb", "wb").write(glb)
PY
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
