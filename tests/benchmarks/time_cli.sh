#!/usr/bin/env bash
# Times `driftcorr correct` end to end (scenario parse, map parse, field, correction, output) on
# one core, as a user runs it. Prints, per scenario, the best and median wall time of N runs and
# the correction stage's poses per second from the tool's own summary.
#
#   tests/benchmarks/time_cli.sh [build_dir=build] [runs=5] [scenario dirs...]
#
# Default scenarios: the KITTI and HCU scenarios of ../shared/datasets when present, else the
# synthetic road scenario generated into the build folder.
set -euo pipefail
REPO="$(cd "$(dirname "$0")/../.." && pwd)"
BUILD="${1:-$REPO/build}"
RUNS="${2:-5}"
shift $(( $# > 2 ? 2 : $# ))
CLI="$BUILD/examples/driftcorr"
[ -x "$CLI" ] || { echo "no $CLI: build first" >&2; exit 1; }

scenarios=("$@")
if [ ${#scenarios[@]} -eq 0 ]; then
    for d in "$REPO"/../shared/datasets/*/; do [ -f "$d/scenario.yaml" ] && scenarios+=("${d%/}"); done
fi
if [ ${#scenarios[@]} -eq 0 ]; then
    "$BUILD/datasets/driftcorr_make_road_scenario" "$BUILD/scenarios/synthetic-road" > /dev/null
    scenarios=("$BUILD/scenarios/synthetic-road")
fi

pin=()
command -v taskset > /dev/null && pin=(taskset -c 0)
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
printf "%-32s %6s %9s %9s %14s\n" scenario poses best_s median_s correction/s
for s in "${scenarios[@]}"; do
    times=()
    for ((k = 0; k < RUNS; ++k)); do
        start=$(date +%s%N)
        "${pin[@]}" "$CLI" correct "$s" -o "$out/c.tum" --quiet > "$out/summary.txt" 2> /dev/null
        end=$(date +%s%N)
        times+=("$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", (b - a) / 1e9 }')")
    done
    sorted=($(printf "%s\n" "${times[@]}" | sort -g))
    poses=$(awk '/^scenario/ {print $(NF-1)}' "$out/summary.txt")
    rate=$(grep -o '= [0-9]* poses/s' "$out/summary.txt" | awk '{print $2}')
    printf "%-32s %6s %9.3f %9.3f %14s\n" "$(basename "$s")" "$poses" "${sorted[0]}" \
        "${sorted[$((RUNS / 2))]}" "$rate"
done
