#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs every benchmark binary in BUILD_DIR/bench (median of repetitions) and prints results.
set -euo pipefail
build=${1:-build/bench}
for bin in "$build"/bench/*/bench_*; do
  [[ -x "$bin" ]] || continue
  echo "== $(basename "$bin")"
  "$bin" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
done
