#!/usr/bin/env python3
"""Writes a road2d scenario (docs/FORMAT.md) on a large synthetic town, for measuring the memory
and time of the road field on maps larger than a city district.

The map: a grid of residential streets 150-400 m apart (a fixed pseudo-random sequence, so that
no two blocks look alike) over SIZE x SIZE metres of the anchor's East-North tangent plane,
written in WGS84 (OpenStreetMap XML) through the exact ENU -> ECEF -> geodetic transform, so that
the streets lie where the ground truth drives in the scenario's `enu` frame. The drive: an L along two streets, about LEG metres East along the second street
from the South, then about LEG metres North, at 10 m/s and 10 Hz. The estimate dead-reckons the drive's steps
with a step scale of 0.99 and a heading that drifts by 1e-6 rad a step; each pose's orientation
faces its next step. Deterministic.

    python3 datasets/large_town/make_large_town.py OUT_DIR [--size 10000] [--leg 8000]
"""
import argparse
import math
import os

LAT0, LON0, ALT0 = 48.98, 8.39, 110.0
A, F = 6378137.0, 1.0 / 298.257223563
E2 = F * (2.0 - F)
S = math.sin(math.radians(LAT0))
M = A * (1.0 - E2) / (1.0 - E2 * S * S) ** 1.5  # meridional radius of curvature
N = A / math.sqrt(1.0 - E2 * S * S)             # prime vertical radius of curvature
SPEED, RATE = 10.0, 10.0


def latlon_near(e, n):
    """A point near the grid's origin through the radii of curvature (the anchor only)."""
    return (LAT0 + math.degrees(n / M), LON0 + math.degrees(e / (N * math.cos(math.radians(LAT0)))))


def ecef(lat_deg, lon_deg, h):
    la, lo = math.radians(lat_deg), math.radians(lon_deg)
    nu = A / math.sqrt(1.0 - E2 * math.sin(la) ** 2)
    return ((nu + h) * math.cos(la) * math.cos(lo), (nu + h) * math.cos(la) * math.sin(lo),
            (nu * (1.0 - E2) + h) * math.sin(la))


def geodetic(x, y, z):
    """ECEF -> (lat, lon) in degrees; the latitude by fixed-point iteration (converges to 1e-12)."""
    lon = math.atan2(y, x)
    p = math.hypot(x, y)
    lat = math.atan2(z, p * (1.0 - E2))
    for _ in range(10):
        nu = A / math.sqrt(1.0 - E2 * math.sin(lat) ** 2)
        h = p / math.cos(lat) - nu
        lat = math.atan2(z, p * (1.0 - E2 * nu / (nu + h)))
    return math.degrees(lat), math.degrees(lon)


class Enu:
    """The East-North-Up tangent plane at (lat, lon, ALT0): plane point -> WGS84 (lat, lon)."""

    def __init__(self, lat_deg, lon_deg):
        self.origin = ecef(lat_deg, lon_deg, ALT0)
        la, lo = math.radians(lat_deg), math.radians(lon_deg)
        self.east = (-math.sin(lo), math.cos(lo), 0.0)
        self.north = (-math.sin(la) * math.cos(lo), -math.sin(la) * math.sin(lo), math.cos(la))

    def latlon(self, e, n):
        return geodetic(*(o + e * ea + n * na for o, ea, na in zip(self.origin, self.east, self.north)))


def streets(size):
    """Street offsets [m] from 0: spacings 150-400 m from a fixed linear congruential sequence."""
    offsets, state = [0.0], 12345
    while True:
        state = (1103515245 * state + 12345) % 2**31
        nxt = offsets[-1] + 150.0 + 250.0 * state / 2**31
        if nxt > size:
            return offsets
        offsets.append(round(nxt, 1))


def write_map(path, xs, enu, e0, n0):
    k = len(xs) - 1
    with open(path + ".tmp", "w") as f:
        f.write('<?xml version="1.0" encoding="UTF-8"?>\n<osm version="0.6" generator="make_large_town">\n')
        for j in range(k + 1):
            for i in range(k + 1):
                lat, lon = enu.latlon(xs[i] - e0, xs[j] - n0)
                f.write(f'  <node id="{1 + j * (k + 1) + i}" lat="{lat:.9f}" lon="{lon:.9f}"/>\n')
        way = 1
        for fixed in range(k + 1):
            for along_x in (True, False):
                f.write(f'  <way id="{way}">\n')
                for m in range(k + 1):
                    i, j = (m, fixed) if along_x else (fixed, m)
                    f.write(f'    <nd ref="{1 + j * (k + 1) + i}"/>\n')
                f.write('    <tag k="highway" v="residential"/>\n  </way>\n')
                way += 1
        f.write('</osm>\n')
    os.replace(path + ".tmp", path)


def drive(xs, leg):
    """East along street 1 from crossing 1 to the crossing nearest leg metres on, then North."""
    step = SPEED / RATE
    x0, y0 = xs[1], xs[1]
    x1 = min(xs, key=lambda x: abs(x - (x0 + leg)))
    y1 = min(xs, key=lambda y: abs(y - (y0 + leg)))
    pts = [(x0 + s * step, y0) for s in range(int((x1 - x0) / step) + 1)]
    pts += [(x1, y0 + s * step) for s in range(1, int((y1 - y0) / step) + 1)]
    return pts, (x0, y0)


def write_tum(path, pts):
    """TUM lines, each orientation a rotation about Up to the direction of the next step."""
    with open(path + ".tmp", "w") as f:
        for i, (x, y) in enumerate(pts):
            j = min(i + 1, len(pts) - 1)
            k = j - 1 if j == i else i
            yaw = math.atan2(pts[j][1] - pts[k][1], pts[j][0] - pts[k][0])
            f.write(f"{i / RATE:.6f} {x:.4f} {y:.4f} 0.0000 0 0 "
                    f"{math.sin(yaw / 2):.9f} {math.cos(yaw / 2):.9f}\n")
    os.replace(path + ".tmp", path)


def dead_reckon(gt):
    est, yaw_err = [gt[0]], 0.0
    for i in range(1, len(gt)):
        dx, dy = gt[i][0] - gt[i - 1][0], gt[i][1] - gt[i - 1][1]
        yaw_err += 1e-6
        c, s = math.cos(yaw_err), math.sin(yaw_err)
        x, y = est[-1]
        est.append((x + 0.99 * (c * dx - s * dy), y + 0.99 * (s * dx + c * dy)))
    return est


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out_dir")
    ap.add_argument("--size", type=float, default=10000.0)
    ap.add_argument("--leg", type=float, default=8000.0)
    a = ap.parse_args()
    xs = streets(a.size)
    if not 0.0 < a.leg < a.size - 2.0 * xs[1]:
        ap.error("--leg must be within (0, size - 2 x the first block)")
    os.makedirs(a.out_dir, exist_ok=True)
    gt, (e0, n0) = drive(xs, a.leg)
    # The trajectory frame starts at the drive's start: the anchor is that crossing, and the
    # map's plane is the anchor's tangent plane.
    lat_s, lon_s = latlon_near(e0, n0)
    write_map(os.path.join(a.out_dir, "map.osm"), xs, Enu(lat_s, lon_s), e0, n0)
    gt = [(x - e0, y - n0) for x, y in gt]
    write_tum(os.path.join(a.out_dir, "ground_truth.tum"), gt)
    write_tum(os.path.join(a.out_dir, "estimate.tum"), dead_reckon(gt))
    yaml = f"""name: large-town-L
mode: road2d
estimate: {{path: estimate.tum, format: tum}}
ground_truth: {{path: ground_truth.tum, format: tum}}
frame: enu
anchor: {{lat_deg: {lat_s:.9f}, lon_deg: {lon_s:.9f}, alt_m: {ALT0}, yaw_deg: 0.0}}
map:
  - {{path: map.osm, format: osm}}
"""
    path = os.path.join(a.out_dir, "scenario.yaml")
    if os.path.exists(path):
        os.remove(path)
    with open(path + ".tmp", "w") as f:
        f.write(yaml)
    os.replace(path + ".tmp", path)


if __name__ == "__main__":
    main()
