#!/usr/bin/env bash
# Installs, builds and wraps the bundled sample; prints where the result and report went.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh -DVDBWRAP_BUILD_TESTS=OFF
mkdir -p out
./build/client/vdbwrap wrap tests/data/fandisk.obj -o out/fandisk_wrap.stl --base-size 1% --report out/fandisk_wrap.json
echo "result: $(pwd)/out/fandisk_wrap.stl"
echo "report: $(pwd)/out/fandisk_wrap.json"
