#!/usr/bin/env bash
# Packs the GPU tests and benchmarks of a build, with the shared libraries they load, into
# gpu_pack/pack.tar.xz for bench/gpu_pack_run.sh on a GPU machine that lacks the build's
# dependencies. Usage: bench/gpu_pack.sh [build-dir]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
root=gpu_pack/root
rm -rf gpu_pack
mkdir -p "$root/bin" "$root/lib"
cp "$build/client/fenestra" "$build/bench/gpu_bench" "$build/bench/qmc_bench" \
  "$build/tests/core/dc/cuda_backend_test" \
  "$build/tests/core/optimize/optimize_test" "$root/bin/"
for extra in cuda_tracer_test annual_tally_test; do
  found="$(find "$build/tests" -name "$extra" -type f -executable | head -1)"
  [ -n "$found" ] && cp "$found" "$root/bin/"
done
# The libraries they load, less the C and C++ runtimes every machine has
ldd "$root"/bin/* | awk '/=> \// {print $3}' | sort -u |
  grep -v -E '/(libc|libm|libpthread|libdl|librt|libgcc_s|libstdc\+\+|ld-linux[^/]*)\.so' |
  xargs -r cp -L -t "$root/lib/"
# Tests find their data through the source directory compiled into them
pwd >"$root/source_dir"
strip "$root"/bin/* "$root"/lib/* 2>/dev/null || true
tar cJf gpu_pack/pack.tar.xz -C gpu_pack root
rm -rf "$root"
du -h gpu_pack/pack.tar.xz
