#!/usr/bin/env python3
"""The step-length error of a pedestrian walk's estimate against its ground truth.

    /usr/bin/python3 datasets/ipin21/step_error_stats.py <scenario dir> [...]

For each scenario directory (estimate.tum and ground_truth.tum, one pose a step, as in
../shared/datasets/hcu_eight, make_zero2four.py's output and make_hcu_walks.py's walks) prints,
over the level steps (ground truth rises less than 0.05 m; both steps 0.2-2 m long), the log
ratio of true to estimated step length: its mean (as a scale), its standard deviation and its
autocorrelation at lags of 1 to 40 steps (a step without a ratio is skipped in the pairs). These
are the figures make_hcu_walks.py's step model reproduces. Python standard library only; exit
code 2 on a missing or unreadable file.
"""
import math
import os
import sys

LAGS = (1, 2, 3, 5, 8, 12, 16, 20, 30, 40)


def read_tum(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                rows.append(tuple(float(v) for v in line.split()[:4]))
    return rows


def log_ratios(est, gt):
    """Per step: log(true / estimated length), None where the step is not a level one."""
    out = []
    for i in range(1, min(len(est), len(gt))):
        de = math.hypot(est[i][1] - est[i - 1][1], est[i][2] - est[i - 1][2])
        dg = math.hypot(gt[i][1] - gt[i - 1][1], gt[i][2] - gt[i - 1][2])
        level = abs(gt[i][3] - gt[i - 1][3]) <= 0.05
        out.append(math.log(dg / de) if level and 0.2 <= de <= 2.0 and 0.2 <= dg <= 2.0 else None)
    return out


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    for d in argv[1:]:
        try:
            est = read_tum(os.path.join(d, "estimate.tum"))
            gt = read_tum(os.path.join(d, "ground_truth.tum"))
        except (OSError, ValueError) as e:
            print(f"{d}: {e}", file=sys.stderr)
            return 2
        r = log_ratios(est, gt)
        vals = [x for x in r if x is not None]
        if len(vals) < 2:
            print(f"{d}: fewer than two level steps")
            continue
        mean = sum(vals) / len(vals)
        var = sum((x - mean) ** 2 for x in vals) / len(vals)
        acf = []
        for lag in LAGS:
            pairs = [(r[i] - mean) * (r[i + lag] - mean) for i in range(len(r) - lag)
                     if r[i] is not None and r[i + lag] is not None]
            if pairs and var > 0.0:
                acf.append(f"{lag}:{sum(pairs) / len(pairs) / var:.2f}")
        print(f"{d}: {len(vals)} level steps of {len(r)}, scale {math.exp(mean):.3f}, "
              f"log ratio sd {math.sqrt(var):.3f}, autocorrelation {' '.join(acf)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
