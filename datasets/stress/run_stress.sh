#!/usr/bin/env bash
# Generates the stress variants of each scenario and runs `driftcorr correct` on each of them
# (clean included), serially; prints one markdown table row per variant. A failing generator or
# correction is reported in its row and never stops the run.
#
# usage: run_stress.sh <driftcorr binary> <generator binary> <out_dir> <scenario dirs...>
#
# Layout: <out_dir>/<scenario folder name>/<variant>/ (the generated scenario),
#         <out_dir>/<scenario folder name>/<variant>.corrected.tum and .log (the correction),
#         <out_dir>/<scenario folder name>/generate.log.
# Columns: exit code of `driftcorr correct` ("skipped" when the generator did not make the
# variant); estimate and corrected ATE / final error [m] from the summary lines starting with
# "  estimate" and "  corrected"; verdict from a summary line starting with "verdict" ("-" when
# the binary prints none).
set -u

if [ $# -lt 4 ]; then
    echo "usage: $0 <driftcorr binary> <generator binary> <out_dir> <scenario dirs...>" >&2
    exit 2
fi
driftcorr=$1
generator=$2
out_dir=$3
shift 3

variants=(clean drop_steps heading_bias_0.1 heading_bias_0.3 heading_bias_0.5
          yaw_off_10 yaw_off_20 yaw_off_30 anchor_off_20m road_removed)

# "ATE / final" of the summary line starting with "  <label>", or "-".
metrics() {
    awk -v label="$1" '
        index($0, "  " label " ") == 1 {
            for (i = 1; i < NF; ++i) {
                if ($i == "ATE") ate = $(i + 1)
                if ($i == "final") fin = $(i + 1)
            }
        }
        END { if (ate != "") printf "%s / %s", ate, fin; else printf "-" }' "$2"
}

verdict() {
    local line
    line=$(grep -m1 '^verdict' "$1" | sed -e 's/^verdict[[:space:]:]*//' -e 's/|/\\|/g')
    if [ -n "$line" ]; then printf '%s' "$line"; else printf -- '-'; fi
}

mkdir -p "$out_dir" || exit 1
echo "| scenario | variant | exit | estimate ATE / final [m] | corrected ATE / final [m] | verdict |"
echo "|---|---|---|---|---|---|"
for scenario in "$@"; do
    name=$(basename "${scenario%/}")
    [ "$name" = "scenario.yaml" ] && name=$(basename "$(dirname "$scenario")")
    dir="$out_dir/$name"
    mkdir -p "$dir"
    "$generator" "$scenario" "$dir" > "$dir/generate.log" 2>&1
    gen_exit=$?
    if [ $gen_exit -ne 0 ]; then
        echo "| $name | (generator) | $gen_exit | - | - | $(head -c 200 "$dir/generate.log" | tr '\n|' '  ') |"
        continue
    fi
    for variant in "${variants[@]}"; do
        if [ ! -f "$dir/$variant/scenario.yaml" ]; then
            echo "| $name | $variant | skipped | - | - | - |"
            continue
        fi
        log="$dir/$variant.log"
        "$driftcorr" correct "$dir/$variant" -o "$dir/$variant.corrected.tum" > "$log" 2>&1
        code=$?
        echo "| $name | $variant | $code | $(metrics estimate "$log") | $(metrics corrected "$log") | $(verdict "$log") |"
    done
done
exit 0
