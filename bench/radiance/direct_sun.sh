#!/bin/bash
# Direct sun "where it is" with Radiance: one 0.533-degree sun per sun-up hour, rcontrib at
# -ab 0 (shadow rays only), times the direct normal illuminance gendaymtx gives each hour.
#
# Usage: bench/radiance/direct_sun.sh RADBIN SCENE DESIGN OUTDIR
#   RADBIN  Radiance's bin folder (its lib folder is RADBIN/../lib), e.g.
#           /work/radiance/src/build/bin
#   SCENE   a Fenestra scene, e.g. examples/city_office/scene.json
#   DESIGN  blind values for `fenestra scene export --set`, e.g.
#           alpha=0.58,width=0.15,spacing=0,thickness=0.01
#   OUTDIR  output folder, e.g. build/bench/radiance/D1
# FENESTRA (environment) names the fenestra executable; default build/client/fenestra.
# Writes OUTDIR/direct_sun_lux.txt (sensors x 8760, lx) and direct_sun_summary.txt
# (bench/radiance/README.md).
set -euo pipefail
if [ $# -ne 4 ]; then sed -n 2,13p "$0"; exit 2; fi
RADBIN=$(cd "$1" && pwd); SCENE=$(realpath "$2"); DESIGN=$3; OUT=$4
HERE=$(cd "$(dirname "$0")" && pwd); ROOT=$(cd "$HERE/../.." && pwd)
FENESTRA=${FENESTRA:-$ROOT/build/client/fenestra}
PY=/usr/bin/python3
export PATH=$RADBIN:$PATH RAYPATH=.:$RADBIN/../lib
mkdir -p "$OUT"; OUT=$(cd "$OUT" && pwd)
now() { date +%s.%N; }
t0=$(now)

"$FENESTRA" scene export "$SCENE" --set "$DESIGN" --obj "$OUT/scene.obj"
$PY "$HERE/scene2rad.py" "$SCENE" "$OUT/scene.obj" "$OUT"
EPW=$(awk '{print $4}' "$OUT/site.txt")
t1=$(now)

# Suns from gensky, one per sun-up record
$PY "$HERE/suns.py" "$RADBIN" "$EPW" "$OUT"
t2=$(now)

# Sun-only sky matrix, visible: -d last, since a later -c or -g would restore sky or ground
gendaymtx -m 1 -c 1 1 1 -O0 -d -od "$EPW" > "$OUT/sun_only.mtx"
t3=$(now)

# Sun coefficients at the sensors: shadow rays to every sun's centre, no ambient bounce
oconv "$OUT/materials.rad" "$OUT/geometry.rad" "$OUT/suns.rad" > "$OUT/direct.oct"
rcontrib -I+ -ab 0 -dc 1 -dt 0 -dj 0 -dr 0 -ds 0 -lr 0 -faa -h \
  -M "$OUT/suns.mod" "$OUT/direct.oct" < "$OUT/sensors.pts" > "$OUT/direct_coef.txt"
t4=$(now)

$PY "$HERE/direct_sun.py" "$SCENE" "$OUT"
t5=$(now)
{
  echo "design $DESIGN"
  awk -v a="$t0" -v b="$t1" -v c="$t2" -v d="$t3" -v e="$t4" -v f="$t5" 'BEGIN {
    printf "wall s: scene %.2f, suns (gensky) %.2f, gendaymtx %.2f, rcontrib %.2f, combine %.2f, total %.2f\n",
      b-a, c-b, d-c, e-d, f-e, f-a }'
} > "$OUT/direct_sun_times.txt"
cat "$OUT/direct_sun_times.txt"
