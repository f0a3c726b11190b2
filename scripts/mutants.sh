#!/usr/bin/env bash
# Mutation testing (cargo-mutants) of one source file: every mutant of FILE is built and the tests
# of its package run against it; a mutant the tests do not catch is a claim nothing guards.
#   scripts/mutants.sh crates/isotrack-sim/src/metrics.rs [more cargo-mutants options]
#   JOBS=1 scripts/mutants.sh ...            (parallel builds, default 2)
# Results in out/mutants/mutants.out/ (caught.txt, missed.txt, unviable.txt, timeout.txt).
# docs/MUTANTS.md records the per-crate counts and the survivors judged harmless.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ] || [ ! -f "$1" ]; then
  echo "usage: scripts/mutants.sh FILE [cargo-mutants options]" >&2
  exit 64
fi
command -v cargo-mutants >/dev/null 2>&1 || cargo install --locked cargo-mutants
file=$1
shift
mkdir -p out/mutants
# Tests built with light optimisation and no debug info: the end-to-end tests run several times
# faster than at opt-level 0, which matters when they run once per mutant.
export CARGO_PROFILE_DEV_OPT_LEVEL=${CARGO_PROFILE_DEV_OPT_LEVEL:-1}
export CARGO_PROFILE_DEV_DEBUG=${CARGO_PROFILE_DEV_DEBUG:-0}
export CARGO_PROFILE_TEST_DEBUG=${CARGO_PROFILE_TEST_DEBUG:-0}
cargo mutants --file "$file" -j "${JOBS:-2}" --timeout 120 -o out/mutants "$@"
