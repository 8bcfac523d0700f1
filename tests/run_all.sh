#!/usr/bin/env bash
# Installs the build dependencies, builds Fenestra and runs the whole test suite.
# Usage: tests/run_all.sh [build-dir]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/debian_packages.sh
build="${1:-build}"
# nvcc is optional; when present (default CUDA location), the CUDA sources are compiled too.
if ! command -v nvcc >/dev/null && [ -x /usr/local/cuda/bin/nvcc ]; then
  export PATH="/usr/local/cuda/bin:$PATH"
fi
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$build" -j"$(nproc)"
ctest --test-dir "$build" --output-on-failure -j"$(nproc)"
