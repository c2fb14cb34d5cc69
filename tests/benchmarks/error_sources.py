#!/usr/bin/python3
"""Where the error of a corrected road drive comes from, against its ground truth and its map.

For a road2d scenario (a `lat_deg`/`lon_deg` anchor, KITTI or TUM ground truth) and a corrected
TUM file of it, prints one line per scenario:

- ATE of the corrected track, split along and across the ground truth's direction of travel
  (RMS and mean; along > 0: the corrected pose is ahead);
- how far the ground truth itself drives from the map's vehicle centre lines: RMS distance
  (capped at 5 m) and its signed lateral offset (right of travel > 0; median), on two-way and
  one-way ways more than 25 m from a junction, and within 25 m of one;
- the same RMS distance for the corrected track;
- the constant East-North shift (and small turn) of the ground truth that brings it closest to the
  centre lines, and that distance then: what a misregistration of the map or of the anchor
  against the ground truth's frame leaves to any correction that follows the map;
- the time shift of the corrected track against the ground truth that minimises the ATE.

    /usr/bin/python3 tests/benchmarks/error_sources.py SCENARIO CORRECTED.tum [SCENARIO CORRECTED.tum ...]

Only OSM XML maps and lat/lon anchors are read; poses are matched by line (the corrected file
holds one pose per estimate line, as `driftcorr correct` writes it).
"""
import math
import os
import re
import sys
import xml.etree.ElementTree as ET

import numpy as np

VEHICLE = {"motorway", "motorway_link", "trunk", "trunk_link", "primary", "primary_link",
           "secondary", "secondary_link", "tertiary", "tertiary_link", "unclassified",
           "residential", "living_street", "service", "road", "track", "busway"}
WGS84_A = 6378137.0
WGS84_E2 = (1 / 298.257223563) * (2 - 1 / 298.257223563)
CAP_M = 5.0


def ecef(lat, lon, h):
    la, lo = math.radians(lat), math.radians(lon)
    n = WGS84_A / math.sqrt(1 - WGS84_E2 * math.sin(la) ** 2)
    return np.array([(n + h) * math.cos(la) * math.cos(lo), (n + h) * math.cos(la) * math.sin(lo),
                     (n * (1 - WGS84_E2) + h) * math.sin(la)])


def tangent_plane(lat0, lon0, h0):
    """WGS84 (lat, lon) at height h0 -> East, North of the tangent plane at the anchor."""
    o = ecef(lat0, lon0, h0)
    la, lo = math.radians(lat0), math.radians(lon0)
    r = np.array([[-math.sin(lo), math.cos(lo), 0.0],
                  [-math.sin(la) * math.cos(lo), -math.sin(la) * math.sin(lo), math.cos(la)]])
    return lambda lat, lon: r @ (ecef(lat, lon, h0) - o)


def read_scenario(folder):
    text = open(os.path.join(folder, "scenario.yaml")).read()

    def number(key):
        m = re.search(r"[\s{,]" + key + r":\s*(-?[0-9.eE+-]+)", text)
        if not m:
            sys.exit(f"{folder}: scenario.yaml has no numeric {key} (a lat/lon anchor is needed)")
        return float(m.group(1))

    def word(key):
        m = re.search(r"[\s{,]" + key + r":\s*([A-Za-z0-9_./-]+)", text)
        return m.group(1) if m else None

    gt = re.search(r"ground_truth:\s*(?:\{[^}]*path:\s*([^,}\s]+)[^}]*format:\s*(\w+)|"
                   r"\n\s+path:\s*(\S+)\s*\n\s+format:\s*(\w+))", text)
    gt_path, gt_format = (gt.group(1), gt.group(2)) if gt.group(1) else (gt.group(3), gt.group(4))
    osm = re.search(r"path:\s*([^,}\s]+\.osm)", text)
    return {"anchor": (number("lat_deg"), number("lon_deg"), number("alt_m"), number("yaw_deg")),
            "frame": word("frame"), "gt": os.path.join(folder, gt_path), "gt_format": gt_format,
            "osm": os.path.join(folder, osm.group(1))}


def horizontal(path, fmt, frame):
    a = np.loadtxt(path)
    if fmt == "kitti":
        x, y = a[:, 3], a[:, 11] if frame == "kitti_camera" else a[:, 7]
    else:
        x, y = a[:, 1], a[:, 3] if frame == "kitti_camera" else a[:, 2]
    return np.stack([x, y], 1)


def to_east_north(xy, yaw_deg):
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return np.stack([c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]], 1)


class CentreLines:
    def __init__(self, osm_path, to_plane):
        root = ET.parse(osm_path).getroot()
        nodes = {n.get("id"): (float(n.get("lat")), float(n.get("lon"))) for n in root.iter("node")}
        a, b, oneway, ends = [], [], [], {}
        for w in root.iter("way"):
            tags = {t.get("k"): t.get("v") for t in w.iter("tag")}
            if tags.get("highway") not in VEHICLE or tags.get("area") == "yes":
                continue
            refs = [r.get("ref") for r in w.iter("nd") if r.get("ref") in nodes]
            if len(refs) < 2:
                continue
            for k, r in enumerate(refs):
                ends[r] = ends.get(r, 0) + (2 if k in (0, len(refs) - 1) else 1)
            one = (tags.get("oneway") in ("yes", "1", "-1", "true")
                   or tags.get("junction") == "roundabout" or tags["highway"].startswith("motorway"))
            pts = [to_plane(*nodes[r]) for r in refs]
            for k in range(1, len(pts)):
                a.append(pts[k - 1])
                b.append(pts[k])
                oneway.append(one)
        self.a, self.b = np.array(a), np.array(b)
        self.d = self.b - self.a
        self.len2 = np.maximum((self.d ** 2).sum(1), 1e-12)
        self.oneway = np.array(oneway)
        self.junctions = np.array([to_plane(*nodes[r]) for r, k in ends.items() if k >= 3])

    def nearest(self, p, direction=None):
        """Index of the nearest segment (aligned within 45 deg of `direction` if given), its foot
        point and distance."""
        t = np.clip(((p - self.a) * self.d).sum(1) / self.len2, 0.0, 1.0)
        foot = self.a + t[:, None] * self.d
        dist = np.linalg.norm(foot - p, axis=1)
        if direction is not None:
            aligned = np.abs((self.d * direction).sum(1)) / np.sqrt(self.len2) > math.cos(math.pi / 4)
            dist = np.where(aligned, dist, np.inf)
        k = int(np.argmin(dist))
        return k, foot[k], dist[k]

    def rms_distance(self, points):
        d = np.array([min(self.nearest(p)[2], CAP_M) for p in points])
        return math.sqrt((d ** 2).mean())


def travel_directions(en):
    n = len(en)
    ahead = en[np.minimum(np.arange(n) + 3, n - 1)] - en[np.maximum(np.arange(n) - 3, 0)]
    norm = np.linalg.norm(ahead, axis=1)
    return ahead / np.maximum(norm, 1e-9)[:, None], norm > 1.0


def best_shift(lines, en):
    """The constant shift (dE, dN, turn about the start) of `en` closest to the centre lines."""
    sample = en[::5]
    best = (lines.rms_distance(sample), 0.0, 0.0, 0.0)
    for turn in (-0.004, -0.002, 0.0, 0.002, 0.004):
        c, s = math.cos(turn), math.sin(turn)
        turned = np.stack([c * sample[:, 0] - s * sample[:, 1], s * sample[:, 0] + c * sample[:, 1]], 1)
        for de in np.arange(-2.0, 2.01, 0.5):
            for dn in np.arange(-2.0, 2.01, 0.5):
                v = lines.rms_distance(turned + [de, dn])
                if v < best[0]:
                    best = (v, de, dn, turn)
    return best


def best_time_shift(gt, corrected, rate_poses):
    n = len(gt)
    out = []
    for shift in np.arange(-0.3, 0.301, 0.05):
        idx = np.arange(n) + shift * rate_poses
        ok = (idx >= 0) & (idx <= n - 1)
        i0 = np.floor(idx[ok]).astype(int)
        f = (idx[ok] - i0)[:, None]
        g = gt[i0] * (1 - f) + gt[np.minimum(i0 + 1, n - 1)] * f
        out.append((math.sqrt(((corrected[ok] - g) ** 2).sum(1).mean()), shift))
    return min(out)


def report(folder, corrected_path):
    sc = read_scenario(folder)
    lat, lon, alt, yaw = sc["anchor"]
    lines = CentreLines(sc["osm"], tangent_plane(lat, lon, alt))
    gt = to_east_north(horizontal(sc["gt"], sc["gt_format"], sc["frame"]), yaw)
    corr = to_east_north(horizontal(corrected_path, "tum", sc["frame"]), yaw)
    n = min(len(gt), len(corr))
    gt, corr = gt[:n], corr[:n]
    err = corr - gt
    direction, moving = travel_directions(gt)
    right = np.stack([direction[:, 1], -direction[:, 0]], 1)
    along, across = (err * direction).sum(1)[moving], (err * right).sum(1)[moving]

    groups = {"two-way": [], "one-way": [], "junction": []}
    for i in np.nonzero(moving)[0]:
        k, foot, dist = lines.nearest(gt[i], direction[i])
        if dist > 15.0:
            continue
        offset = float((gt[i] - foot) @ right[i])
        near = len(lines.junctions) and np.min(np.linalg.norm(lines.junctions - gt[i], axis=1)) <= 25
        groups["junction" if near else ("one-way" if lines.oneway[k] else "two-way")].append(offset)

    times = np.loadtxt(corrected_path)[:n, 0]
    rate = 1.0 / np.median(np.diff(times))
    shift = best_shift(lines, gt)
    tshift = best_time_shift(gt, corr, rate)

    def rms(v):
        return math.sqrt((np.asarray(v) ** 2).mean())

    name = os.path.basename(os.path.normpath(folder))
    print(f"{name}: ATE {rms(np.linalg.norm(err, axis=1)):.2f} m; along {rms(along):.2f} "
          f"(mean {along.mean():+.2f}), across {rms(across):.2f} (mean {across.mean():+.2f})")
    print("  ground truth from the centre lines: RMS %.2f m; signed offset (right +), median: %s"
          % (lines.rms_distance(gt[::5]), ", ".join(
              f"{g} {np.median(v):+.2f} (n {len(v)})" for g, v in groups.items() if v)))
    print(f"  corrected from the centre lines: RMS {lines.rms_distance(corr[::5]):.2f} m")
    print(f"  ground truth shifted E {shift[1]:+.1f} N {shift[2]:+.1f} m, turned "
          f"{math.degrees(shift[3]):+.2f} deg: RMS {shift[0]:.2f} m from the centre lines")
    print(f"  corrected against the ground truth {tshift[1]:+.2f} s later: ATE {tshift[0]:.2f} m")


def main():
    args = sys.argv[1:]
    if len(args) < 2 or len(args) % 2:
        sys.exit(__doc__)
    for k in range(0, len(args), 2):
        report(args[k], args[k + 1])


if __name__ == "__main__":
    main()
