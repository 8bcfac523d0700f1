#!/usr/bin/env bash
# On a GPU machine without the build's dependencies: unpacks what bench/gpu_pack.sh packed
# (gpu_pack/pack.tar.xz at the repository's root), runs the GPU tests and the benchmarks and
# leaves their outputs in $OUT/results.tar.xz (a summary line per run on stdout).
# Usage: bench/gpu_pack_run.sh [tests|bench|comfort|qmc|all]
set -u
cd "$(dirname "$0")/.."
tar xJf gpu_pack/pack.tar.xz -C gpu_pack
export LD_LIBRARY_PATH=$PWD/gpu_pack/root/lib
B=$PWD/gpu_pack/root/bin
# The tests look for their data where the packed build's sources were
source_dir="$(cat gpu_pack/root/source_dir)"
if [ "$source_dir" != "$PWD" ] && [ ! -e "$source_dir" ]; then
  mkdir -p "$(dirname "$source_dir")" && ln -s "$PWD" "$source_dir" || echo "no link to $source_dir"
fi
R=$(mktemp -d)
OUT="${OUT:-$PWD/gpu_pack/out}"
mkdir -p "$OUT"
nvidia-smi --query-gpu=name,driver_version --format=csv > "$R/gpu.txt" 2>&1; nproc >> "$R/gpu.txt"
run() { local name=$1; shift; local t0=$SECONDS; "$@" > "$R/$name.txt" 2>&1; echo "$name rc=$? $((SECONDS - t0)) s" | tee -a "$R/summary.txt"; }
case "${1:-all}" in
  tests|all)
    run cuda_backend_test $B/cuda_backend_test
    run cuda_tracer_test $B/cuda_tracer_test
    run annual_tally_test $B/annual_tally_test
    run optimize_gpu $B/optimize_test --gtest_filter='*Gpu*'
    ;;&
  bench|all)
    run job_corner $B/gpu_bench job 4 examples/corner_office/tilt_and_spacing.json
    run job_city $B/gpu_bench job 4
    run cpu_corner $B/fenestra optimize --local examples/corner_office/tilt_and_spacing.json --backend cpu -o "$R/cpu_corner.json"
    ;;
  qmc)
    run qmc $B/qmc_bench cuda "${2:-32}"
    run qmc_jobs bash bench/qmc_jobs.sh $B/fenestra "${3:-4}"
    ;;
  comfort)
    F="$B/fenestra optimize --local"
    for k in 1 2; do
      run pareto_$k $F examples/sunny_office/pareto_sda_glare.json -o "$R/pareto_$k.json"
      run plain_$k $F bench/comfort/sda_plain.json -o "$R/plain_$k.json"
      run glare_$k $F bench/comfort/sda_glare.json -o "$R/glare_$k.json"
      run gain_$k $F bench/comfort/sda_gain.json -o "$R/gain_$k.json"
    done
    run cpu_plain $F bench/comfort/sda_plain.json --backend cpu -o "$R/cpu_plain.json"
    run cpu_glare $F bench/comfort/sda_glare.json --backend cpu -o "$R/cpu_glare.json"
    run cuda_backend_test $B/cuda_backend_test
    ;;
esac
tar cJf "$OUT/results.tar.xz" -C "$R" .
