#!/usr/bin/env bash
# Regenerates the leaderboard in COMPARISON.md: runs the standard suite (recorded gains) and
# puts its leaderboard.md between the markers. About 20 s on 2 cores after the build.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked -p isotrack-cli
out=out/standard-v2
rm -rf "$out"
target/release/isotrack benchmark suites/standard-v2.toml --out "$out" >/dev/null
awk -v board="$out/leaderboard.md" '
  /<!-- leaderboard:begin -->/ { print; while ((getline line < board) > 0) print line; skip = 1; next }
  /<!-- leaderboard:end -->/ { skip = 0 }
  !skip { print }
' COMPARISON.md > COMPARISON.md.new
mv COMPARISON.md.new COMPARISON.md
echo "COMPARISON.md: leaderboard from $out"
