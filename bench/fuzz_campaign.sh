#!/usr/bin/env bash
# A fuzzing campaign: every fuzz target at once, each with WORKERS processes sharing one
# corpus, until each target has run RUNS inputs or SECONDS have passed. Writes a table
# (target, executions, time, exec/s, corpus size, crashes, leaks, timeouts, out-of-memory)
# with the machine it ran on.
# Usage: bench/fuzz_campaign.sh [--build DIR] [--runs N] [--seconds S] [--workers K]
#                               [--targets T1,T2,...] [--out FILE]
#   --build    a build configured with -DFENESTRA_FUZZ=ON (clang), default build-sanitize
#              (tests/run_all.sh makes it: build-sanitize)
#   --runs     executions per target (default 10000000), split among its workers
#   --seconds  wall-clock cap per target (default 0 = none)
#   --workers  processes per target (default: cores / targets, at least 1)
#   --targets  which fuzz targets (default all: tests/fuzz/fuzz_common.sh lists them)
#   --out      the table (default bench/results/fuzz_campaign_cpuN.txt, N = this machine's cores)
# New corpus inputs and crashing inputs stay in DIR/fuzz-campaign/<target>/; a crash is
# committed under tests/fuzz/regressions/<target>/ once fixed.
set -euo pipefail
cd "$(dirname "$0")/.."
source tests/fuzz/fuzz_common.sh

build=build-sanitize
runs=10000000
seconds=0
workers=0
out=bench/results/fuzz_campaign_cpu$(nproc).txt
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --seconds) seconds="$2"; shift 2 ;;
    --workers) workers="$2"; shift 2 ;;
    --targets) IFS=, read -r -a FUZZ_TARGETS <<<"$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    *) echo "unknown option $1 (see the top of $0)" >&2; exit 2 ;;
  esac
done
if [ "$workers" -le 0 ]; then
  workers=$(($(nproc) / ${#FUZZ_TARGETS[@]}))
  [ "$workers" -ge 1 ] || workers=1
fi
for target in "${FUZZ_TARGETS[@]}"; do
  if [ ! -x "$build/tests/fuzz/${target}_fuzz" ]; then
    echo "$build/tests/fuzz/${target}_fuzz is missing: configure $build with" \
      "-DCMAKE_CXX_COMPILER=clang++ -DFENESTRA_FUZZ=ON and build it" >&2
    exit 2
  fi
done
work="$build/fuzz-campaign"
mkdir -p "$work"
symbolizer="$(command -v llvm-symbolizer || true)"
export ASAN_SYMBOLIZER_PATH="${symbolizer:-}"

# Every worker of every target at once; worker W of TARGET logs to TARGET.W.log
runs_per_worker=$(((runs + workers - 1) / workers))
rm -rf "$work"/*.log "$work"/*/artifacts  # the corpus grows from one campaign to the next
pids=()
for target in "${FUZZ_TARGETS[@]}"; do
  for ((w = 0; w < workers; ++w)); do
    fuzz_run "$build" "$work" "$target" "$work/$target.$w.log" -runs="$runs_per_worker" \
      -max_total_time="$seconds" -seed=$((w + 1)) &
    pids+=($!)
  done
done
status=0
for pid in "${pids[@]}"; do wait "$pid" || status=1; done

# The table, from each worker's log: executions (libFuzzer's final stats) and seconds ("Done N
# runs in S second(s)")
sum_stat() {  # sum_stat NAME LOG...
  cat "${@:2}" | { grep -ao "stat::$1: [0-9]*" || true; } | awk '{s += $2} END {print s + 0}'
}
max_seconds() {  # max_seconds LOG...
  cat "$@" | { grep -ao "Done [0-9]* runs in [0-9]* second" || true; } |
    awk '{if ($5 > m) m = $5} END {print m + 0}'
}
{
  echo "# Fuzzing campaign, $(date -u '+%Y-%m-%d %H:%M UTC'), commit $(git rev-parse --short HEAD)"
  echo "# machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(nproc) cores," \
    "$(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo), $(. /etc/os-release && echo "$PRETTY_NAME")"
  echo "# build: $build (clang, ASan + UBSan, libFuzzer); all targets at once, $workers worker(s) each;" \
    "budget $runs executions per target$([ "$seconds" -gt 0 ] && echo ", at most $seconds s")"
  echo "# time: the target's longest worker [s]; exec/s: per worker (one core); corpus: files in the"
  echo "# work corpus and the seeds; crashes, leaks, timeouts, ooms: inputs libFuzzer saved"
  printf '%-16s %12s %7s %7s %7s %7s %5s %8s %4s\n' target executions time_s exec/s corpus \
    crashes leaks timeouts ooms
  for target in "${FUZZ_TARGETS[@]}"; do
    logs=("$work/$target".*.log)
    count() { find "$work/$target/artifacts" -name "$1-*" | wc -l; }
    executions=$(sum_stat number_of_executed_units "${logs[@]}")
    time_s=$(max_seconds "${logs[@]}")
    printf '%-16s %12d %7d %7d %7d %7d %5d %8d %4d\n' "$target" "$executions" "$time_s" \
      $((executions / (time_s > 0 ? time_s : 1) / workers)) \
      "$(find "$work/$target/corpus" "$FUZZ_DIR/corpus/$target" -type f | wc -l)" \
      "$(count crash)" "$(count leak)" "$(count timeout)" "$(count oom)"
  done
} | tee "$out"
exit $status
