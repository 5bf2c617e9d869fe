#!/usr/bin/env bash
# Bounded libFuzzer runs (tests/fuzz/README.md). Builds the harnesses with clang, ASan and UBSan
# into build-fuzz and runs each fuzzer for SECONDS (default 60), one process at a time.
# Every crash, timeout, leak or out-of-memory input is minimized and copied to
# tests/fuzz/crashes/NAME/; the script then exits 1.
#
#   scripts/fuzz.sh [SECONDS] [--merge] [--light] [--only NAME[,NAME...]] [--no-build]
#
#   SECONDS     per fuzzer; 0 builds and runs nothing
#   --merge     add the inputs that found new coverage to tests/fuzz/corpus/NAME (libFuzzer -merge)
#   --light     only the fuzzers that need no OpenVDB/CGAL core (readers, parameter texts, mapping)
#   --only      these fuzzers (fuzz_mesh_read, fuzz_params_text, fuzz_params_proto, fuzz_wrap)
#   --no-build  use the fuzzers already in the build directory
#
# Environment: FUZZ_BUILD_DIR (build-fuzz), FUZZ_TIMEOUT (seconds per input, 30),
# FUZZ_RSS_MB (2048), VDBWRAP_BUILD_LOCK (a file to flock around the build, if set).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)

SECONDS_EACH=60
MERGE=0
LIGHT=0
BUILD=1
ONLY=""
while [ $# -gt 0 ]; do
  case "$1" in
    --merge) MERGE=1 ;;
    --light) LIGHT=1 ;;
    --no-build) BUILD=0 ;;
    --only) ONLY="$2"; shift ;;
    [0-9]*) SECONDS_EACH="$1" ;;
    *) echo "fuzz.sh: unknown argument $1" >&2; exit 2 ;;
  esac
  shift
done

BUILD_DIR=${FUZZ_BUILD_DIR:-build-fuzz}
TIMEOUT=${FUZZ_TIMEOUT:-30}
RSS_MB=${FUZZ_RSS_MB:-2048}
LIGHT_FUZZERS=(fuzz_mesh_read fuzz_params_text fuzz_params_proto)
if [ -n "$ONLY" ]; then
  IFS=, read -r -a FUZZERS <<<"$ONLY"
elif [ "$LIGHT" = 1 ]; then
  FUZZERS=("${LIGHT_FUZZERS[@]}")
else
  FUZZERS=("${LIGHT_FUZZERS[@]}" fuzz_wrap)
fi

if [ "$BUILD" = 1 ]; then
  GEN=()
  command -v ninja >/dev/null && GEN=(-G Ninja)
  # Everything compiled with the sanitizers and libFuzzer's coverage; only the harnesses link
  # libFuzzer. No tests, service or benchmarks: the harnesses are the only targets built.
  SAN="-fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined -fno-omit-frame-pointer -gline-tables-only"
  SAN+=" -fsanitize-ignorelist=$ROOT/tests/fuzz/ubsan-ignorelist.txt"
  cmake -S . -B "$BUILD_DIR" "${GEN[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_CXX_FLAGS="$SAN" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DVDBWRAP_BUILD_FUZZERS=ON -DVDBWRAP_BUILD_TESTS=OFF -DVDBWRAP_BUILD_SERVICE=OFF -DVDBWRAP_BUILD_BENCH=OFF >/dev/null
  LOCK=()
  [ -n "${VDBWRAP_BUILD_LOCK:-}" ] && LOCK=(flock "$VDBWRAP_BUILD_LOCK")
  "${LOCK[@]}" cmake --build "$BUILD_DIR" -j "$(nproc)" --target "${FUZZERS[@]}"
fi

[ "$SECONDS_EACH" -gt 0 ] || exit 0
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
FOUND=0
for name in "${FUZZERS[@]}"; do
  bin="$BUILD_DIR/tests/fuzz/$name"
  seeds="$ROOT/tests/fuzz/corpus/$name"
  work="$BUILD_DIR/fuzz-corpus/$name"      # grows across runs; seeds stay as they are
  artifacts="$BUILD_DIR/fuzz-artifacts/$name"
  kept="$ROOT/tests/fuzz/crashes/$name"
  mkdir -p "$work" "$artifacts" "$kept"
  echo "fuzz.sh: $name for ${SECONDS_EACH}s" >&2
  log="$BUILD_DIR/fuzz-$name.log"
  start=$(date +%s)
  extra=()
  # The pipeline's caches (TBB, OpenVDB) make libFuzzer re-run most inputs to look for leaks,
  # halving the pipeline's speed; leaks still show when each worker exits.
  # Its inputs need up to 7 + 48 x 10 bytes (48 triangles, fuzz_wrap.cpp); without -max_len and
  # -len_control=0 every -fork job starts from its seeds' largest size and lengthens inputs only
  # after some hundreds of runs without new coverage, which a job of fuzz_wrap (a few runs a
  # second) hardly ever sees: a 60-minute run made no input over 28 bytes
  # (bench/results/2026-11-26-fuzz-wrap-long.md).
  [ "$name" = fuzz_wrap ] && extra=(-detect_leaks=0 -max_len=512 -len_control=0)
  # -fork=1 with -ignore_crashes: one worker; a crash is saved and the run goes on to find more.
  "$bin" "${extra[@]}" -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
    -max_total_time="$SECONDS_EACH" -timeout="$TIMEOUT" -rss_limit_mb="$RSS_MB" \
    -artifact_prefix="$artifacts/" -print_final_stats=1 "$work" "$seeds" >"$log" 2>&1 || true
  end=$(date +%s)
  stats=$(grep -E "^#[0-9]+" "$log" | tail -1 || true)  # the last progress line of the fork server
  echo "fuzz.sh: $name ran $((end - start))s: ${stats:-no stats (see $log)}" >&2
  for slow in "$artifacts"/slow-unit-*; do
    [ -f "$slow" ] && echo "fuzz.sh: $name: an input over 10 s (not a finding): $slow" >&2
  done
  for a in "$artifacts"/crash-* "$artifacts"/timeout-* "$artifacts"/oom-* "$artifacts"/leak-*; do
    [[ -f "$a" && "$a" != *.log ]] || continue
    base=$(basename "$a")
    [ -f "$kept/$base" ] && continue
    # Minimized copy when libFuzzer manages within the time; else the input as found.
    if [[ "$base" == crash-* || "$base" == leak-* ]]; then
      "$bin" -minimize_crash=1 -max_total_time=30 -timeout="$TIMEOUT" -exact_artifact_path="$kept/$base" \
        "$a" >"$artifacts/$base.minimize.log" 2>&1 || true
    fi
    [ -f "$kept/$base" ] || cp "$a" "$kept/$base"
    echo "fuzz.sh: FINDING $name: $kept/$base (log: $log)" >&2
    FOUND=1
  done
  if [ "$MERGE" = 1 ]; then
    # Only inputs adding coverage over the seeds are copied in.
    "$bin" -merge=1 -timeout="$TIMEOUT" -rss_limit_mb="$RSS_MB" "$seeds" "$work" >"$BUILD_DIR/merge-$name.log" 2>&1 ||
      echo "fuzz.sh: merge of $name failed (see $BUILD_DIR/merge-$name.log)" >&2
  fi
done
if [ "$FOUND" = 1 ]; then
  echo "fuzz.sh: findings copied to tests/fuzz/crashes/ (see above)" >&2
  exit 1
fi
echo "fuzz.sh: no findings" >&2
