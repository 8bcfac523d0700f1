#!/usr/bin/env bash
# Installs the dependencies, builds Fenestra and runs the main job end to end on the
# embedded example (the city office in Montevideo).
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/debian_packages.sh
if ! command -v nvcc >/dev/null && [ -x /usr/local/cuda/bin/nvcc ]; then
  export PATH="/usr/local/cuda/bin:$PATH"
fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
fenestra=build/client/fenestra
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

$fenestra scene check examples/city_office/scene.json
$fenestra sky --epw examples/weather/URY_Montevideo.865800_IWEC.epw -o "$out/sky.mtx"
$fenestra dc examples/city_office/scene.json --paths 20000 --bounces 5 -o "$out/dc.mtx"
