#!/usr/bin/env bash
# The Python package's tests: a fresh virtual environment in target/pyenv, the package built
# and installed from ./python (maturin, through pip), then pytest. Needs python3 (>= 3.9) with
# venv; the tests compare against the CLI built by `cargo test --release` / `cargo build --release`.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/pyenv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
"$venv/bin/pip" install -q --upgrade pip
"$venv/bin/pip" install -q maturin numpy pytest "gymnasium>=1.0" matplotlib pymavlink "mavsdk>=4"
"$venv/bin/pip" install -q ./python
[ -x target/release/isotrack ] || cargo build --release --locked -p isotrack-cli
ISOTRACK_BIN="$PWD/target/release/isotrack" "$venv/bin/python" -m pytest -q python/tests
