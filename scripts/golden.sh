#!/usr/bin/env bash
# The golden manifest (tests/golden/MANIFEST.sha256, issue 31): checks that every output it lists
# is unchanged, or with --update regenerates it (the Rust part: crates/isotrack-cli/tests/golden.rs;
# the python/ lines: python/tests/test_golden.py). After --update, list every changed line in the
# commit message with the reason (`git diff tests/golden/MANIFEST.sha256`).
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  --update) export ISOTRACK_GOLDEN_UPDATE=1 ;;
  "") ;;
  *) echo "usage: scripts/golden.sh [--update]" >&2; exit 64 ;;
esac
cargo test --workspace --release --locked --all-features --test golden
# The Python test needs the package built into target/pyenv (scripts/test-python.sh does it).
scripts/test-python.sh python/tests/test_golden.py
if [ "${ISOTRACK_GOLDEN_UPDATE:-}" = 1 ]; then
  git --no-pager diff --stat -- tests/golden/MANIFEST.sha256 || true
fi
