#!/usr/bin/env bash
# Does the installed package work for a project outside this tree?
#
#   tests/consumer/run_consumer_check.sh BUILD_DIR
#
# Installs the built tree BUILD_DIR into a temporary prefix, configures and builds the project in
# tests/consumer against it (find_package(driftcorr), CMAKE_PREFIX_PATH=prefix only) and runs it;
# runs the installed CLI too when the build has it. Exits non-zero on any failure.
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:?usage: run_consumer_check.sh BUILD_DIR}" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/driftcorr_consumer.XXXXXX")
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"

cmake --install "$build" --prefix "$prefix" >"$work/install.log"
echo "[consumer] installed $(find "$prefix" -type f | wc -l) files into a temporary prefix"
for f in lib/cmake/driftcorr/driftcorrConfig.cmake lib/cmake/driftcorr/driftcorrConfigVersion.cmake \
         include/driftcorr/optim/corrector.h; do
    [ -f "$prefix/$f" ] || { echo "[consumer] missing from the install: $f" >&2; exit 1; }
done

# A copy of the consumer outside the source tree, so nothing can reach this repository's build.
cp -r "$repo/tests/consumer" "$work/src"
cmake -S "$work/src" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
    >"$work/configure.log" || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/build" >"$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
"$work/build/driftcorr_consumer"

if [ -x "$prefix/bin/driftcorr" ]; then
    status=0
    "$prefix/bin/driftcorr" >/dev/null 2>"$work/cli.log" || status=$?
    # No arguments: usage on stderr and exit code 1 (a missing library would fail differently).
    if [ $status -ne 1 ] || ! grep -qi usage "$work/cli.log"; then
        echo "[consumer] installed CLI failed (exit $status):" >&2; cat "$work/cli.log" >&2; exit 1
    fi
    echo "[consumer] installed CLI runs (usage, exit 1)"
fi
echo "[consumer] ok"
