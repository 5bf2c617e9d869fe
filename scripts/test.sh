#!/usr/bin/env bash
# Installs the dependencies, builds from scratch and runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
# Tests on explicitly: a build directory configured by wrap-sample.sh has them off.
bash scripts/build.sh -DVDBWRAP_BUILD_TESTS=ON -DVDBWRAP_BUILD_SERVICE=ON
# Bounded fuzzing of the readers, parameter files and API mapping (tests/fuzz/README.md), which
# build in a minute. The pipeline harness needs an ASan build of the whole core and runs a few
# inputs a second: not here; ctest below replays its seeds and kept crashes. First, so that
# ctest's summary closes the output.
bash scripts/fuzz.sh "${FUZZ_SECONDS:-60}" --light
cd "${BUILD_DIR:-build}"
ctest --output-on-failure --no-tests=error -j "$(nproc)" --timeout 900
