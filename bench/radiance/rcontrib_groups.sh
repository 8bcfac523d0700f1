#!/usr/bin/env bash
# Radiance's rcontrib for glossy.sh's cases on a machine of many cores: per case 16 processes
# of their own seeds (libfaketime's dates MONTH-01..16, MONTH from the environment, default
# 2022-03), each 192000 paths per sensor in 8 groups (-c 24000), into
# /tmp/r/CASE/dc_MONTH_pK.txt; glossy.py reads every dc_*.txt of a folder, so runs of
# different months add up.
# Usage: bench/radiance/rcontrib_groups.sh DIR CASE...
#   DIR holds rcontrib, reinhart.cal, rayinit.cal, libfaketime.so.1 and per CASE a frozen
#   octree CASE.oct (oconv -f scene.rad skyglow.rad, from glossy.sh's OUTDIR) and CASE.pts
set -euo pipefail
if [ $# -lt 2 ]; then sed -n 2,10p "$0"; exit 2; fi
MONTH=${MONTH:-2022-03}
cd "$1"; shift; export RAYPATH=.:$PWD
chmod +x rcontrib
for c in "$@"; do
  mkdir -p /tmp/r/$c
  s0=$(date +%s)
  for k in $(seq 0 15); do
    awk -v n=192000 '{for (i = 0; i < n; i++) print}' $c.pts |
      LD_PRELOAD=$PWD/libfaketime.so.1 FAKETIME="$MONTH-$(printf %02d $((k + 1))) 00:00:00" \
        ./rcontrib -n 1 -I+ -ab 30 -ad 1 -lw 1e-6 -lr 0 -st 0 -c 24000 -faa -h -e MF:1 \
        -f reinhart.cal -b rbin -bn Nrbins -m skyglow $c.oct > /tmp/r/$c/dc_${MONTH}_p$k.txt &
  done
  wait
  echo "$c ($MONTH): 16 processes x 192000 paths per sensor, $(( $(date +%s) - s0 )) s on $(nproc) cores" | tee -a /tmp/r/times.txt
done
