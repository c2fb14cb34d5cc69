#!/usr/bin/env bash
# Correction time against trajectory length: synthetic road drives of 1,001 to 100,001 poses
# (datasets/synth_road generator, 10 Hz, the same town driven lap after lap), each corrected by
# `driftcorr correct` on one core. Prints per length the correction stage's time and poses per
# second (and its share spent in the incremental windows and the final solve), the peak resident
# memory, the ATE, and the rate relative to the 4,501-pose drive: a linear cost keeps it near 1.
#
#   tests/benchmarks/scaling.sh [build_dir=build] [work_dir=/tmp/driftcorr_scaling] [durations_s...]
set -euo pipefail
REPO="$(cd "$(dirname "$0")/../.." && pwd)"
BUILD="${1:-$REPO/build}"
WORK="${2:-/tmp/driftcorr_scaling}"
shift $(( $# > 2 ? 2 : $# ))
durations=("$@")
[ ${#durations[@]} -eq 0 ] && durations=(100 450 1000 3000 10000)
CLI="$BUILD/examples/driftcorr"
GEN="$BUILD/datasets/driftcorr_make_road_scenario"
[ -x "$CLI" ] && [ -x "$GEN" ] || { echo "no $CLI or $GEN: build first" >&2; exit 1; }
pin=()
command -v taskset > /dev/null && pin=(taskset -c "${CPUS:-0}")
mkdir -p "$WORK"
printf "%8s %9s %9s %9s %9s %8s %7s %10s\n" poses corr_s poses/s incr_s refine_s peak_MB ATE_m vs_4501
base=""
for d in "${durations[@]}"; do
    dir="$WORK/road_${d}s"
    [ -f "$dir/scenario.yaml" ] || "$GEN" "$dir" --duration-s "$d" > /dev/null
    "${pin[@]}" "$CLI" correct "$dir" -o "$dir/corrected.tum" --quiet > "$dir/summary.txt"
    # time T s (load L, map M, correction C = R poses/s: incremental I, refine F); peak memory P MB
    read -r corr rate incr refine peak < <(grep '^time' "$dir/summary.txt" | tr -d '(),;:=' |
        awk '{ print $9, $10, $13, $15, $18 }')
    poses=$(awk '/^scenario/ {print $(NF-1)}' "$dir/summary.txt")
    ate=$(awk '/^  corrected/ {print $3}' "$dir/summary.txt")
    [ "$poses" = "4501" ] && base=$rate
    ratio="-"
    [ -n "$base" ] && ratio=$(awk -v r="$rate" -v b="$base" 'BEGIN { printf "%.2f", r / b }')
    printf "%8s %9s %9s %9s %9s %8s %7s %10s\n" "$poses" "$corr" "$rate" "$incr" "$refine" \
        "$peak" "$ate" "$ratio"
done
