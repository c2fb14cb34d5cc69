#!/usr/bin/python3
"""What the height error of a KITTI road drive is made of, against its ground truth.

For each (scenario, corrected TUM) pair of a road2d scenario with KITTI ground truth and estimate
in the `kitti_camera` frame (x right, y down, z forward; up = -y), prints:

- the vertical RMS error of the estimate and of the corrected file (matched by line);
- the estimate's error after removing the best plane through it, e = a x + b z + c (a tilt of the
  estimate's frame against the ground truth's, and an offset): the tilt's two angles and the RMS
  left. A tilt is the same at every revisit of a place, so neither a revisit's height nor a road's
  bounded grade observes it; only an elevation reference (a DEM, surveyed heights) does;
- the RMS left after removing the best error proportional to the path travelled (a constant
  pitch drift), for comparison.

    /usr/bin/python3 tests/benchmarks/height_error_sources.py SCENARIO CORRECTED.tum [...]
"""
import os
import sys

import numpy as np


def up_and_plane(path):
    a = np.loadtxt(path)
    return a[:, 3], -a[:, 7], a[:, 11]


def rms(v):
    return float(np.sqrt(np.mean(v ** 2)))


def main(args):
    if len(args) < 2 or len(args) % 2:
        sys.exit(__doc__)
    print("| scenario | vertical RMS input / corrected [m] | frame tilt about z / x [deg] | "
          "input after the tilt [m] | input after a pitch drift [m] |")
    print("|---|---|---|---|---|")
    for scenario, corrected in zip(args[0::2], args[1::2]):
        gx, gu, gz = up_and_plane(os.path.join(scenario, "ground_truth.txt"))
        _, eu, _ = up_and_plane(os.path.join(scenario, "estimate.txt"))
        cu = -np.loadtxt(corrected, usecols=(2,))
        n = min(len(gu), len(eu), len(cu))
        e_in, e_out = eu[:n] - gu[:n], cu[:n] - gu[:n]
        plane = np.c_[gx[:n], gz[:n], np.ones(n)]
        coef, *_ = np.linalg.lstsq(plane, e_in, rcond=None)
        path = np.r_[0.0, np.cumsum(np.hypot(np.diff(gx[:n]), np.diff(gz[:n])))]
        drift = np.c_[path, np.ones(n)]
        dcoef, *_ = np.linalg.lstsq(drift, e_in, rcond=None)
        print(f"| {os.path.basename(os.path.normpath(scenario))} | {rms(e_in):.2f} / {rms(e_out):.2f} | "
              f"{np.degrees(np.arctan(coef[0])):.2f} / {np.degrees(np.arctan(coef[1])):.2f} | "
              f"{rms(e_in - plane @ coef):.2f} | {rms(e_in - drift @ dcoef):.2f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
