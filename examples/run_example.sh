#!/usr/bin/env bash
# Installs the dependencies, builds Fenestra and runs the main job end to end on the
# embedded example (the sunny office in Phoenix, its blind operated by IES LM-83's rule):
# starts fenestrad on localhost with a temporary data directory, registers the site (its
# outdoor matrix is traced once and cached), submits the tilt optimization with the client
# (maximize UDI keeping sDA at least 55%), shows its progress and the best design with ASE,
# sDA and the constraint, then stops the daemon and prints its lines on the site and the job
# (its whole log when a step fails).
# Usage: examples/run_example.sh [JOB.json]   (default: examples/sunny_office/leed_quick.json;
#        examples/city_office/alpha_max.json is the source publication's tilt experiment)
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/debian_packages.sh
if ! command -v nvcc >/dev/null && [ -x /usr/local/cuda/bin/nvcc ]; then
  export PATH="/usr/local/cuda/bin:$PATH"
fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
fenestra=build/client/fenestra
job="${1:-examples/sunny_office/leed_quick.json}"
data=$(mktemp -d)
pid=""
stop_daemon() {
  if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid"
    wait "$pid" || true
  fi
  pid=""
}
# On failure the daemon's whole log, else only its lines about the site and the job and its
# warnings
finish() {
  local status=$?
  stop_daemon
  if [ "$status" -ne 0 ] && [ -s "$data/fenestrad.log" ]; then
    echo "fenestrad log:" >&2
    cat "$data/fenestrad.log" >&2
  fi
  rm -rf "$data"
  exit "$status"
}
trap finish EXIT

# The job's scene (its sceneFile, relative to the job's folder)
scene=$(sed -n 's/.*"sceneFile": *"\([^"]*\)".*/\1/p' "$job" | head -1)
$fenestra scene check "$(dirname "$job")/$scene"

# The daemon, on a free localhost port; auth none: every caller is the local user
# (allowed on loopback only)
build/server/fenestrad --listen 127.0.0.1:0 --auth none --data-dir "$data" --port-file "$data/port" \
  2>"$data/fenestrad.log" &
pid=$!
for _ in $(seq 100); do [ -s "$data/port" ] && break; sleep 0.1; done
if [ ! -s "$data/port" ]; then
  exit 1
fi
server="127.0.0.1:$(cat "$data/port")"
echo "fenestrad listening on $server (data in $data)"

# The site, then the job on it: progress, then the best design
$fenestra site add --job "$job" --wait --server "$server"
$fenestra job submit "$job" --site site-1 --watch --server "$server"

stop_daemon
echo "fenestrad, on the site and the job:"
grep -E '^[^ ]+ [^ ]+ ([a-z]+ (site|job) |(warning|error|critical) )' "$data/fenestrad.log" || true
