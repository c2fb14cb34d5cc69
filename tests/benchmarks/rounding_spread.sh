#!/usr/bin/env bash
# How much a scenario's result moves with rounding alone: N copies of the scenario whose
# estimate has every horizontal position moved by a uniform +-1e-7 m (TUM x and y, KITTI camera x
# and z; seeds 1..N), each corrected by `driftcorr correct --on-failure write`. Prints per copy
# the corrected ATE, the share of poses on the right floor (indoor3d) and the verdict, then the
# median and range of the ATE.
#
#   tests/benchmarks/rounding_spread.sh [build_dir=build] [runs=20] <scenario dir>
set -euo pipefail
REPO="$(cd "$(dirname "$0")/../.." && pwd)"
BUILD="${1:-$REPO/build}"
RUNS="${2:-20}"
SCENARIO="${3:?a scenario directory}"
CLI="$BUILD/examples/driftcorr"
[ -x "$CLI" ] || { echo "no $CLI: build first" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

for ((k = 1; k <= RUNS; ++k)); do
    copy="$work/copy"
    rm -rf "$copy"
    cp -r "$SCENARIO" "$copy"
    /usr/bin/python3 - "$copy" "$k" <<'EOF'
import random
import re
import sys

folder, seed = sys.argv[1], int(sys.argv[2])
random.seed(seed)
yaml = open(folder + "/scenario.yaml").read()
path = re.search(r"estimate:\s*\{?\s*path:\s*([^,}\s]+)", yaml).group(1)
rows = [line.split() for line in open(folder + "/" + path)
        if line.strip() and not line.startswith("#")]
moved = (3, 11) if len(rows[0]) == 12 else (1, 2)  # KITTI camera x, z; TUM x, y
with open(folder + "/" + path, "w") as out:
    for row in rows:
        values = [float(v) for v in row]
        for i in moved:
            values[i] += random.uniform(-1e-7, 1e-7)
        out.write(" ".join(repr(v) for v in values) + "\n")
EOF
    "$CLI" correct "$copy" -o "$work/corrected.tum" --on-failure write 2>&1 |
        awk -v k="$k" '/^  corrected/ { ate = $3; if ($(NF - 2) == "floor") floor = $(NF - 1) }
                       /^verdict/ { verdict = $2 }
                       END { printf "%3d %8s %6s %s\n", k, ate, floor == "" ? "-" : floor, verdict }'
done | tee "$work/rows"
sort -g -k2 "$work/rows" | awk '{ a[NR] = $2 } END {
    printf "ATE median %s m, range %s-%s m over %d runs\n", a[int((NR + 1) / 2)], a[1], a[NR], NR }'
