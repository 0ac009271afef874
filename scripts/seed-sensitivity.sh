#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# How much a real-data segmentation depends on where exactly the seed is: runs `ido segment`
# from the README's seed and from six seeds STEP mm away along ±x, ±y, ±z, and scores each
# against the reference with `ido compare`. One line per seed: Dice, HD95, volume ratio,
# Euler characteristic, iterations, seconds.
# Usage: scripts/seed-sensitivity.sh IDO_BINARY CASE [STEP_MM [SEGMENT_OPTION...]]
#   CASE: abdomen | ctpa | ctpa-roi | vmtk    (data in ../shared/data, seeds from its README)
#   SEGMENT_OPTION: passed on to every `ido segment` (e.g. --edge-reach 2)
set -euo pipefail
ido=${1:?usage: seed-sensitivity.sh IDO_BINARY CASE [STEP_MM]}
case_name=${2:?usage: seed-sensitivity.sh IDO_BINARY CASE [STEP_MM]}
step=${3:-0.5}
shift $(( $# < 3 ? $# : 3 ))
root=$(cd "$(dirname "$0")/.." && pwd)
data=${IDO_SHARED_DATA:-$root/../shared/data}
extra=("$@")
compare=()
case "$case_name" in
  abdomen) ct=$data/abdomen-dicom/series; truth=$data/abdomen-dicom/aorta.nii.gz; seed=(7.32 -145.52 -782.50) ;;
  ctpa) ct=$data/ctpa/ct.nii.gz; truth=$data/ctpa/pulmonary_artery.nii.gz; seed=(33.34 -186.66 693.20) ;;
  # The reference's bounding box grown by 10 mm on every side (world LPS mm), as issue 4 allows.
  ctpa-roi) ct=$data/ctpa/ct.nii.gz; truth=$data/ctpa/pulmonary_artery.nii.gz; seed=(33.34 -186.66 693.20)
            extra+=(--roi -62.16,-213.16,666.7,62.84,-110.66,733.2) ;;
  vmtk) ct=$data/vmtk-aorta/aorta.mha; truth=$data/vmtk-aorta/aorta-reference-levelset.mha; seed=(-219.73 -174.90 21.00)
        compare=(--truth-below 0) ;;
  *) echo "seed-sensitivity.sh: unknown case '$case_name' (abdomen, ctpa, ctpa-roi, vmtk)" >&2; exit 2 ;;
esac
[[ -e "$ct" ]] || { echo "seed-sensitivity.sh: $ct not found (set IDO_SHARED_DATA)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
offsets=("0 0 0" "$step 0 0" "-$step 0 0" "0 $step 0" "0 -$step 0" "0 0 $step" "0 0 -$step")
for off in "${offsets[@]}"; do
  read -r dx dy dz <<< "$off"
  s=$(awk -v x="${seed[0]}" -v y="${seed[1]}" -v z="${seed[2]}" -v a="$dx" -v b="$dy" -v c="$dz" \
      'BEGIN { printf "%.4f,%.4f,%.4f", x + a, y + b, z + c }')
  "$ido" -q segment "$ct" --seed "$s" "${extra[@]}" -o "$work/s.ply" --mask "$work/m.nii.gz" --report "$work/r.json" > /dev/null
  "$ido" compare --mask "$work/m.nii.gz" --truth "$truth" "${compare[@]}" --json > "$work/c.json"
  /usr/bin/python3 - "$work/c.json" "$work/r.json" "$s" "$off" <<'PY'
import json, sys
c = json.load(open(sys.argv[1])); r = json.load(open(sys.argv[2]))
print(f"seed {sys.argv[3]} (offset {sys.argv[4].replace(' ', ',')}): Dice {c['dice']:.4f}  HD95 {c['hd95_mm']:.1f} mm  "
      f"volume ratio {c['volume_ratio']:.2f}  Euler {r['euler_characteristic']}  {r['iterations']} iterations  {r['seconds']:.1f} s")
PY
done
