#!/usr/bin/env bash
# Fuzz the parsers and loaders for a bounded time (default 60 s per target).
# Needs the nightly toolchain (preinstalled on the development machines; not used by CI) and
# cargo-fuzz (installed here if missing). Crashes land in fuzz/artifacts/<target>/; fix them and
# add the input as a regression test (crates/isotrack-fields/tests/fuzz_regressions.rs).
#   scripts/fuzz.sh            # every target, 60 s each
#   SECONDS_PER_TARGET=600 scripts/fuzz.sh grid
#   FUZZ_FLAGS="-s none -O" scripts/fuzz.sh   # no sanitizer: 5-10x the executions (safe Rust)
set -euo pipefail
cd "$(dirname "$0")/.."
if ! rustup toolchain list | grep -q '^nightly'; then
  echo "error: the nightly toolchain is needed for cargo-fuzz (rustup toolchain list)" >&2
  exit 1
fi
command -v cargo-fuzz >/dev/null 2>&1 || cargo install cargo-fuzz --locked
secs="${SECONDS_PER_TARGET:-60}"
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scenario sweep grid stations series suite netcdf4)
for t in "${targets[@]}"; do
  echo "== fuzzing $t for ${secs}s"
  mkdir -p "fuzz/corpus/$t"
  (cd fuzz && cargo +nightly fuzz run ${FUZZ_FLAGS:-} "$t" "corpus/$t" "seeds/$t" -- -max_total_time="$secs" -timeout=10 -rss_limit_mb=4096)
done
