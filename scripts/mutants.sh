#!/usr/bin/env bash
# Mutation testing (cargo-mutants): every mutant is built and the tests of its package run against
# it; a mutant the tests do not catch is a claim nothing guards.
#   scripts/mutants.sh crates/isotrack-sim/src/metrics.rs [more cargo-mutants options]   one file
#   scripts/mutants.sh isotrack-sim [more cargo-mutants options]                          one crate
#   JOBS=1 TIMEOUT=30 OUT=out/mutants-sim scripts/mutants.sh ...
#     (parallel builds, default 2; seconds per test run, default 120; output folder)
# Results in $OUT/mutants.out/ (caught.txt, missed.txt, unviable.txt, timeout.txt).
# docs/MUTANTS.md records the per-crate counts and the survivors judged harmless.
set -euo pipefail
cd "$(dirname "$0")/.."
usage() {
  echo "usage: scripts/mutants.sh FILE|CRATE [cargo-mutants options]" >&2
  exit 64
}
[ $# -ge 1 ] || usage
target=$1
shift
if [ -f "$target" ]; then
  case "$target" in
    crates/*/src/*) package=$(echo "$target" | cut -d/ -f2) ;;
    *) usage ;;
  esac
  select=(--file "$target")
elif [ -d "crates/$target" ]; then
  package=$target
  select=(--package "$target")
else
  usage
fi
command -v cargo-mutants >/dev/null 2>&1 || cargo install --locked cargo-mutants
out=${OUT:-out/mutants}
mkdir -p "$out"
# The `mutants` profile (workspace Cargo.toml) builds every crate at full optimisation except the
# mutated one, which is rebuilt once per mutant and so stays at opt-level 1: the end-to-end tests
# spend their time in optimised code and each rebuild stays short.
# With cargo-nextest the tests of a mutant stop at the first failure (and run across the
# package's test binaries in parallel); without it, `cargo test` (doc tests included).
tool=()
if command -v cargo-nextest >/dev/null 2>&1; then
  tool=(--test-tool=nextest)
fi
cargo mutants "${select[@]}" -j "${JOBS:-2}" --timeout "${TIMEOUT:-120}" -o "$out" --profile mutants \
  "${tool[@]}" --cargo-arg=--config --cargo-arg="profile.mutants.package.$package.opt-level=1" "$@"
