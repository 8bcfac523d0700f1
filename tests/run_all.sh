#!/usr/bin/env bash
# Installs the build dependencies, then:
#   1. builds Fenestra (with CUDA when nvcc is there) and runs the whole test suite;
#   2. builds it again with clang, AddressSanitizer and UndefinedBehaviorSanitizer (no CUDA)
#      and runs the whole suite there;
#   3. runs each fuzz target of that build on its seed corpus for a short time.
# Any failure (build, warning, test, sanitizer report, fuzzer crash) fails the script.
# Usage: tests/run_all.sh [build-dir]   (default: build; the sanitizer build goes to
# <build-dir>-sanitize). FENESTRA_FUZZ_SECONDS sets the seconds per fuzz target (10;
# bench/fuzz_campaign.sh runs them for hours).
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/debian_packages.sh
build="${1:-build}"
sanitize_build="$build-sanitize"
fuzz_seconds="${FENESTRA_FUZZ_SECONDS:-10}"
jobs="$(nproc)"
# Tests run one more at a time than there are cores: many daemon tests wait on sockets and
# child processes, and with exactly one per core the cores idle 10-20% of the time
test_jobs=$((jobs + 1))
timings=()
times_file="$(mktemp)"
phase_start=$SECONDS
phase_cpu=0
# end_phase NAME: records the wall time and the CPU time (user + system of the finished child
# processes, from `times`, which must run in this shell) of the phase that just ended.
end_phase() {
  times >"$times_file"
  local cpu
  cpu=$(awk 'NR == 2 {split($1, u, "m"); split($2, s, "m"); printf "%d", u[1] * 60 + u[2] + s[1] * 60 + s[2]}' \
    "$times_file")
  timings+=("$(printf '%-40s %5d s wall %6d s CPU' "$1" $((SECONDS - phase_start)) \
    $((cpu - phase_cpu)))")
  phase_start=$SECONDS
  phase_cpu=$cpu
}
trap 'printf "%s\n" "${timings[@]}"; rm -f "$times_file"' EXIT

# 1. The suite as shipped. nvcc is optional; when present (default CUDA location), the CUDA
# sources are compiled too.
if ! command -v nvcc >/dev/null && [ -x /usr/local/cuda/bin/nvcc ]; then
  export PATH="/usr/local/cuda/bin:$PATH"
fi
# Each target's sources are compiled as one unit (a unity build: the heavy headers parsed once
# per target, not per file), as in the sanitizer build below.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFENESTRA_WARNINGS_AS_ERRORS=ON \
  -DCMAKE_UNITY_BUILD=ON
cmake --build "$build" -j"$jobs"
end_phase "build"
ctest --test-dir "$build" --output-on-failure -j"$test_jobs"
end_phase "tests"

# 2. The suite under AddressSanitizer + UndefinedBehaviorSanitizer. The same build holds
# the fuzz targets, so its libraries carry libFuzzer's coverage instrumentation too. The
# benchmarks, built and so checked above, are left out: nothing here runs them. A unity
# build, as above.
cmake -S . -B "$sanitize_build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CUDA_COMPILER=CUDA-NOTFOUND -DFENESTRA_FUZZ=ON \
  -DFENESTRA_WARNINGS_AS_ERRORS=ON -DFENESTRA_BENCH=OFF -DCMAKE_UNITY_BUILD=ON
cmake --build "$sanitize_build" -j"$jobs"
end_phase "sanitizer build (clang, ASan+UBSan)"
symbolizer="$(command -v llvm-symbolizer || command -v llvm-symbolizer-14 || true)"
export ASAN_SYMBOLIZER_PATH="${symbolizer:-}"
export ASAN_OPTIONS="detect_leaks=1"
export UBSAN_OPTIONS="print_stacktrace=1"
ctest --test-dir "$sanitize_build" --output-on-failure -j"$test_jobs"
end_phase "sanitizer tests"

# 3. Each fuzz target for a short time, as many at once as there are cores.
source tests/fuzz/fuzz_common.sh
work="$sanitize_build/fuzz-run"
rm -rf "$work"
mkdir -p "$work"
failed=()
pids=()
names=()
# wait_first: waits for the oldest running target and records a failure.
wait_first() {
  if ! wait "${pids[0]}"; then failed+=("${names[0]}"); fi
  pids=("${pids[@]:1}")
  names=("${names[@]:1}")
}
for target in "${FUZZ_TARGETS[@]}"; do
  [ "${#pids[@]}" -ge "$jobs" ] && wait_first
  fuzz_run "$sanitize_build" "$work" "$target" "$work/$target.log" \
    -max_total_time="$fuzz_seconds" &
  pids+=($!)
  names+=("$target")
done
while [ "${#pids[@]}" -gt 0 ]; do wait_first; done
for target in "${FUZZ_TARGETS[@]}"; do
  runs="$(grep -o 'stat::number_of_executed_units: [0-9]*' "$work/$target.log" | grep -o '[0-9]*$' ||
    true)"
  printf 'fuzz %-16s %10s executions in %s s\n' "$target" "${runs:-?}" "$fuzz_seconds"
done
for target in "${failed[@]}"; do
  echo "=== fuzz target $target failed; its log ends:"
  tail -n 40 "$work/$target.log"
  ls -l "$work/$target/artifacts"
done
end_phase "fuzzing (${#FUZZ_TARGETS[@]} targets x $fuzz_seconds s)"

if [ "${#failed[@]}" -gt 0 ]; then
  echo "fuzz targets failed: ${failed[*]}" >&2
  exit 1
fi
