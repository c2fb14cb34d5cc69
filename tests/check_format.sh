#!/usr/bin/env bash
# Is every C++ file of the repository formatted as .clang-format says?
#
#   tests/check_format.sh [CLANG_FORMAT]
#
# Runs CLANG_FORMAT (default clang-format-14, Debian's) over every tracked *.cpp and *.h and prints
# the places it would change; exits 1 when there is one. `git ls-files '*.cpp' '*.h' | xargs
# clang-format-14 -i` formats them.
set -uo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
tool=${1:-clang-format-14}
command -v "$tool" >/dev/null || { echo "check_format: $tool not found" >&2; exit 2; }
cd "$repo"
out=$(git ls-files -z '*.cpp' '*.h' | xargs -0 "$tool" --dry-run 2>&1)
if [ -n "$out" ]; then
    printf '%s\n' "$out" | grep 'warning:' >&2
    echo "check_format: $(printf '%s\n' "$out" | grep -c 'warning:') place(s) not formatted as .clang-format says" >&2
    exit 1
fi
echo "check_format: $(git ls-files '*.cpp' '*.h' | wc -l) files formatted as .clang-format says"
