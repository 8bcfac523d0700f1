#!/usr/bin/env bash
# The four-variable city-office job (examples/city_office/four_variables.json) with both
# sequences (Sampling.sequence) and seeds 1 to N: per run the best design's UDI with its
# standard error and the job's times, for the efficiency of the Sobol draws in the search
# (bench/README.md). Usage: bench/qmc_jobs.sh FENESTRA [N] [extra optimize flags...]
set -euo pipefail
cd "$(dirname "$0")/.."
fenestra="$1"
runs="${2:-4}"
shift 2 || shift $#
dir=$(mktemp -d)
for sequence in SEQUENCE_PSEUDO_RANDOM SEQUENCE_SOBOL; do
  for seed in $(seq 1 "$runs"); do
    job="$dir/${sequence}_$seed.json"
    sed -e "s|\"sceneFile\": \"scene.json\"|\"sceneFile\": \"$PWD/examples/city_office/scene.json\"|" \
      -e "s|\"seed\": 1,|\"seed\": $seed, \"sequence\": \"$sequence\",|" \
      examples/city_office/four_variables.json >"$job"
    echo "== $sequence seed $seed"
    "$fenestra" optimize --local "$job" -o "$dir/result.json" "$@" 2>&1 |
      grep -E "^best design|^objective|evaluations \(" || true
  done
done
rm -rf "$dir"
