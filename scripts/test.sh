#!/usr/bin/env bash
# Installs the dependencies, builds from scratch and runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
# Tests on explicitly: a build directory configured by wrap-sample.sh has them off.
bash scripts/build.sh -DVDBWRAP_BUILD_TESTS=ON -DVDBWRAP_BUILD_SERVICE=ON
cd "${BUILD_DIR:-build}"
ctest --output-on-failure --no-tests=error -j "$(nproc)" --timeout 900
