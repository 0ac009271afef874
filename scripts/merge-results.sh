#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Assembles bench/RESULTS.md from the per-module figure files in bench/results/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out="$root/bench/RESULTS.md"
{
  echo "# Measured figures"
  echo
  echo "Every figure below was measured on the project's 2-core Debian 12 machine (no GPU);"
  echo "the machine is noisy, so times are medians of repetitions. Each section names the"
  echo "command that produced it. Ratios compare against the peer named in the issue, run"
  echo "in the same process or the same script."
  echo
  for f in "$root"/bench/results/*.md; do
    [[ -f "$f" ]] || continue
    cat "$f"
    echo
  done
} > "$out.tmp"
mv "$out.tmp" "$out"
echo "wrote $out"
