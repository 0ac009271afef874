#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs every libFuzzer target in BUILD_DIR for SECONDS each, seeded from tests/data.
set -euo pipefail
build=${1:-build/fuzz}; seconds=${2:-30}
root=$(cd "$(dirname "$0")/.." && pwd)
status=0
for bin in "$build"/fuzz/fuzz_*; do
  [[ -x "$bin" ]] || continue
  name=$(basename "$bin")
  corpus="$build/corpus/$name"; mkdir -p "$corpus"
  seeds="$root/tests/data/fuzz-seeds/${name#fuzz_}"
  echo "== $name ($seconds s)"
  if ! "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 "$corpus" ${seeds:+$( [[ -d $seeds ]] && echo "$seeds")} 2>"$build/$name.log"; then
    echo "   FAILED: see $build/$name.log"; tail -30 "$build/$name.log"; status=1
  else
    grep -E "^Done|stat::number_of_executed_units" "$build/$name.log" | tail -1 || true
  fi
done
exit $status
