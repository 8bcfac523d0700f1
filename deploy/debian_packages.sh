#!/usr/bin/env bash
# Installs the Debian 12 packages Fenestra builds and runs with (idempotent).
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler libabsl-dev
  libembree-dev libtbb-dev libeigen3-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libcli11-dev libtinyobjloader-dev libsqlite3-dev libpq-dev zlib1g-dev libexpat1-dev
  libssl-dev openssl chromium
  postgresql-15
  python3 python3-grpcio python3-grpc-tools python3-numpy
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
