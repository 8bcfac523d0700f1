#!/usr/bin/env bash
# The four city-office experiments (examples/city_office/: alpha_max, alpha_target,
# alpha_width_target, four_variables), each run by `fenestra optimize --local` on one backend,
# with its result file, history CSV and report page, and a summary of what each printed (best
# design, values with errors, the final check, timings).
#
#   bash bench/experiments.sh [MACHINE] [BACKEND] [OUT]
#   bash bench/experiments.sh cpu2 cpu     # a 2-core machine (the defaults)
#   bash bench/experiments.sh h100 cuda    # a GPU build on an H100
#
# Writes the summary bench/results/experiments_MACHINE.txt and, per experiment E, the large
# outputs OUT/experiment_E_MACHINE.{result.json,csv,html} (OUT: default build/bench, not
# committed; bench/final_check_bench reads the cpu2 result files from there).
# FENESTRA names the executable (default build/client/fenestra); run from the repository root.
set -euo pipefail

machine=${1:-cpu2}
backend=${2:-cpu}
fenestra=${FENESTRA:-build/client/fenestra}
out=${3:-build/bench}
results=bench/results
log=$results/experiments_$machine.txt

mkdir -p "$results" "$out"
{
  echo "# bench/experiments.sh $machine $backend: the four city-office experiments, 'fenestra optimize --local --backend $backend'"
  echo "# machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) hardware threads"
  if command -v nvidia-smi > /dev/null && [ "$backend" != cpu ]; then
    echo "# GPU: $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | head -1)"
  fi
  echo "# date: $(date -u '+%Y-%m-%d %H:%M UTC'); load average at the start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "# executable: $fenestra ($(git rev-parse --short HEAD 2> /dev/null || echo unknown commit))"
  echo "# wall: the whole process (start, sky, outdoor stage, search, final check, files)"
} > "$log"

for experiment in alpha_max alpha_target alpha_width_target four_variables; do
  prefix=$out/experiment_${experiment}_$machine
  echo | tee -a "$log"
  echo "## $experiment ($(grep -m1 '"name"' "examples/city_office/$experiment.json" | cut -d'"' -f4))" |
    tee -a "$log"
  start=$(date +%s%N)
  # The live progress line is left out of the log; everything else is kept
  "$fenestra" optimize --local "examples/city_office/$experiment.json" --backend "$backend" \
    -o "$prefix.result.json" --csv "$prefix.csv" --report "$prefix.html" 2>&1 |
    tr '\r' '\n' | grep -v '^\[' | tee -a "$log"
  end=$(date +%s%N)
  echo "wall $(((end - start) / 1000000)) ms; load average after: $(cut -d' ' -f1-3 /proc/loadavg)" |
    tee -a "$log"
done
