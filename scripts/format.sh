#!/usr/bin/env bash
# Formats the C++ sources with the repository's .clang-format (Debian's clang-format).
#   scripts/format.sh          rewrite the files in place
#   scripts/format.sh --check  list the files that differ, exit 1 if any
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files '*.h' '*.cpp')
if [[ ${1:-} == --check ]]; then
    bad=0
    for f in "${files[@]}"; do
        if ! clang-format "$f" | cmp -s - "$f"; then echo "$f"; bad=1; fi
    done
    exit $bad
fi
clang-format -i "${files[@]}"
