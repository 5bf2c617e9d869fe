#!/usr/bin/env bash
# Repairs every mesh of the given folders with the default settings and prints a SHA-256 per output:
# two runs of this script before and after a refactor of the repair must print the same lines.
# The union of crossing bodies (CGAL corefinement) depends on where its data lie in memory:
# box.STL of the corpus comes out as one of two surfaces, by thread count, by allocations
# elsewhere, even by the length of the output's name. One worker thread by default keeps the
# runs of one binary alike; a box.STL line that flips between two binaries needs a look with
# other output names before it counts as a difference.
# Usage: scripts/repair-digests.sh [--threads 1] [--build build] DIR... > digests.txt
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build"; threads=1
while [ $# -gt 0 ]; do
  case "$1" in
    --threads) threads="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    *) break ;;
  esac
done
[ $# -gt 0 ] || { echo "usage: $0 [--threads N] [--build DIR] DIR..." >&2; exit 2; }
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
for dir in "$@"; do
  for f in "$dir"/*; do
    case "${f,,}" in *.stl|*.obj|*.off|*.ply|*.vtp) ;; *) continue ;; esac
    out="$work/out.ply"; rm -f "$out"
    # Doubles (PLY) so that no rounding hides a difference.
    if "$build/client/vdbwrap" repair "$f" -o "$out" --threads "$threads" -q >"$work/log" 2>&1; then
      echo "$(sha256sum < "$out" | cut -c1-16)  $(basename "$f")"
    else
      echo "exit-$?            $(basename "$f")"
    fi
  done
done
