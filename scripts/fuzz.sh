#!/usr/bin/env bash
# Fuzz the parsers and loaders for a number of executions (or a time) per target, with the
# settings of the recorded runs (docs/ROBUSTNESS.md, "Fuzzing"). Needs the nightly toolchain
# (preinstalled on the development machines; not used by CI) and cargo-fuzz (installed here if
# missing). Crashes, timeouts and out-of-memory inputs land in fuzz/artifacts/<target>/: fix
# them in the product and add the input as a regression test
# (crates/isotrack-fields/tests/fuzz_regressions.rs and fuzz/seeds/<target>/).
#
#   scripts/fuzz.sh                      # every target, 1 000 000 executions each
#   RUNS=10000000 scripts/fuzz.sh netcdf4 suite
#   SECONDS_PER_TARGET=600 scripts/fuzz.sh grid   # a time instead of a count
#
# Settings (environment):
#   RUNS                 executions per target (libFuzzer -runs; the seeds' first pass counts)
#   SECONDS_PER_TARGET   if set, a time per target instead (-max_total_time)
#   SANITIZER            none (default) or address. The fuzzed crates are safe Rust, so a
#                        sanitizer finds nothing a panic or abort does not; without one a run
#                        makes several times the executions, and `ulimit -v` below works
#                        (AddressSanitizer reserves terabytes of address space).
#   MEM_MB               address-space limit of the fuzzed process (ulimit -v) and libFuzzer's
#                        -rss_limit_mb, default 3072. The loaders' memory budget honours
#                        `ulimit -v`, so a file declaring more than fits is refused, and any
#                        allocation past the limit is a crash, not a machine out of memory.
#   MAX_LEN              largest input, bytes (default 65536: twice the largest seed)
#   TIMEOUT_S            an input slower than this is a defect (default 5)
#   NICE                 niceness (default 19: the machines are shared)
# Runs one target at a time, one job (the other cores are for others). Built optimised with
# debug assertions and overflow checks on (cargo fuzz build -O -a).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! rustup toolchain list | grep -q '^nightly'; then
  echo "error: the nightly toolchain is needed for cargo-fuzz (rustup toolchain list)" >&2
  exit 1
fi
command -v cargo-fuzz >/dev/null 2>&1 || cargo install cargo-fuzz --locked
runs="${RUNS:-1000000}"
san="${SANITIZER:-none}"
mem_mb="${MEM_MB:-3072}"
max_len="${MAX_LEN:-65536}"
timeout_s="${TIMEOUT_S:-5}"
nice_n="${NICE:-19}"
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scenario sweep grid stations series suite netcdf4)
if [ -n "${SECONDS_PER_TARGET:-}" ]; then
  limit=(-max_total_time="$SECONDS_PER_TARGET")
else
  limit=(-runs="$runs")
fi
netcdf_fixtures=crates/isotrack-fields/tests/fixtures/netcdf
for t in "${targets[@]}"; do
  (cd fuzz && nice -n "$nice_n" cargo +nightly fuzz build -O -a -s "$san" "$t")
  bin="fuzz/target/x86_64-unknown-linux-gnu/release/$t"
  mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
  seeds=("fuzz/seeds/$t")
  # The NetCDF readers are seeded with the xarray fixtures (scripts/make-netcdf-fixtures.py).
  case "$t" in netcdf4) seeds+=("$netcdf_fixtures") ;; esac
  echo "== fuzzing $t: ${limit[*]}, sanitizer $san, ulimit -v $mem_mb MiB, max_len $max_len, timeout ${timeout_s}s"
  (
    [ "$san" = none ] && ulimit -v $((mem_mb * 1024))
    exec nice -n "$nice_n" "$bin" "fuzz/corpus/$t" "${seeds[@]}" \
      -artifact_prefix="fuzz/artifacts/$t/" "${limit[@]}" -max_len="$max_len" \
      -timeout="$timeout_s" -rss_limit_mb="$mem_mb" -print_final_stats=1
  )
done
