#!/bin/bash
# Annual illuminance with the sun separated (the five-phase idea) and with the sun smeared over
# sky patches, from Radiance daylight coefficients over the 146 Tregenza bins.
#
# Usage: bench/radiance/five_phase.sh RADBIN SCENE DESIGN OUTDIR [PATHS] [DIRECT_PATHS]
#   RADBIN, SCENE, DESIGN, OUTDIR as for direct_sun.sh (run first when
#                 OUTDIR/direct_sun_lux.txt is missing)
#   PATHS         paths per sensor in each of two independent halves of DC (default 1000000)
#   DIRECT_PATHS  the same for D_d (default 4000000)
# Seeds: each half is its own rcontrib process (-n 1) under faketime with its own date.
# Writes OUTDIR/E_five_phase_lux.txt, E_old_lux.txt (sensors x 8760, lx) and
# five_phase_summary.txt (bench/radiance/README.md).
set -euo pipefail
if [ $# -lt 4 ]; then sed -n 2,12p "$0"; exit 2; fi
RADBIN=$(cd "$1" && pwd); SCENE=$(realpath "$2"); DESIGN=$3; OUT=$4
PATHS=${5:-1000000}; DIRECT_PATHS=${6:-4000000}
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3
export PATH=$RADBIN:$PATH RAYPATH=.:$RADBIN/../lib
mkdir -p "$OUT"; OUT=$(cd "$OUT" && pwd)
now() { date +%s.%N; }

[ -s "$OUT/direct_sun_lux.txt" ] || bash "$HERE/direct_sun.sh" "$RADBIN" "$SCENE" "$DESIGN" "$OUT"
$PY "$HERE/scene2rad.py" "$SCENE" "$OUT/scene.obj" "$OUT" --black
EPW=$(awk '{print $4}' "$OUT/site.txt")

# Sky and ground: one glow over the whole sphere, binned by reinhart.cal (MF 1: bin 0 for
# every direction below the horizon, 1..145 the Tregenza patches)
cat > "$OUT/skyglow.rad" <<'EOF'
void glow skyglow
0
0
4 1 1 1 0

skyglow source skyball
0
0
4 0 0 1 360
EOF
oconv "$OUT/materials.rad" "$OUT/geometry.rad" "$OUT/skyglow.rad" > "$OUT/dc.oct"
oconv "$OUT/materials_black.rad" "$OUT/geometry.rad" "$OUT/skyglow.rad" > "$OUT/dc_black.oct"

# One half: AB octree paths date output
half() {
  awk -v n="$3" '{for (i = 0; i < n; i++) print}' "$OUT/sensors.pts" |
    faketime -f "$4 00:00:00" rcontrib -n 1 -I+ -ab "$1" -ad 1 -lw 1e-6 -lr 0 -c "$3" -faa -h \
      -e MF:1 -f reinhart.cal -b rbin -bn Nrbins -m skyglow "$2" > "$5"
}

# DC: -ab 30 (up to 29 reflections), both halves at once on two cores
t0=$(now)
half 30 "$OUT/dc.oct" "$PATHS" 2021-01-01 "$OUT/dc_a.txt" &
half 30 "$OUT/dc.oct" "$PATHS" 2021-01-02 "$OUT/dc_b.txt" &
wait
t1=$(now)
# D_d: every material black, -ab 1: the sky seen straight from the sensor
half 1 "$OUT/dc_black.oct" "$DIRECT_PATHS" 2021-01-03 "$OUT/dd_a.txt" &
half 1 "$OUT/dc_black.oct" "$DIRECT_PATHS" 2021-01-04 "$OUT/dd_b.txt" &
wait
t2=$(now)

# Sky matrices, visible, double precision. -d and -s after -c and -g (-d zeroes sky and
# ground colours; a later -c or -g would set them again).
gendaymtx -m 1 -c 1 1 1 -g 0.2 0.2 0.2 -O0 -s -od "$EPW" > "$OUT/sky_only.mtx"
gendaymtx -m 1 -c 1 1 1 -g 0.2 0.2 0.2 -O0 -d -od "$EPW" > "$OUT/sun_patches.mtx"
gendaymtx -m 1 -c 1 1 1 -g 0.2 0.2 0.2 -r 0 -O0 -od "$EPW" > "$OUT/sky_full.mtx"
t3=$(now)

$PY "$HERE/five_phase.py" "$SCENE" "$OUT"
t4=$(now)
{
  echo "design $DESIGN; DC $PATHS + $PATHS paths per sensor (-ab 30), D_d $DIRECT_PATHS + $DIRECT_PATHS (-ab 1)"
  awk -v a="$t0" -v b="$t1" -v c="$t2" -v d="$t3" -v e="$t4" 'BEGIN {
    printf "wall s (2 processes on 2 cores): DC %.1f, D_d %.1f, gendaymtx x3 %.2f, combine %.2f\n",
      b-a, c-b, d-c, e-d }'
} > "$OUT/five_phase_times.txt"
cat "$OUT/five_phase_times.txt"
