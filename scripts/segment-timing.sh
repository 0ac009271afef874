#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Interleaved timing of two `ido` builds on the three real cases of ../shared/data (seeds from
# its README): for each case, RUNS × (A, B), one line per run with the process's wall time
# (/usr/bin/time) and the report's balloon seconds, repairs, local repairs and iterations.
# Usage: scripts/segment-timing.sh BEFORE/ido AFTER/ido [RUNS]   (quote medians of the lines)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
data=${IDO_SHARED_DATA:-$root/../shared/data}
a=$1 b=$2 runs=${3:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cases=("ctpa $data/ctpa/ct.nii.gz 33.34,-186.66,693.20"
       "abdomen-dicom $data/abdomen-dicom/series 7.32,-145.52,-782.50"
       "vmtk-aorta $data/vmtk-aorta/aorta.mha -219.73,-174.90,21.00")
for c in "${cases[@]}"; do
  read -r name input seed <<<"$c"
  for _ in $(seq "$runs"); do
    for bin in "$a" "$b"; do
      wall=$({ /usr/bin/time -f "%e" "$bin" -q segment "$input" --seed "$seed" -o "$tmp/s.ply" \
               --report "$tmp/r.json"; } 2>&1 | tail -1)
      figures=$(python3 -c "import json,sys; r=json.load(open(sys.argv[1])); \
print(round(r['seconds'], 3), r['repairs'], r.get('local_repairs', '-'), r['iterations'])" "$tmp/r.json")
      echo "$name $bin wall $wall balloon $figures"
    done
  done
done
