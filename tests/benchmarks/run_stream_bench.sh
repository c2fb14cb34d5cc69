#!/usr/bin/env bash
# Online correction through the real binary and a pipe: each scenario's estimate is written as TUM
# lines at each rate (0: as fast as the pipe takes them) into `driftcorr stream --status-column`,
# whose output is scored against the ground truth (causal ATE, no re-alignment). Prints one line
# per run and keeps the stream's stderr summary (freshness, solve time per window, output latency
# per line, the verdict) in <out>/<scenario>_<rate>.log. The producer starts once the stream has
# loaded its map (STARTUP_BURST=1: at once, so the poses written meanwhile arrive as a burst).
# Usage: tests/benchmarks/run_stream_bench.sh [build dir] [out dir] -- [scenario dirs...]
#   RATES="10 100 1000 0" (default), STREAM_ARGS="--max-lag 20" (extra stream options),
#   CPU=0 pins the stream to one core (taskset), as "keeping up on one core" means.
set -euo pipefail
build=${1:-build}
out=${2:-/tmp/driftcorr_stream_bench}
shift 2 || true
[[ "${1:-}" == "--" ]] && shift
here=$(cd "$(dirname "$0")" && pwd)
shared="$here/../../../shared/datasets"
if [[ $# -eq 0 ]]; then
    set -- "$shared"/kitti00_cvo_stereo_geometric "$shared"/kitti07_cvo_stereo_geometric \
        "$shared"/kitti00_gicp_frame2frame "$shared"/kitti07_gicp_frame2frame \
        "$shared"/kitti00_orb2_longruidong
fi
rates=${RATES:-10 100 1000 0}
pin=()
[[ -n "${CPU:-}" ]] && pin=(taskset -c "$CPU")
mkdir -p "$out"
for scenario in "$@"; do
    name=$(basename "$scenario")
    for rate in $rates; do
        tag="${name}_${rate}hz"
        rm -f "$out/$tag.log"
        ready=("$out/$tag.log")
        [[ -n "${STARTUP_BURST:-}" ]] && ready=()
        code=0
        "$build/tests/stream_replay" feed "$scenario" "$rate" "${ready[@]}" |
            "${pin[@]}" "$build/examples/driftcorr" stream "$scenario" --status-column \
                ${STREAM_ARGS:-} >"$out/$tag.tum" 2>"$out/$tag.log" || code=$?
        score=$("$build/tests/stream_replay" score "$scenario" "$out/$tag.tum")
        # Exit 3: the stream wrote every pose but could not vouch for them (its log says why).
        [[ $code -eq 3 ]] && score="$score; stream exit 3: $(grep -o 'failed: [^;]*' \
            "$out/$tag.log" | head -1)"
        [[ $code -ne 0 && $code -ne 3 ]] && { echo "rate ${rate} Hz: stream exit $code" >&2; exit "$code"; }
        solve=$(grep -o 'solve time per window [^;]*' "$out/$tag.log" || true)
        latency=$(grep -o 'output latency per line [^;]*' "$out/$tag.log" || true)
        echo "rate ${rate} Hz ${STREAM_ARGS:-}| $score | $solve | $latency"
    done
done
