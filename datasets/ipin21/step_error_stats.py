#!/usr/bin/env python3
"""The step-length error of a pedestrian walk's estimate against its ground truth.

    /usr/bin/python3 datasets/ipin21/step_error_stats.py <scenario dir> [...]

For each scenario directory (estimate.tum and ground_truth.tum, one pose a step, as in
../shared/datasets/hcu_eight, make_zero2four.py's output and make_hcu_walks.py's walks) prints,
over the level steps (ground truth rises less than 0.05 m; both steps 0.2-2 m long), the log
ratio of true to estimated step length: its mean (as a scale), its standard deviation and its
autocorrelation at lags of 1 to 40 steps (a step without a ratio is skipped in the pairs); and
the standard deviation of the log true and of the log estimated step, and the regression slopes
of each on the other (how much of a walker's step the estimate's tells, and how much of it the
estimate follows); and the along-track error of spans of 40 steps (every third step starts one)
at the walk's one best scale, RMS, with the estimate's step lengths as read and read about their
median at exponent 0.25 (driftcorr's indoor_model.step_length_exponent). These are the figures
make_hcu_walks.py's step model reproduces. Python standard library only; exit
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


def level_steps(est, gt):
    """Per step: (log true length, log estimated length), None where the step is not a level
    one."""
    out = []
    for i in range(1, min(len(est), len(gt))):
        de = math.hypot(est[i][1] - est[i - 1][1], est[i][2] - est[i - 1][2])
        dg = math.hypot(gt[i][1] - gt[i - 1][1], gt[i][2] - gt[i - 1][2])
        level = abs(gt[i][3] - gt[i - 1][3]) <= 0.05
        ok = level and 0.2 <= de <= 2.0 and 0.2 <= dg <= 2.0
        out.append((math.log(dg), math.log(de)) if ok else None)
    return out


def spread(pairs):
    """Standard deviations of the log true and log estimated steps, the slope of the first on the
    second and of the second on the first."""
    n = len(pairs)
    mt = sum(t for t, _ in pairs) / n
    me = sum(e for _, e in pairs) / n
    vt = sum((t - mt) ** 2 for t, _ in pairs) / n
    ve = sum((e - me) ** 2 for _, e in pairs) / n
    cov = sum((t - mt) * (e - me) for t, e in pairs) / n
    nan = float("nan")
    return (math.sqrt(vt), math.sqrt(ve), cov / ve if ve > 0.0 else nan,
            cov / vt if vt > 0.0 else nan)


def span_errors(est, gt, exponent, span=40):
    """RMS of (true path - scale * estimated path) over spans of `span` steps, every third step
    starting one, the estimate's steps of 0.2-2 m read as median^(1 - exponent) * L^exponent and
    scale the ratio of the whole true path to the whole read one."""
    n = min(len(est), len(gt))
    dg = [math.dist(gt[i][1:3], gt[i - 1][1:3]) for i in range(1, n)]
    de = [math.dist(est[i][1:3], est[i - 1][1:3]) for i in range(1, n)]
    moving = sorted(x for x in de if 0.2 <= x <= 2.0)
    if not moving or len(dg) <= span:
        return float("nan")
    median = moving[len(moving) // 2]
    read = [median ** (1.0 - exponent) * x ** exponent if 0.2 <= x <= 2.0 else x for x in de]
    scale = sum(dg) / sum(read)
    errs = [sum(dg[i:i + span]) - scale * sum(read[i:i + span])
            for i in range(0, len(dg) - span, 3)]
    return math.sqrt(sum(e * e for e in errs) / len(errs))


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
        steps = level_steps(est, gt)
        r = [None if p is None else p[0] - p[1] for p in steps]
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
        sd_true, sd_est, true_on_est, est_on_true = spread([p for p in steps if p is not None])
        print(f"  log step sd: true {sd_true:.3f}, estimated {sd_est:.3f}; slope of the true on "
              f"the estimated {true_on_est:.2f}, of the estimated on the true {est_on_true:.2f}")
        print(f"  along-track error of 40-step spans: {span_errors(est, gt, 1.0):.2f} m as read, "
              f"{span_errors(est, gt, 0.25):.2f} m read about the median")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
