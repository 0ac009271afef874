#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The leak phantoms' pictures in docs/segmentation.md: each phantom at the accuracy suite's noise
# (20 % of the contrast) and blur (0.7 voxel), one seed, segmented with leak control off and on,
# drawn with the CT slice through the seed. Usage: scripts/leak-pictures.sh BUILD_DIR OUT_DIR
set -euo pipefail
build=${1:-build/release}
out=${2:-docs/images}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"
PYTHONPATH="$build/python" /usr/bin/python3 - "$tmp" <<'PY'
import json, sys
import ido
tmp = sys.argv[1]
cases = {"valve-chamber": "generic", "vein-in-parenchyma": "generic", "vertebra-stack": "vertebra", "lung-seed": "generic"}
facts = {}
for kind, organ in cases.items():
    contrast = ido.phantom(kind).contrast_hu
    ph = ido.phantom(kind, noise_hu=0.2 * contrast, blur_voxels=0.7, seed=1)
    ido.write_volume(f"{tmp}/{kind}.nii.gz", ph.ct)
    seed = [round(x) for x in ph.ct.world_to_index(ph.seeds[0])] if hasattr(ph.ct, "world_to_index") else [int(round((c - 0.5) / s)) for c, s in zip(ph.seeds[0], ph.ct.spacing)]
    for on in (False, True):
        r = ido.segment(ph.ct, seeds=[ph.seeds[0]], organ=organ, leak_control=on)
        name = f"{kind}-{'on' if on else 'off'}"
        ido.write_mesh(f"{tmp}/{name}.ply", r.surface)
        ido.write_volume(f"{tmp}/{name}-mask.nii.gz", ido.surface_to_mask(r.surface, ph.ct))
        s = ido.compare(ido.surface_to_mask(r.surface, ph.ct), ph.labels)
        facts[name] = {"dice": round(s["dice"], 4), "volume_ratio": round(s["volume_ratio"], 2), "slice_i": int(seed[0]),
                       "leaks": [e["cause"] for e in r.report["leak_control"]["events"]]}
# L3 of the shared abdomen-spine scan, when it is found (IDO_SHARED_DATA or ../shared/data).
import os
data = os.environ.get("IDO_SHARED_DATA", "../shared/data")
if os.path.exists(f"{data}/abdomen-spine/ct.nii.gz"):
    ct = ido.read_volume(f"{data}/abdomen-spine/ct.nii.gz")
    ido.write_volume(f"{tmp}/abdomen-spine-l3.nii.gz", ct)
    for on in (False, True):
        r = ido.segment(ct, seed_voxels=[(58, 45, 74)], organ="vertebra", leak_control=on)
        name = f"abdomen-spine-l3-{'on' if on else 'off'}"
        ido.write_mesh(f"{tmp}/{name}.ply", r.surface)
        ido.write_volume(f"{tmp}/{name}-mask.nii.gz", ido.surface_to_mask(r.surface, ct))
        facts[name] = {"slice_i": 58, "volume_ml": round(r.report["volume_mm3"] / 1000, 1),
                       "leaks": [e["cause"] for e in r.report["leak_control"]["events"]]}
json.dump(facts, open(f"{tmp}/facts.json", "w"), indent=1)
PY
for f in "$tmp"/*-o*.ply; do
  name=$(basename "$f" .ply)
  kind=${name%-o*}
  i=$(/usr/bin/python3 -c "import json; print(json.load(open('$tmp/facts.json'))['$name']['slice_i'])")
  "$build/bin/ido" render "$f" "$tmp/$kind.nii.gz" --slice "i:$i" --overlay "$tmp/$name-mask.nii.gz" \
    --camera 90,10 --size 480x400 -o "$out/leak-$name.png" -q
done
cat "$tmp/facts.json"
