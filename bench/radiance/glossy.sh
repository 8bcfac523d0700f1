#!/usr/bin/env bash
# Every sensor's sky sum of one design with slats of a given material, by Radiance's rcontrib
# and by Fenestra's one-stage and two-stage methods (bench/radiance/README.md, "Glossy and
# metallic slats").
# Usage: bench/radiance/glossy.sh RADBIN SCENE DESIGN SLATS OUTDIR [PATHS] [BACKEND]
#   SLATS    the slats' material as scene JSON, e.g.
#            '{"metal": {"reflectance": 0.8, "specularity": 0.9, "roughness": 0.05}}'
#   PATHS    Radiance's paths per sensor in each of two independent halves (default 500000, a
#            multiple of 8)
#   BACKEND  Fenestra's: cpu (default), cuda, or none (Radiance alone). RADBIN "-" skips
#            Radiance: its halves are read from OUTDIR, as an earlier run left them
# Fenestra's paths: ONE_STAGE_PATHS per sensor (environment, default 4e6), two-stage
# OUTDOOR_PATHS (1e8) and INDOOR_PATHS per sensor (2e6), bounces unlimited; seeds
# ONE_STAGE_SEED (21) and TWO_STAGE_SEED (22).
# Writes OUTDIR/scene.json (SCENE with the slats' material), scene.rad and sensors.pts (by
# `fenestra scene export --rad`), Radiance's halves dc_a.txt and dc_b.txt, Fenestra's logs
# one_stage_BACKEND.log and two_stage_BACKEND.log, and prints the comparison (glossy.py).
set -euo pipefail
if [ $# -lt 5 ]; then sed -n 2,17p "$0"; exit 2; fi
RADBIN=$1; SCENE=$(realpath "$2"); DESIGN=$3; SLATS=$4; OUT=$5
PATHS=${6:-500000}; BACKEND=${7:-cpu}
ONE=${ONE_STAGE_PATHS:-4000000} OUTDOOR=${OUTDOOR_PATHS:-100000000} INDOOR=${INDOOR_PATHS:-2000000}
ONE_SEED=${ONE_STAGE_SEED:-21} TWO_SEED=${TWO_STAGE_SEED:-22}
HERE=$(cd "$(dirname "$0")" && pwd)
FENESTRA=${FENESTRA:-$HERE/../../build/client/fenestra}
mkdir -p "$OUT"; OUT=$(cd "$OUT" && pwd)
now() { date +%s.%N; }

/usr/bin/python3 - "$SCENE" "$SLATS" "$OUT/scene.json" <<'PY'
import json, os, sys
scene_path, slats, out = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3]
scene = json.load(open(scene_path))
folder = os.path.dirname(scene_path)
scene["materials"].append(dict(name="slats", **slats))
scene["blind"]["material"] = "slats"
site = scene.get("site", {})
for key in ("weather_file", "weatherFile"):
    if key in site:
        site[key] = os.path.join(folder, site[key])
for surface in scene.get("surfaces", []):
    if "obj" in surface:
        surface["obj"]["path"] = os.path.join(folder, surface["obj"]["path"])
json.dump(scene, open(out, "w"), indent=1)
PY

if [ "$RADBIN" != "-" ]; then
  export PATH=$(cd "$RADBIN" && pwd):$PATH RAYPATH=.:$(cd "$RADBIN/../lib" && pwd)
  "$FENESTRA" scene export "$OUT/scene.json" --set "$DESIGN" --rad "$OUT/scene.rad" \
    --pts "$OUT/sensors.pts"
  cat > "$OUT/skyglow.rad" <<'RAD'
void glow skyglow
0
0
4 1 1 1 0

skyglow source skyball
0
0
4 0 0 1 360
RAD
  oconv "$OUT/scene.rad" "$OUT/skyglow.rad" > "$OUT/dc.oct"
  # -st 0: every specular lobe sampled (else Radiance folds lobes below its threshold into the
  # diffuse part); each half its own process and seed (faketime), its paths in 8
  # groups per sensor (8 rows), so that the 16 groups' scatter gives the standard error
  half() {
    awk -v n="$PATHS" '{for (i = 0; i < n; i++) print}' "$OUT/sensors.pts" |
      faketime -f "$1 00:00:00" rcontrib -n 1 -I+ -ab 30 -ad 1 -lw 1e-6 -lr 0 -st 0 \
        -c $((PATHS / 8)) -faa -h -e MF:1 -f reinhart.cal -b rbin -bn Nrbins -m skyglow \
        "$OUT/dc.oct" > "$2"
  }
  t0=$(now)
  half 2021-01-01 "$OUT/dc_a.txt" &
  half 2021-01-02 "$OUT/dc_b.txt" &
  wait
  echo "$(echo "$(now) - $t0" | bc)" > "$OUT/radiance_seconds.txt"
fi

[ "$BACKEND" = none ] && exit 0
"$FENESTRA" dc "$OUT/scene.json" --set "$DESIGN" --backend "$BACKEND" --method one-stage \
  --paths "$ONE" --seed "$ONE_SEED" -o "$OUT/one_stage_$BACKEND.txt" > "$OUT/one_stage_$BACKEND.log"
"$FENESTRA" dc "$OUT/scene.json" --set "$DESIGN" --backend "$BACKEND" --method two-stage \
  --outdoor-paths "$OUTDOOR" --indoor-paths "$INDOOR" --seed "$TWO_SEED" -o "$OUT/two_stage_$BACKEND.txt" \
  > "$OUT/two_stage_$BACKEND.log"
/usr/bin/python3 "$HERE/glossy.py" "$OUT" "$BACKEND"
