# The fuzz targets and how libFuzzer runs them, for tests/run_all.sh and
# bench/fuzz_campaign.sh (sourced). FUZZ_DIR is this folder.
FUZZ_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
FUZZ_TARGETS=(scene_json job_json epw obj radiance_matrix outdoor_cache daemon_request rad_import
  hbjson_import)

# fuzz_options TARGET: libFuzzer flags for TARGET. Inputs are capped a little above the
# largest seed; one input may take at most 10 s and 2 GB (a single allocation above 1 GB
# is reported as a crash: sizes read from a file must be checked before allocating).
fuzz_options() {
  local common="-timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024"
  case "$1" in
    scene_json | job_json) echo "$common -max_len=16384 -dict=$FUZZ_DIR/dict/json.dict" ;;
    epw) echo "$common -max_len=16384 -dict=$FUZZ_DIR/dict/epw.dict" ;;
    obj) echo "$common -max_len=4096 -dict=$FUZZ_DIR/dict/obj.dict" ;;
    radiance_matrix) echo "$common -max_len=4096 -dict=$FUZZ_DIR/dict/radiance_matrix.dict" ;;
    outdoor_cache) echo "$common -max_len=16384" ;;
    daemon_request) echo "$common -max_len=32768" ;;
    rad_import) echo "$common -max_len=16384 -dict=$FUZZ_DIR/dict/rad_import.dict" ;;
    hbjson_import) echo "$common -max_len=16384 -dict=$FUZZ_DIR/dict/hbjson.dict" ;;
    *) echo "unknown fuzz target $1" >&2; return 1 ;;
  esac
}

# fuzz_run BUILD_DIR WORK_DIR TARGET LOG FLAGS...: fuzzes TARGET with its seeds (corpus and
# regressions), new inputs going to WORK_DIR/TARGET/corpus (never into the repository) and
# crashing ones to WORK_DIR/TARGET/artifacts; libFuzzer's output to LOG. The targets that
# read files write each input to a temporary folder, in memory (/dev/shm) where there is
# one: on disk, file creation costs more than most parsers. Fails on a crash, leak,
# timeout or out-of-memory.
fuzz_run() {
  local build="$1" work="$2" target="$3" log="$4"
  shift 4
  local dir="$work/$target"
  mkdir -p "$dir/corpus" "$dir/artifacts"
  local seeds=("$FUZZ_DIR/corpus/$target")
  [ -d "$FUZZ_DIR/regressions/$target" ] && seeds+=("$FUZZ_DIR/regressions/$target")
  local tmp
  tmp="$(mktemp -d -p "$([ -w /dev/shm ] && echo /dev/shm || echo "$dir")" fenestra-fuzz.XXXXXX)"
  local status=0
  # shellcheck disable=SC2046
  TMPDIR="$tmp" "$build/tests/fuzz/${target}_fuzz" $(fuzz_options "$target") \
    -print_final_stats=1 -artifact_prefix="$dir/artifacts/" "$@" "$dir/corpus" "${seeds[@]}" \
    >"$log" 2>&1 || status=$?
  rm -rf "$tmp"
  return $status
}
