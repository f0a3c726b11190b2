#!/usr/bin/env bash
# The Python package's tests: a fresh virtual environment in target/pyenv, the package built
# and installed from ./python (maturin, through pip), then pytest. Needs python3 (>= 3.9) with
# venv; the tests compare against the CLI built by `cargo test --release` / `cargo build --release`.
# Arguments select tests (`scripts/test-python.sh python/tests/test_golden.py`); default: all.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/pyenv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/pip" install -q --upgrade pip
"$venv/bin/pip" install -q maturin numpy pytest "gymnasium>=1.0" "pettingzoo>=1.24" matplotlib pymavlink "mavsdk>=4"
# -v: cargo's crate-by-crate progress (a cold build takes many minutes), not a silent wait.
echo "building the isotrack Python extension (cargo's progress follows)" >&2
"$venv/bin/pip" install -v ./python
[ -x target/release/isotrack ] || cargo build --release --locked -p isotrack-cli
ISOTRACK_BIN="$PWD/target/release/isotrack" "$venv/bin/python" -m pytest -q "${@:-python/tests}"
