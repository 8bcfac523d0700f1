#!/bin/bash
# evalglare's DGP on rendered fisheye images of the city office's two views, for three hours
# of Montevideo (the sun in view of the first, a clear hour with the sun out of view, an
# overcast hour), beside Fenestra's `fenestra glare` of the same scene, design and hours.
#
# Usage: bench/evalglare/make_reference.sh RADBIN OUTDIR
#   RADBIN  Radiance's bin folder (its lib folder is RADBIN/../lib), e.g. /work/radiance/bin
#   OUTDIR  output folder for the images and tables, e.g. build/bench/evalglare
# FENESTRA (environment) names the fenestra executable; default build/client/fenestra.
# Writes OUTDIR/reference.csv (one row per view and hour, Radiance's figures and Fenestra's)
# and prints it (bench/evalglare/README.md says what each column is).
set -euo pipefail
if [ $# -ne 2 ]; then sed -n 2,11p "$0"; exit 2; fi
RADBIN=$(cd "$1" && pwd); OUT=$2
HERE=$(cd "$(dirname "$0")" && pwd); ROOT=$(cd "$HERE/../.." && pwd)
FENESTRA=${FENESTRA:-$ROOT/build/client/fenestra}
SCENE=$ROOT/tests/data/evalglare/city_office_views.json
EPW=$ROOT/examples/weather/URY_Montevideo.865800_IWEC.epw
DESIGN=alpha=0,spacing=0.1
# Records (0-based index into the EPW's 8760): 2677 April 22 13-14 h (sun in view of the
# first view), 2673 April 22 9-10 h (clear, sun out of view), 2435 April 12 11-12 h (overcast)
RECORDS="2677 2673 2435"
PY=/usr/bin/python3
export PATH=$RADBIN:$PATH RAYPATH=.:$RADBIN/../lib
mkdir -p "$OUT"; OUT=$(cd "$OUT" && pwd)

"$FENESTRA" scene export "$SCENE" --set "$DESIGN" --rad "$OUT/room.rad"
# The views: x y z dx dy dz ux uy uz name, from the scene
$PY - "$SCENE" > "$OUT/views.txt" <<'EOF'
import json, sys
for v in json.load(open(sys.argv[1]))["views"]:
    p, d, u = v["position"], v["direction"], v.get("up", {"x": 0, "y": 0, "z": 1})
    print(p["x"], p["y"], p["z"], d["x"], d["y"], d["z"], u["x"], u["y"], u["z"], v["name"])
EOF

echo "view,month,day,hour,dni_w_m2,dhi_w_m2,ev_rtrace_lx,ev_image_lx,dgp_sun_only,dgp_default" \
  > "$OUT/radiance.csv"
for k in $RECORDS; do
  # EPW fields: month 2, day 3, hour 4 (the hour ending then), DNI 15, DHI 16 [W/m2]
  read -r M D H DNI DHI < <(awk -F, -v k="$k" 'NR == 9 + k {print $2, $3, $4, $15, $16}' "$EPW")
  T=$(awk -v h="$H" 'BEGIN {print h - 0.5}')  # the hour's centre, local standard time
  SKY=$OUT/sky_$k.rad
  gendaylit "$M" "$D" "$T" -a -34.83 -o 56 -m 45 -W "$DNI" "$DHI" -g 0.2 > "$SKY"
  cat >> "$SKY" <<'EOF'

skyfunc glow sky_glow
0
0
4 1 1 1 0

sky_glow source sky
0
0
4 0 0 1 180

skyfunc glow ground_glow
0
0
4 1 1 1 0

ground_glow source ground
0
0
4 0 0 -1 180
EOF
  oconv "$OUT/room.rad" "$SKY" > "$OUT/scene_$k.oct"
  v=0
  while read -r x y z dx dy dz ux uy uz name; do
    IMG=$OUT/view${v}_$k.hdr
    rpict -vta -vp "$x" "$y" "$z" -vd "$dx" "$dy" "$dz" -vu "$ux" "$uy" "$uz" -vh 180 -vv 180 \
      -x 1000 -y 1000 -ps 1 -pj 0 -ab 4 -ad 2048 -as 512 -aa 0.1 -ar 256 -lw 1e-4 \
      "$OUT/scene_$k.oct" > "$IMG" 2> "$OUT/rpict_${v}_$k.log"
    EV=$(echo "$x $y $z $dx $dy $dz" |
      rtrace -I -h -ab 6 -ad 8192 -as 2048 -aa 0.05 -ar 512 -lw 1e-5 "$OUT/scene_$k.oct" |
      rcalc -e '$1=179*(0.265*$1+0.67*$2+0.065*$3)')
    # -b 500000: only pixels above 5e5 cd/m2 are glare sources (the solar disc; the sky's
    # brightest, round the sun, stays below 1e5); the default finds the windows too
    SUN=$(evalglare -d -vta -vh 180 -vv 180 -b 500000 "$IMG" 2>/dev/null | awk '/^dgp,av_lum,E_v/ {print $2, $4}')
    ALL=$(evalglare -vta -vh 180 -vv 180 "$IMG" 2>/dev/null | awk '/^dgp/ {print $2}')
    read -r DGP_SUN EV_IMAGE <<< "$SUN"
    echo "$v,$M,$D,$T,$DNI,$DHI,$EV,$EV_IMAGE,$DGP_SUN,$ALL" >> "$OUT/radiance.csv"
    v=$((v + 1))
  done < "$OUT/views.txt"
done

"$FENESTRA" glare "$SCENE" --set "$DESIGN" --paths 400000 --seed 1 --hourly "$OUT/fenestra_hourly.csv" \
  > "$OUT/fenestra_glare.txt"
$PY - "$OUT" "$RECORDS" <<'EOF'
import csv, sys
out, records = sys.argv[1], [int(k) for k in sys.argv[2].split()]
hourly = list(csv.reader(open(f"{out}/fenestra_hourly.csv")))
rows = list(csv.DictReader(open(f"{out}/radiance.csv")))
with open(f"{out}/reference.csv", "w") as f:
    f.write(",".join(rows[0].keys()) + ",ev_fenestra_lx,ev_fenestra_se_lx,dgp_fenestra\n")
    for row in rows:
        k = next(r for r in records if hourly[1 + r][:2] == [row["month"], row["day"]]
                 and float(hourly[1 + r][2]) == float(row["hour"]))
        v = int(row["view"])
        ev, se, dgp = (hourly[1 + k][3 + 4 * v + i] for i in (0, 1, 3))
        f.write(",".join(row.values()) + f",{ev},{se},{dgp}\n")
EOF
column -s, -t < "$OUT/reference.csv"
