#!/usr/bin/env bash
# Installs the Debian 12 packages Fenestra builds and runs with (idempotent).
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler libabsl-dev
  libembree-dev libtbb-dev libeigen3-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libcli11-dev libtinyobjloader-dev libsqlite3-dev libpq-dev zlib1g-dev libexpat1-dev
  libssl-dev openssl chromium libcpp-httplib-dev
  postgresql-15  # the store and cluster tests start a throwaway PostgreSQL server
  python3 python3-grpcio python3-grpc-tools python3-numpy python3-yaml
  # tests/run_all.sh's sanitizer and fuzzing builds: clang, libFuzzer, llvm-symbolizer
  clang libclang-rt-14-dev llvm
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
# tests/deploy renders deploy/kubernetes with `kubectl kustomize`, which needs kustomize 5
# (kubectl 1.27 or newer). It comes from a `kubectl` package outside Debian's archive (the
# Kubernetes project's or the Google Cloud SDK's apt repository; the build machines have
# kubectl 1:528.0.0-0 of the latter: kubectl 1.32, kustomize 5.5). Debian 12's own
# kubernetes-client is kubectl 1.20 with kustomize 2.0.3, too old for these manifests, so
# it is not installed here.
if ! command -v kubectl >/dev/null; then
  echo "debian_packages.sh: no kubectl: tests/deploy needs kubectl 1.27 or newer" >&2
fi
