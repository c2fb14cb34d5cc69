#!/usr/bin/python3
"""When does a stream say it is in doubt, against when its causal output goes wrong?

For each scenario (a KITTI ground truth in its folder): the batch ATE from `driftcorr eval
--methods driftcorr`, then `driftcorr stream --replay --sync --status-column`; the first line whose
causal error (horizontal, the scenario's frame, no re-alignment) exceeds max(2x the batch ATE,
batch + 2 m), against the first line whose doubt column (the status column's last) is not 0.
Prints one line per scenario: the stream's exit code, when it went beyond the bound, whether and
when it was flagged, and the share of the lines beyond the bound that carry a flag.

    /usr/bin/python3 tests/benchmarks/stream_doubt_delay.py build/examples/driftcorr SCENARIO...
"""
import os
import subprocess
import sys

import numpy as np


def batch_ate(driftcorr, scenario):
    out = subprocess.run([driftcorr, "eval", scenario, "--methods", "driftcorr", "--quiet"],
                         capture_output=True, text=True).stdout.splitlines()
    row = next(l for l in out if l.split() and l.split()[0] == os.path.basename(scenario.rstrip("/")))
    return float(row.split("|")[1].split()[0])


def main():
    driftcorr = sys.argv[1]
    for scenario in sys.argv[2:]:
        b = batch_ate(driftcorr, scenario)
        bound = max(2.0 * b, b + 2.0)
        run = subprocess.run([driftcorr, "stream", scenario, "--replay", "--sync", "-q",
                              "--status-column"], capture_output=True, text=True)
        rows = np.array([[float(x) for x in l.split()] for l in run.stdout.splitlines() if l.strip()])
        truth = np.loadtxt(os.path.join(scenario, "ground_truth.txt"))
        gt = truth[:, [3, 11]]  # KITTI poses: x and z are horizontal
        n = min(len(gt), len(rows))
        err = np.linalg.norm(rows[:n, [1, 3]] - gt[:n], axis=1)
        t = rows[:n, 0]
        flagged = rows[:n, -1] > 0
        beyond = np.nonzero(err > bound)[0]
        name = scenario.rstrip("/")
        if len(beyond) == 0:
            print(f"{name}: exit {run.returncode}, never beyond the bound {bound:.1f} m, "
                  f"{np.count_nonzero(flagged)} lines flagged")
            continue
        i0 = beyond[0]
        flags = np.nonzero(flagged)[0]
        if np.any(flags <= i0):
            when = "flagged at or before"
        elif len(flags):
            when = f"first flag {t[flags[flags >= i0][0]] - t[i0]:.1f} s after"
        else:
            when = "never flagged"
        print(f"{name}: exit {run.returncode}, beyond the bound {bound:.1f} m at "
              f"t+{t[i0] - t[0]:.1f} s ({100 * np.mean(err > bound):.0f} % of the lines); {when}; "
              f"{100 * np.mean(flagged[err > bound]):.0f} % of the lines beyond it flagged")


if __name__ == "__main__":
    main()
