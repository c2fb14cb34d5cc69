#!/usr/bin/python3
"""When does a stream say it is in doubt, and does its causal output come back?

For each scenario (a KITTI ground truth in its folder): the batch ATE from `driftcorr eval
--methods driftcorr`, then `driftcorr stream --replay --sync --status-column`. The bound is
max(2x the batch ATE, batch + 2 m) on the causal error (horizontal, the scenario's frame, no
re-alignment). Every excursion (a stretch of lines beyond the bound) is reported with:
- the delay of its flag: the first line with a doubt bit (the status column's last) from 5 s
  before the excursion's start to its end, in seconds after the start (negative: flagged before);
- when the map disambiguates: the end of the ground truth's first turn (its heading 30 degrees
  or more from the heading at the excursion's start) after the start and after the dropped-step
  episode in progress then (`drop_steps` variants: the steps shorter than the `clean` sibling's);
- the return: seconds from that moment to the first line back within the bound (negative: back
  before the turn); "never back" when the stream ends beyond it, with the time from the turn to
  the end.
Excursions shorter than 1 s are merged into their neighbours.

    /usr/bin/python3 tests/benchmarks/stream_doubt_delay.py build/examples/driftcorr SCENARIO...
"""
import os
import subprocess
import sys

import numpy as np

FLAG_BEFORE_S = 5.0
TURN_DEG = 30.0
MERGE_S = 1.0


def batch_ate(driftcorr, scenario):
    out = subprocess.run([driftcorr, "eval", scenario, "--methods", "driftcorr", "--quiet"],
                         capture_output=True, text=True).stdout.splitlines()
    row = next(l for l in out if l.split() and l.split()[0] == os.path.basename(scenario.rstrip("/")))
    return float(row.split("|")[1].split()[0])


def kitti_xz(path):
    poses = np.loadtxt(path)
    if poses.shape[1] == 13:  # frame index first
        poses = poses[:, 1:]
    return poses[:, [3, 11]]


def dropped_until(scenario, n):
    """Per step, the index of the end of the dropped-step episode it lies in (or itself)."""
    clean = os.path.join(os.path.dirname(scenario.rstrip("/")), "clean", "estimate.txt")
    until = np.arange(n)
    if os.path.basename(scenario.rstrip("/")) != "drop_steps" or not os.path.exists(clean):
        return until
    a = np.linalg.norm(np.diff(kitti_xz(os.path.join(scenario, "estimate.txt"))[:n], axis=0), axis=1)
    b = np.linalg.norm(np.diff(kitti_xz(clean)[:n], axis=0), axis=1)
    short = np.concatenate([[False], a < 0.95 * b - 1e-6])
    end = n - 1
    for i in range(n - 1, -1, -1):
        if not short[i]:
            end = i
        until[i] = end if short[i] else i
    return until


def headings(gt):
    """Heading of the ground truth at each pose, over the next 5 m of path."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(gt, axis=0), axis=1))])
    j = np.minimum(np.searchsorted(s, s + 5.0), len(gt) - 1)
    i = np.maximum(np.searchsorted(s, s - 5.0), 0)
    d = gt[j] - gt[i]
    return np.arctan2(d[:, 1], d[:, 0])


def excursions(beyond, t):
    runs, i, n = [], 0, len(beyond)
    while i < n:
        if not beyond[i]:
            i += 1
            continue
        j = i
        while j < n and beyond[j]:
            j += 1
        if runs and t[i] - t[runs[-1][1]] < MERGE_S:
            runs[-1][1] = j
        else:
            runs.append([i, j])
        i = j
    return [(a, b) for a, b in runs if b - a > 0]


def main():
    driftcorr = sys.argv[1]
    for scenario in sys.argv[2:]:
        b = batch_ate(driftcorr, scenario)
        bound = max(2.0 * b, b + 2.0)
        run = subprocess.run([driftcorr, "stream", scenario, "--replay", "--sync", "-q",
                              "--status-column"], capture_output=True, text=True)
        rows = np.array([[float(x) for x in l.split()] for l in run.stdout.splitlines() if l.strip()])
        gt = kitti_xz(os.path.join(scenario, "ground_truth.txt"))
        n = min(len(gt), len(rows))
        gt = gt[:n]
        err = np.linalg.norm(rows[:n, [1, 3]] - gt, axis=1)
        t = rows[:n, 0]
        flagged = rows[:n, -1] > 0
        beyond = err > bound
        name = scenario.rstrip("/")
        head = f"{name}: exit {run.returncode}, bound {bound:.1f} m"
        runs = excursions(beyond, t)
        if not runs:
            print(f"{head}, never beyond it, {np.count_nonzero(flagged)} lines flagged")
            continue
        until = dropped_until(scenario, n)
        yaw = headings(gt)
        parts = []
        for a, e in runs:
            window = np.nonzero(flagged & (t >= t[a] - FLAG_BEFORE_S) & (np.arange(n) < e))[0]
            flag = f"flag {t[window[0]] - t[a]:+.1f} s" if len(window) else "never flagged"
            k0 = until[a]
            turned = np.abs(np.angle(np.exp(1j * (yaw[k0:] - yaw[k0])))) >= np.radians(TURN_DEG)
            k = np.nonzero(turned)[0]
            if len(k):
                kt = k0 + k[0]
                # the turn ends where the heading stops changing by more than 2 degrees a second
                while kt + 1 < n and abs(np.angle(np.exp(1j * (yaw[kt + 1] - yaw[kt])))) > \
                        np.radians(2.0) * (t[kt + 1] - t[kt]):
                    kt += 1
                td = t[kt]
            else:
                td = None
            if e >= n and td is None:
                back = "the drive ends beyond it, with no turn after its start"
            elif e >= n:
                back = f"never back; the drive ends {t[-1] - td:.1f} s after the turn"
            elif td is None:
                back = f"back after {t[e] - t[a]:.1f} s (no turn after)"
            else:
                back = f"back {t[e] - td:+.1f} s after the turn"
            parts.append(f"[t+{t[a] - t[0]:.1f} s, {t[min(e, n - 1)] - t[a]:.1f} s long, "
                         f"max {err[a:e].max():.1f} m: {flag}; {back}]")
        print(f"{head}, {100 * np.mean(beyond):.0f} % of the lines beyond it, "
              f"{100 * np.mean(flagged[beyond]):.0f} % of those flagged; " + " ".join(parts))


if __name__ == "__main__":
    main()
