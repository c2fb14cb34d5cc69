#!/usr/bin/env bash
# Multi-floor walks in the real HCU building: generates the walks of a seed range with
# datasets/ipin21/make_hcu_walks.py, corrects each with `driftcorr correct` (defaults, or
# CONFIG=params.yaml) and prints one line per walk and a summary: ATE median / p90 / mean, the
# share of poses on the right floor, how many walks end worse than their estimate, and how many
# of those the verdict let pass as `ok`.
#
#   tests/benchmarks/hcu_walks.sh [build_dir=build] [seeds=1001-1030] [out_dir=<build>/hcu_walks]
#
# Seeds 1-40 chose the pedestrian defaults; 1001-1030 chose nothing (the figures of
# docs/results.md). Needs ../shared/datasets/hcu_eight. JOBS=N runs N corrections at a time;
# GEN_ARGS="--lift-poses-hz 1" passes options to the generator.
set -euo pipefail
REPO="$(cd "$(dirname "$0")/../.." && pwd)"
BUILD="${1:-$REPO/build}"
SEEDS="${2:-1001-1030}"
OUT="${3:-$BUILD/hcu_walks}"
CLI="$BUILD/examples/driftcorr"
HCU="$REPO/../shared/datasets/hcu_eight"
[ -x "$CLI" ] || { echo "no $CLI: build first" >&2; exit 1; }
[ -f "$HCU/scenario.yaml" ] || { echo "no $HCU: the HCU walks need its plans" >&2; exit 1; }

rm -rf "$OUT/walks"
mkdir -p "$OUT/walks" "$OUT/corrected"
/usr/bin/python3 "$REPO/datasets/ipin21/make_hcu_walks.py" "$HCU" "$OUT/walks" --seeds "$SEEDS" ${GEN_ARGS:-} \
    > "$OUT/generated.txt"

correct_one() {
    local dir="$1" name out rc
    name="$(basename "$dir")"
    out="$("$CLI" correct "$dir" -o "$OUT/corrected/$name.tum" --on-failure write \
        ${CONFIG:+--config "$CONFIG"} 2>&1)" && rc=0 || rc=$?
    printf '%s %s rc %s\n' "$name" \
        "$(echo "$out" | awk '/^  estimate/{e=$3} /^  corrected/{c=$3; f=$(NF-1)}
                              /^verdict/{v=$2} END{print "estimate", e, "corrected", c,
                                                   "floor", f, "verdict", v}')" "$rc"
}
export -f correct_one
export CLI OUT CONFIG
ls -d "$OUT"/walks/walk_* | sort -V | xargs -P "${JOBS:-2}" -I{} bash -c 'correct_one {}' \
    | sort -V > "$OUT/results.txt"
cat "$OUT/results.txt"

/usr/bin/python3 - "$OUT/results.txt" <<'EOF'
import statistics as st
import sys
rows = [line.split() for line in open(sys.argv[1]) if line.strip()]
bad = [r for r in rows if r[4] == "" or not r[2].replace(".", "").isdigit()]
rows = [r for r in rows if r not in bad]
est = [float(r[2]) for r in rows]
cor = sorted(float(r[4]) for r in rows)
floor = [float(r[6]) for r in rows]
worse = [r for r in rows if float(r[4]) > float(r[2])]
p90 = cor[min(len(cor) - 1, int(0.9 * len(cor)))]
verdicts = {v: sum(r[8] == v for r in rows) for v in ("ok", "degraded", "failed")}
print(f"{len(rows)} walks: ATE median {st.median(cor):.2f} m, p90 {p90:.2f} m, mean "
      f"{st.mean(cor):.2f} m (estimate median {st.median(est):.2f} m); right floor mean "
      f"{st.mean(floor):.1f} %, 100 % on {sum(f >= 99.95 for f in floor)}, >= 99 % on "
      f"{sum(f >= 99.0 for f in floor)}; verdicts ok {verdicts['ok']} / degraded "
      f"{verdicts['degraded']} / failed {verdicts['failed']}; worse than the estimate "
      f"{len(worse)}, of them verdict ok {sum(r[8] == 'ok' for r in worse)}")
if bad:
    print(f"{len(bad)} walks without figures: {' '.join(r[0] for r in bad)}")
EOF
