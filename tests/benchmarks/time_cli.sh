#!/usr/bin/env bash
# Times `driftcorr correct` end to end (scenario parse, map parse, field, correction, output) on
# one core, as a user runs it. Prints, per scenario, the best and median wall time of N runs, the
# median of each stage the tool's own summary reports (load, map and field, correction with its
# incremental windows and final solve), the correction stage's poses per second and the peak
# resident memory. CPUS="0,1" gives the run two cores (the field build uses them).
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
command -v taskset > /dev/null && pin=(taskset -c "${CPUS:-0}")
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
median() { sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
printf "%-30s %6s %7s %7s | %6s %6s %6s %6s %6s | %8s %7s\n" scenario poses best_s median_s \
    load map corr incr refine poses/s peak_MB
for s in "${scenarios[@]}"; do
    : > "$out/times"
    : > "$out/stages"
    for ((k = 0; k < RUNS; ++k)); do
        start=$(date +%s%N)
        "${pin[@]}" "$CLI" correct "$s" -o "$out/c.tum" --quiet > "$out/summary.txt" 2> /dev/null
        end=$(date +%s%N)
        awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f\n", (b - a) / 1e9 }' >> "$out/times"
        # time T s (load L, map M, correction C = R poses/s: incremental I, refine F); peak memory P MB
        grep '^time' "$out/summary.txt" | tr -d '(),;:=' |
            awk '{ print $5, $7, $9, $10, $18, $13, $15 }' >> "$out/stages"
    done
    poses=$(awk '/^scenario/ {print $(NF-1)}' "$out/summary.txt")
    cols=()
    for c in 1 2 3 4 5 6 7; do cols+=("$(awk -v c=$c '{ print $c }' "$out/stages" | median)"); done
    printf "%-30s %6s %7.3f %7.3f | %6.3f %6.3f %6.3f %6.3f %6.3f | %8.0f %7.0f\n" \
        "$(basename "$s")" "$poses" "$(sort -g "$out/times" | head -1)" "$(median < "$out/times")" \
        "${cols[0]}" "${cols[1]}" "${cols[2]}" "${cols[5]}" "${cols[6]}" "${cols[3]}" "${cols[4]}"
done
