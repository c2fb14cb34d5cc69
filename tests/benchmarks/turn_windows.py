#!/usr/bin/python3
"""The verdict's test of turns the estimate does not make, recomputed from written files.

For each (scenario directory, corrected TUM file) pair: per window of corrected path, the mean
square of the corrected minus the estimated heading change per step (the steps' directions, where
both steps are longer than --min-step-m and span no gap in the input's times, over 3 times its
median step time), and the largest window's ratio to the median window
(VerdictConfig::turn_window_m, turn_min_step_m, turn_ratio; optim/src/verdict.cpp JudgeTurns).
Prints the ratio, where it lies, and the window's mean square against the model's heading noise
over its steps (the verdict flags a window beyond both).

The estimate is read in the scenario's frame (KITTI camera frame: x and z horizontal; ENU: x and
y); an estimate of unknown size (`scale: auto`) has its steps compared with --min-step-m at the
corrected path's median step over its own.

  /usr/bin/python3 tests/benchmarks/turn_windows.py <scenario_dir> <corrected.tum> [...]
"""
import argparse
import os
import re

import numpy as np


def load_estimate(scenario_dir):
    text = open(os.path.join(scenario_dir, "scenario.yaml")).read()
    m = re.search(r'estimate:\s*\{?\s*\n?\s*path:\s*"?([^",}\n]+)"?', text)
    e = np.loadtxt(os.path.join(scenario_dir, m.group(1).strip()))
    if e.shape[1] == 8:  # TUM, ENU
        return e[:, 0], e[:, 1:3], (1, 2)
    if e.shape[1] == 13:  # KITTI with frame indices (10 Hz)
        return e[:, 0] * 0.1, e[:, 1:][:, [3, 11]], (1, 3)
    return np.arange(len(e)) * 0.1, e[:, [3, 11]], (1, 3)


def turn_windows(scenario_dir, corrected_path, window_m, min_step_m, rw, rel):
    t, est, cols = load_estimate(scenario_dir)
    cor = np.loadtxt(corrected_path, usecols=range(8))
    if cor[:, 0].size == t.size:
        t = cor[:, 0]
    cor = cor[:, list(cols)]
    n = min(len(est), len(cor))
    est, cor, t = est[:n], cor[:n], t[:n]
    de, dc = np.diff(est, axis=0), np.diff(cor, axis=0)
    le, lc = np.hypot(*de.T), np.hypot(*dc.T)
    moving_c = lc[lc > 0]
    ratio = np.median(moving_c) / np.median(le[le > 0]) if moving_c.size else 1.0
    dts = np.diff(t)
    no_gap = dts <= 3.0 * np.median(dts) if np.median(dts) > 0 else np.ones_like(dts, bool)
    moving = (lc > min_step_m) & (le * ratio > min_step_m) & no_gap
    he, hc = np.arctan2(de[:, 1], de[:, 0]), np.arctan2(dc[:, 1], dc[:, 0])
    wrap = lambda a: (a + np.pi) % (2 * np.pi) - np.pi
    path = np.cumsum(lc)
    sums, noise, counts = {}, {}, {}
    for i in range(1, n - 1):
        if not (moving[i] and moving[i - 1]):
            continue
        turn_e = wrap(he[i] - he[i - 1])
        r = wrap(wrap(hc[i] - hc[i - 1]) - turn_e)
        k = int(path[i] // window_m)
        dt = max(t[i + 1] - t[i], 0.0)
        sums[k] = sums.get(k, 0.0) + r * r
        noise[k] = noise.get(k, 0.0) + rw * rw * dt + (rel * turn_e) ** 2
        counts[k] = counts.get(k, 0) + 1
    keys = [k for k in sorted(sums) if counts[k] >= 10]
    if len(keys) < 3:
        return None
    ms = np.array([sums[k] / counts[k] for k in keys])
    median = np.median(ms)
    if not median > 0:
        return None
    j = int(np.argmax(ms / median))
    return ms[j] / median, keys[j] * window_m, sums[keys[j]] / noise[keys[j]], path[-1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pairs", nargs="+", help="scenario_dir corrected.tum, repeated")
    ap.add_argument("--window-m", type=float, default=200.0)
    ap.add_argument("--min-step-m", type=float, default=0.3)
    ap.add_argument("--heading-rw", type=float, default=0.004, help="rad/sqrt(s)")
    ap.add_argument("--heading-rel", type=float, default=0.02)
    a = ap.parse_args()
    if len(a.pairs) % 2:
        ap.error("give scenario_dir corrected.tum pairs")
    for d, c in zip(a.pairs[::2], a.pairs[1::2]):
        r = turn_windows(d, c, a.window_m, a.min_step_m, a.heading_rw, a.heading_rel)
        if r is None:
            print(f"{d}: fewer than three windows")
            continue
        ratio, at_m, over_noise, path_m = r
        print(f"{d}: largest window {ratio:.1f} x the median, from {at_m:.0f} m of {path_m:.0f} m; "
              f"its heading-change differences {over_noise:.2f} x the model's noise")


if __name__ == "__main__":
    main()
