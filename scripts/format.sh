#!/usr/bin/env bash
# Formats the project's C++ with .clang-format (Debian's clang-format-14). --check lists the
# files that differ and exits 1, changing nothing. Generated code and fuzz inputs are left out.
set -euo pipefail
cd "$(dirname "$0")/.."
fmt=$(command -v clang-format-14 || command -v clang-format || true)
[ -n "$fmt" ] || { echo "format.sh: clang-format is not installed (apt-get install clang-format)" >&2; exit 2; }
mapfile -t files < <(git ls-files '*.cpp' '*.h' | grep -v '^clients/\|\.pb\.\|^tests/fuzz/corpus/\|^tests/fuzz/crashes/')
if [ "${1:-}" = "--check" ]; then
  bad=0
  for f in "${files[@]}"; do
    if ! "$fmt" "$f" | cmp -s - "$f"; then echo "$f"; bad=1; fi
  done
  exit $bad
fi
"$fmt" -i "${files[@]}"
