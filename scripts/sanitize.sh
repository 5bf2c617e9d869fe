#!/usr/bin/env bash
# Builds everything (core, CLI, server, tests) with AddressSanitizer and UndefinedBehaviorSanitizer
# (gcc) into build-asan and runs the whole ctest suite there. Any sanitizer report fails the
# test it happens in. Extra arguments go to ctest (e.g. -R Io to run some tests only).
# Environment: ASAN_BUILD_DIR (build-asan), VDBWRAP_BUILD_LOCK (a file to flock around the build).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
BUILD_DIR=${ASAN_BUILD_DIR:-build-asan}
GEN=()
command -v ninja >/dev/null && GEN=(-G Ninja)
# Release semantics (NDEBUG) as shipped; -O2 keeps the wrap tests within their timeouts and
# -g1 gives line numbers in the reports.
SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g1"
cmake -S . -B "$BUILD_DIR" "${GEN[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS="$SAN" -DCMAKE_CXX_FLAGS_RELEASE="-O2 -DNDEBUG" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DVDBWRAP_BUILD_TESTS=ON -DVDBWRAP_BUILD_SERVICE=ON -DVDBWRAP_BUILD_BENCH=ON
LOCK=()
[ -n "${VDBWRAP_BUILD_LOCK:-}" ] && LOCK=(flock "$VDBWRAP_BUILD_LOCK")
"${LOCK[@]}" cmake --build "$BUILD_DIR" -j "$(nproc)"
# Child processes (the CLI and server the tests start) inherit these. abort_on_error gives a
# core-dump-like exit the tests cannot mistake for a normal error exit code.
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1:detect_stack_use_after_return=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
cd "$BUILD_DIR"
ctest --output-on-failure --no-tests=error -j "$(nproc)" --timeout 1800 "$@"
