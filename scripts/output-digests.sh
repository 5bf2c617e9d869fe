#!/usr/bin/env bash
# Wraps every mesh of the given folders at one base size and prints a SHA-256 per output:
# two runs of this script before and after a refactor must print the same lines.
# Usage: scripts/output-digests.sh [--base-size 1%] [--build build] DIR... > digests.txt
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
base="1%"; build="$root/build"
while [ $# -gt 0 ]; do
  case "$1" in
    --base-size) base="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    *) break ;;
  esac
done
[ $# -gt 0 ] || { echo "usage: $0 [--base-size S] [--build DIR] DIR..." >&2; exit 2; }
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
for dir in "$@"; do
  for f in "$dir"/*; do
    case "${f,,}" in *.stl|*.obj|*.off|*.ply|*.vtp) ;; *) continue ;; esac
    out="$work/out.ply"; rm -f "$out"
    # Doubles (PLY) so that no rounding hides a difference; distances off, they are sampled.
    if "$build/client/vdbwrap" wrap "$f" -o "$out" --base-size "$base" --no-distances -q >"$work/log" 2>&1; then
      echo "$(sha256sum < "$out" | cut -c1-16)  $(basename "$f")"
    else
      echo "exit-$?            $(basename "$f")"
    fi
  done
done
