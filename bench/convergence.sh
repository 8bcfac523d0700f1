#!/usr/bin/env bash
# Error against wall time of both daylight-coefficient methods on both example scenes
# (bench/README.md, "Convergence"): `fenestra convergence` for the light well and the city
# office, one-stage and two-stage (unlimited reflections, the jobs' default, and the source
# publication's limits, 30 outdoors and 5 indoors), against a reference D:
#   light well: Radiance's (tests/data/reference/, 2 x 10^7 paths per sensor, -ab 30);
#   city office: a long one-stage run of this machine, traced first to --target-error
#   REFERENCE_ERROR (with a seed none of the measured runs uses).
# Writes bench/results/convergence_MACHINE_{lightwell,city_office}_{one_stage,two_stage,
# two_stage_30_5}.{csv,svg} and a log of everything printed, bench/results/convergence_MACHINE.txt;
# the city office's reference D goes to OUT/convergence_MACHINE_city_office_reference.mtx
# (OUT: default build/bench, not committed).
#
#   bash bench/convergence.sh [MACHINE] [BACKEND] [MAX_SECONDS] [REFERENCE_ERROR] [REFERENCE_SECONDS] [OUT]
#   bash bench/convergence.sh cpu2 cpu 150 0.004 300    # a 2-core machine (the defaults)
#   bash bench/convergence.sh h100 cuda 60 0.001 300    # a GPU build on an H100
#
# FENESTRA names the executable (default build/client/fenestra); run from the repository root.
set -euo pipefail

machine=${1:-cpu2}
backend=${2:-cpu}
max_seconds=${3:-150}
reference_error=${4:-0.004}
reference_seconds=${5:-300}
fenestra=${FENESTRA:-build/client/fenestra}
out=${6:-build/bench}
results=bench/results
log=$results/convergence_$machine.txt
reference_seed=1000

mkdir -p "$results" "$out"
{
  echo "# bench/convergence.sh $machine $backend $max_seconds $reference_error $reference_seconds"
  echo "# machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) hardware threads"
  if command -v nvidia-smi > /dev/null && [ "$backend" != cpu ]; then
    echo "# GPU: $(nvidia-smi --query-gpu=name --format=csv,noheader | head -1)"
  fi
  echo "# date: $(date -u '+%Y-%m-%d %H:%M UTC'); load average at the start:$(cut -d' ' -f1-3 /proc/loadavg | sed 's/^/ /')"
  echo "# executable: $fenestra ($(git rev-parse --short HEAD 2> /dev/null || echo unknown commit))"
} > "$log"

# Runs fenestra with its output also in the log; returns its exit code.
run() {
  local status=0
  echo "\$ fenestra $*" | tee -a "$log"
  "$fenestra" "$@" 2>&1 | tee -a "$log" || status=$?
  echo "# load average after: $(cut -d' ' -f1-3 /proc/loadavg)" | tee -a "$log"
  return $status
}

# The city office's reference: one-stage to the reference error (exit code 2: the time ran out
# first; the reference is then as good as that time allowed, which the log shows)
city_reference=$out/convergence_${machine}_city_office_reference.mtx
run dc examples/city_office/scene.json --backend "$backend" --seed "$reference_seed" \
  --target-error "$reference_error" --max-seconds "$reference_seconds" -o "$city_reference" ||
  [ $? -eq 2 ]

# Each method with unlimited reflections, as the references (the two-stage method's are the
# jobs' defaults); the two-stage method also with the source publication's reflection limits
# (30 outdoors, 5 indoors), whose bias shows against the reference
declare -A variants=(
  [one_stage]="--method one-stage"
  [two_stage]="--method two-stage --outdoor-bounces -1 --indoor-bounces -1"
  [two_stage_30_5]="--method two-stage --outdoor-bounces 30 --indoor-bounces 5"
)
for scene in lightwell city_office; do
  reference=$city_reference
  [ "$scene" = lightwell ] && reference=tests/data/reference/lightwell_dc_radiance_ab30_2e7.txt
  for variant in one_stage two_stage two_stage_30_5; do
    # shellcheck disable=SC2086 # the variant's flags are words
    run convergence "examples/$scene/scene.json" ${variants[$variant]} --backend "$backend" \
      --reference "$reference" --max-seconds "$max_seconds" \
      -o "$results/convergence_${machine}_${scene}_${variant}"
  done
done
