#!/usr/bin/env bash
# The Python module's tests (docs/python.md): a virtual environment (created once, reused),
# maturin, pytest, NumPy and OpenEXR in it, the module built and installed through pip (maturin
# as its PEP 517 backend, in cargo's target folder: a rebuild compiles only what changed), the
# command line it is compared with, then pytest over python/tests/. Idempotent.
#
#   scripts/python_tests.sh [PYTEST ARGS...]
#
# CONVSHADOW_VENV: the environment's folder (default .venv in the repository).
set -euo pipefail
cd "$(dirname "$0")/.."

venv="${CONVSHADOW_VENV:-.venv}"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
# maturin's PEP 517 hooks run the `maturin` of PATH.
PATH="$(cd "$venv/bin" && pwd):$PATH"
export PATH
pip=("$venv/bin/python" -m pip --disable-pip-version-check --quiet)
# Already satisfied after the first run (nothing downloaded).
"${pip[@]}" install "maturin>=1.9,<2" "pytest>=7" "numpy>=1.21" "OpenEXR>=3.2"
# The module: maturin from the environment (no isolated build environment to download), the
# same release profile and target folder as `cargo test --release`.
"${pip[@]}" install --no-build-isolation --no-deps --force-reinstall ./python
# The binary the tests compare with, as `cargo test --release --workspace` builds it (nothing
# to do after it; a plain `cargo build` would unify features without the dev-dependencies and
# compile most of the tree again).
cargo test --release --workspace --no-run --quiet
target="${CARGO_TARGET_DIR:-target}"
export CONVSHADOW_BIN
CONVSHADOW_BIN="$(cd "$target/release" && pwd)/convshadow"
"$venv/bin/python" -m pytest python/tests -q "$@"
