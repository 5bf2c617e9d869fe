#!/usr/bin/env bash
# The long stress run (issue 33): every hostile mesh kind at scales 1 and 2, two seeds, every
# option set, 2 runs at once, 300 s bound per run. Writes the outcome table to TABLE (default
# stress-long.md) and keeps failing inputs with their command lines under WORK/failures.
#   tests/stress/run_long.sh [BUILD_DIR] [TABLE] [extra vdbwrap_stress options, e.g. --scales 4 --kinds open_scan]
# Scale 1 with two seeds takes about 25 min on 2 cores; scale 2 about twice that.
set -euo pipefail
build="${1:-build}"
table="${2:-stress-long.md}"
shift $(( $# < 2 ? $# : 2 ))
# A private copy of the CLI: a rebuild in the shared build directory during the run must not
# swap the binary under it.
work="${STRESS_WORK:-/tmp/vdbwrap_stress_long}"
mkdir -p "$work"
cp "$build/client/vdbwrap" "$work/vdbwrap"
exec "$build/tests/stress/vdbwrap_stress" --set full --jobs 2 --timeout 300 --gdb --cli "$work/vdbwrap" \
  --work "$work/run" --table "$table" "$@"
