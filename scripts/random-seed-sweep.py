#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""What `ido segment` does from seeds nobody chose: random voxels of the shared scans (inside the
body: above -300 HU for CT, above 0 for the MRA), each run with every organ choice, as a user
clicking anywhere would. Every run must end with a closed, manifold surface free of
self-intersections and of positive volume, or with a one-line error (exit 2) that leaves no
output; a run the work limit stopped must say so (leak_warning); and, unless --max-seconds 0,
each whole process must take at most that long (default 5 s, issue 27's bound). One JSON line
per run on stdout and a summary on stderr; exit 1 when a run breaks one of these, 77 when the
scans are not found (IDO_SHARED_DATA or ../shared/data). Reads the scans with the ido Python
module (PYTHONPATH).

Usage: scripts/random-seed-sweep.py IDO_BINARY [SEEDS_PER_SCAN [RANDOM_SEED]] [--max-seconds S]
"""
import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import time

import numpy as np

import ido

ORGANS = ["generic", "artery", "vein", "vertebra"]


def main() -> int:
    parser = argparse.ArgumentParser(description="random seeds x organ choices on the shared scans")
    parser.add_argument("ido", help="the ido binary")
    parser.add_argument("seeds_per_scan", nargs="?", type=int, default=8)
    parser.add_argument("random_seed", nargs="?", type=int, default=1)
    parser.add_argument("--max-seconds", type=float, default=5.0, help="bound on each run's time; 0: not checked")
    args = parser.parse_args()
    binary, per_scan, rng = args.ido, args.seeds_per_scan, random.Random(args.random_seed)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    data = os.environ.get("IDO_SHARED_DATA", os.path.join(root, "..", "shared", "data"))
    scans = {
        "abdomen-spine": (os.path.join(data, "abdomen-spine", "ct.nii.gz"), -300.0),
        "ctpa": (os.path.join(data, "ctpa", "ct.nii.gz"), -300.0),
        "vmtk-aorta": (os.path.join(data, "vmtk-aorta", "aorta.mha"), 0.0),
        "abdomen-dicom": (os.path.join(data, "abdomen-dicom", "series"), -300.0),
    }
    broken = runs = 0
    slowest = 0.0
    with tempfile.TemporaryDirectory() as work:
        surface, report = os.path.join(work, "s.ply"), os.path.join(work, "r.json")
        for name, (path, level) in scans.items():
            if not os.path.exists(path):
                print(f"random-seed-sweep: {path} not found (set IDO_SHARED_DATA)", file=sys.stderr)
                return 77
            voxels = np.asarray(ido.read_volume(path).array).transpose(2, 1, 0)  # (i, j, k)
            candidates = np.argwhere(voxels > level)
            for _ in range(per_scan):
                v = [int(x) for x in candidates[rng.randrange(len(candidates))]]
                for organ in ORGANS:
                    for f in (surface, report):
                        if os.path.exists(f):
                            os.remove(f)
                    start = time.monotonic()
                    p = subprocess.run([binary, "segment", path, "--seed-voxel", ",".join(map(str, v)), "--organ", organ,
                                        "-o", surface, "--report", report], capture_output=True, text=True, timeout=300)
                    seconds = time.monotonic() - start
                    rec = {"scan": name, "voxel": v, "value": float(voxels[tuple(v)]), "organ": organ,
                           "exit": p.returncode, "seconds": round(seconds, 2)}
                    problems = []
                    if p.returncode == 0:
                        j = json.load(open(report))
                        for key in ("volume_mm3", "euler_characteristic", "stop_reason", "leak_warning"):
                            rec[key] = j[key]
                        rec["leak_events"] = len(j["leak_control"]["events"])
                        if not (j["closed"] and j["manifold"] and j["self_intersections"] == 0 and j["volume_mm3"] > 0):
                            problems.append("invalid surface")
                        if j["stop_reason"] == "work_limit" and not j["leak_warning"]:
                            problems.append("work limit without warning")
                    else:
                        lines = p.stderr.strip().splitlines()
                        rec["error"] = lines[-1] if lines else ""
                        if p.returncode != 2 or len(lines) != 1:
                            problems.append("not a one-line error with exit 2")
                        if os.path.exists(surface) or os.path.exists(report):
                            problems.append("output left behind")
                    if args.max_seconds > 0 and seconds > args.max_seconds:
                        problems.append(f"over {args.max_seconds:g} s")
                    rec["problems"] = problems
                    runs += 1
                    broken += bool(problems)
                    slowest = max(slowest, seconds)
                    print(json.dumps(rec), flush=True)
    print(f"random-seed-sweep: {runs} runs, {broken} broken, slowest {slowest:.2f} s", file=sys.stderr)
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
