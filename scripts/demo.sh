#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `make demo`: the whole ido chain on the embedded default, a generated CT phantom of a
# vertebra next to the aorta, then (when ../shared/data or $IDO_SHARED_DATA is present) the aorta of a real scan.
# Says where the results and pictures are.
set -euo pipefail
ido=${1:-build/release/bin/ido}
root=$(cd "$(dirname "$0")/.." && pwd)
ido=$(cd "$(dirname "$ido")" && pwd)/$(basename "$ido")
out="$root/demo-output"
rm -rf "$out"
mkdir -p "$out"
cd "$out"
py() { /usr/bin/python3 -c "$@"; }

echo "== 1. A CT phantom: vertebra beside the aorta (HU, 0.8 mm voxels, noise, blur)"
"$ido" phantom spine-aorta -o phantom_ct.nii.gz --labels phantom_labels.nii.gz \
  --spacing 0.8,0.8,0.8 --noise-fraction 0.1 --blur 0.7 --seed 7 \
  --drill-path pedicle_path.csv --json-seeds > phantom.json
"$ido" info phantom_ct.nii.gz | head -8
vessel_seed=$(py 'import json;d=json.load(open("phantom.json"));print(",".join("%.3f"%v for v in [s for s in d["seeds"] if s["label"]==1][0]["world_mm"]))')
bone_seed=$(py 'import json;d=json.load(open("phantom.json"));print(",".join("%.3f"%v for v in [s for s in d["seeds"] if s["label"]==2][0]["world_mm"]))')
echo "   aorta seed $vessel_seed mm, vertebra seed $bone_seed mm"

echo "== 2. Pipeline: segment aorta and vertebra, mesh the vertebra, drill a pedicle-screw path"
echo "      (density from the phantom's HU), deform the aorta segment"
"$ido" pipeline phantom_ct.nii.gz --seed "$vessel_seed" --bone-seed "$bone_seed" \
  --truth phantom_labels.nii.gz --drill-path pedicle_path.csv --tool sphere:radius=2 \
  --max-depth 2 --deform --deform-steps 40 -o pipeline

echo "== 3. Format conversions of the results"
"$ido" convert pipeline/bone_tets.vtu pipeline/bone_tets.msh
"$ido" convert pipeline/vessel_surface.stl pipeline/vessel_surface.ply
"$ido" info pipeline/vessel_surface.ply | head -12

# The real scans: ../shared/data beside the checkout, or $IDO_SHARED_DATA (as for the tests).
shared="${IDO_SHARED_DATA:-$root/../shared/data}"
missing=()
[[ -d "$shared/abdomen-dicom/series" ]] || missing+=("$shared/abdomen-dicom/series (step 4)")
[[ -f "$shared/ctpa/ct.nii.gz" ]] || missing+=("$shared/ctpa/ct.nii.gz (step 5)")
[[ -f "$shared/abdomen-spine/ct.nii.gz" ]] || missing+=("$shared/abdomen-spine/ct.nii.gz (step 6)")
if (( ${#missing[@]} > 0 )); then
  echo "== Real scans not found, so skipped. Looked for:"
  printf '     %s\n' "${missing[@]}"
  if [[ -n "${IDO_SHARED_DATA:-}" ]]; then
    echo "   (IDO_SHARED_DATA=$IDO_SHARED_DATA)"
  else
    echo "   (IDO_SHARED_DATA is not set, so ../shared/data beside the checkout was used)"
  fi
  echo "   To run them, point IDO_SHARED_DATA at the folder that holds abdomen-dicom/ and ctpa/:"
  echo "     IDO_SHARED_DATA=/path/to/shared/data make demo"
fi
if [[ -d "$shared/abdomen-dicom/series" ]]; then
  echo "== 4. A real scan: the abdominal aorta from the DICOM series in $shared"
  "$ido" info "$shared/abdomen-dicom/series" | head -6
  # One seed and the organ choice (docs/segmentation.md, "Organ choices")
  "$ido" segment "$shared/abdomen-dicom/series" --seed-voxel 263,299,11 --organ artery \
    -o real_aorta.stl --mask real_aorta_mask.nii.gz --report real_aorta_report.json
  "$ido" compare --mask real_aorta_mask.nii.gz --truth "$shared/abdomen-dicom/aorta.nii.gz" || true
  "$ido" render real_aorta.stl -o real_aorta.png
fi
if [[ -f "$shared/ctpa/ct.nii.gz" ]]; then
  echo "== 5. A real scan: the pulmonary arteries of a CT pulmonary angiogram in $shared"
  # --organ artery: the lumen, as the reference draws it (docs/segmentation.md, "Organ choices")
  "$ido" segment "$shared/ctpa/ct.nii.gz" --seed 33.34,-186.66,693.20 --organ artery \
    -o real_pulmonary.stl --mask real_pulmonary_mask.nii.gz --report real_pulmonary_report.json
  "$ido" compare --mask real_pulmonary_mask.nii.gz --truth "$shared/ctpa/pulmonary_artery.nii.gz" || true
  "$ido" render real_pulmonary.stl -o real_pulmonary.png
fi
if [[ -f "$shared/abdomen-spine/ct.nii.gz" ]]; then
  echo "== 6. A real scan: one lumbar vertebra (L3) from one seed, to tetrahedra, in $shared"
  # The bone balloon takes the vertebra choice: kept apart from L2 and L4 (docs/segmentation.md)
  "$ido" pipeline "$shared/abdomen-spine/ct.nii.gz" --bone-seed-voxel 58,45,74 \
    --truth "$shared/abdomen-spine/vertebrae.nii.gz" --bone-label 29 -o real_vertebra
  grep -E "^\| (segment bone|tetrahedral mesh)" real_vertebra/summary.md || true
fi

echo
echo "Demo results are in $out"
echo "  summary with pictures:  $out/pipeline/summary.md"
echo "  whole-run report:       $out/pipeline/report.json"
echo "  pictures:               $(cd "$out" && ls pipeline/*.png pipeline/deformation/*.png *.png 2>/dev/null | tr '\n' ' ')"

# The one command that opens the results in the window (docs/viewer.md): the CT (Segment,
# F1), the surfaces and the drilled surface (Scene, F2), the vertebra's tetrahedra first among
# the meshes, so Mesh (F3) shows them and Drill (F4, p) replays the pedicle path on them, and
# the deformation scene (Deform, F5). Without a display, prefix it with xvfb-run -a.
view=(phantom_ct.nii.gz pipeline/bone_tets.vtu pipeline/vessel_surface.stl pipeline/bone_surface.stl
      pipeline/drilled_surface.stl pipeline/deformation/scene.json)
view_args=("$ido" view)
for f in "${view[@]}"; do
  if [[ -f "$out/$f" ]]; then view_args+=("$out/$f"); fi
done
if [[ -f "$out/pedicle_path.csv" ]]; then view_args+=(--drill-replay "$out/pedicle_path.csv"); fi
echo "  open them in the window:"
echo "    $(printf '%q ' "${view_args[@]}")"
