#!/usr/bin/env python3
"""Writes road2d scenarios (docs/FORMAT.md) whose estimate is a drive's ground truth re-integrated
with the errors of an odometry of a chosen quality, for judging a corrector on inputs of every
accuracy: from a LiDAR odometry that is already better than the map's centre lines to a drifting
visual odometry. Its errors differ from the road generator's (datasets/synth_road): they are laid
on a real drive's motion and a real map.

Each step of the ground truth (KITTI 3x4 poses, camera frame: x right, y down, z forward) is
re-integrated with
  - its translation times a step scale 1 + c + w(path): c a constant scale error, w a random walk
    of --scale-rw per sqrt(100 m) of path;
  - its rotation turned about the camera's vertical axis by (b + v(t)) dt: b a constant
    heading-rate bias [deg/s], v a random walk of --bias-rw [deg/s per sqrt(s)];
  - a white error of --step-noise-m per axis added to its horizontal translation.
The scenario folder gets the new estimate.txt and links to the source scenario's ground truth and
map (nothing of the source is copied); its scenario.yaml is the source's with the name changed.
Deterministic for a seed.

    /usr/bin/python3 datasets/stress/make_odometry_from_truth.py SRC_SCENARIO_DIR OUT_DIR \
        [--scale 0.005] [--scale-rw 0.002] [--bias-deg-s 0.01] [--bias-rw 0.001] \
        [--step-noise-m 0.005] [--seed 1]
"""
import argparse
import math
import os
import re
import sys

import numpy as np


def read_kitti(path):
    rows = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            v = line.split()
            if not v:
                continue
            if len(v) != 12:
                sys.exit(f"{path}:{number}: expected 12 numbers of a KITTI pose, got {len(v)}")
            t = np.eye(4)
            t[:3, :] = np.array([float(x) for x in v]).reshape(3, 4)
            rows.append(t)
    return rows


def yaw_about_vertical(angle_rad):
    """A rotation about the camera's y axis (down): turns the horizontal x-z plane."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    r = np.eye(4)
    r[0, 0], r[0, 2], r[2, 0], r[2, 2] = c, s, -s, c
    return r


def perturb(truth, rate_hz, args, rng):
    dt = 1.0 / rate_hz
    out = [truth[0].copy()]
    walk, bias_walk = 0.0, 0.0
    for i in range(1, len(truth)):
        rel = np.linalg.inv(truth[i - 1]) @ truth[i]
        step_m = float(np.linalg.norm(rel[:3, 3]))
        walk += args.scale_rw * math.sqrt(step_m / 100.0) * rng.standard_normal()
        bias_walk += args.bias_rw * math.sqrt(dt) * rng.standard_normal()
        rel = rel.copy()
        rel[:3, 3] *= 1.0 + args.scale + walk
        rel[0, 3] += args.step_noise_m * rng.standard_normal()
        rel[2, 3] += args.step_noise_m * rng.standard_normal()
        rel = yaw_about_vertical(math.radians((args.bias_deg_s + bias_walk) * dt)) @ rel
        out.append(out[-1] @ rel)
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("src", help="a road2d scenario folder with a KITTI ground truth")
    p.add_argument("out", help="the folder to write the scenario into")
    p.add_argument("--scale", type=float, default=0.005, help="constant step scale error")
    p.add_argument("--scale-rw", type=float, default=0.002, help="per sqrt(100 m)")
    p.add_argument("--bias-deg-s", type=float, default=0.01, help="heading-rate bias [deg/s]")
    p.add_argument("--bias-rw", type=float, default=0.001, help="[deg/s per sqrt(s)]")
    p.add_argument("--step-noise-m", type=float, default=0.005, help="per step and axis [m]")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()

    yaml_path = os.path.join(args.src, "scenario.yaml")
    with open(yaml_path) as f:
        text = f.read()
    m = re.search(r"ground_truth:\s*\n\s*path:\s*(\S+)\s*\n\s*format:\s*kitti\s*\n\s*rate_hz:\s*(\S+)",
                  text)
    if not m:
        sys.exit(f"{yaml_path}: no ground_truth of format kitti with rate_hz")
    truth = read_kitti(os.path.join(args.src, m.group(1)))
    estimate = perturb(truth, float(m.group(2)), args, np.random.default_rng(args.seed))

    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "estimate.txt"), "w") as f:
        for t in estimate:
            f.write(" ".join(repr(float(x)) for x in t[:3, :].reshape(-1)) + "\n")
    src = os.path.abspath(args.src)
    for name in os.listdir(src):
        if name not in ("scenario.yaml", "estimate.txt"):
            link = os.path.join(args.out, name)
            if os.path.lexists(link):
                os.remove(link)
            os.symlink(os.path.join(src, name), link)
    name = os.path.basename(os.path.normpath(args.out))
    text = re.sub(r"^name:.*$", f"name: {name}", text, count=1, flags=re.M)
    text = re.sub(r"(estimate:\s*\n\s*path:\s*)\S+", r"\1estimate.txt", text, count=1)
    with open(os.path.join(args.out, "scenario.yaml"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
