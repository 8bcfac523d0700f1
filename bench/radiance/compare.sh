#!/usr/bin/env bash
# Fenestra's direct sun and total annual illuminance of one design against Radiance's
# (direct_sun.sh and five_phase.sh, run first into RADDIR): a job with every design variable
# fixed at DESIGN, run by `fenestra optimize --local` at seeds 1 and 2 (the city office's
# four-variable sampling: 2e7 outdoor paths, 2e5 per sensor indoors, 8 batches), then
# compare.py.
# Usage: bench/radiance/compare.sh SCENE DESIGN RADDIR OUTDIR
#   e.g. bench/radiance/compare.sh examples/city_office/scene.json \
#          alpha=0,width=0.13,spacing=0.07,thickness=0.014 build/bench/radiance/D2 build/bench/fen/D2
set -euo pipefail
cd "$(dirname "$0")/../.."
scene=$(realpath "$1") design=$2 rad=$3 out=$4
fenestra=${FENESTRA:-build/client/fenestra}
mkdir -p "$out"
for seed in 1 2; do
  /usr/bin/python3 - "$scene" "$design" "$seed" > "$out/job_$seed.json" <<'PY'
import json, sys
scene, design, seed = sys.argv[1], sys.argv[2], int(sys.argv[3])
values = dict(kv.split("=") for kv in design.split(","))
print(json.dumps({
    "sceneFile": scene, "name": f"{design}, fixed",
    "sampling": {"outdoorPaths": 20000000, "indoorPathsPerSensor": 200000, "seed": seed,
                 "basisCells": 288, "batches": 8, "finalCheck": False},
    "variables": [{"name": k, "lower": float(v), "upper": float(v), "start": float(v)}
                  for k, v in values.items()],
    "budget": {"maxEvaluations": 1}}, indent=1))
PY
  "$fenestra" optimize --local "$out/job_$seed.json" -o "$out/result_$seed.json" >"$out/run_$seed.log"
done
/usr/bin/python3 bench/radiance/compare.py "$out/result_1.json" "$out/result_2.json" "$rad"
