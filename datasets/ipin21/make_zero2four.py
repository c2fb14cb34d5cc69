#!/usr/bin/python3
"""Builds a driftcorr scenario (docs/FORMAT.md) from the IPIN 2021 "Zero2four" walk.

The walk (Samsung S10, HCU building Hamburg) starts on the ground floor, climbs the stairs to the
1st floor and takes the lift to the 4th floor. Its data is public but carries no licence, so it is
not in this repository: clone https://github.com/Hossein-Shoushtari/IPIN21Data and run

    /usr/bin/python3 datasets/ipin21/make_zero2four.py <IPIN21Data clone> <output dir>

Conventions, the same as ../shared/datasets/hcu_eight (the "Eight" walk of the same data set):
- estimate.tum: PDR integrated from the authors' step lengths, step headings and barometric height
  changes, starting at waypoint 0; the initial heading is the bearing from waypoint 0 to waypoint 2
  (the repository's own 3DPDR.py uses a hand-set 20 deg instead). Step i ends at ground-truth row i.
- ground_truth.tum: the authors' per-step ground truth minus waypoint 0; orientation = direction of
  travel. The ground truth has no height: each row gets the height of the surveyed waypoints around
  it, linear in time between two waypoints on different floors (the stairs), relative to waypoint 0.
- local ENU frame, anchor = waypoint 0 in UTM 32N (EPSG:32632); the map is the repository's
  MapMaterial floor plans and walkway networks of the three floors, copied next to the scenario.
Python standard library only. Exit code 2 on missing or inconsistent input, nothing written then.
"""
import glob
import math
import os
import sys

FLOORS = (("EG", 1.3), ("1OG", 7.6), ("4OG", 19.6))


def fail(msg):
    print("make_zero2four: " + msg, file=sys.stderr)
    sys.exit(2)


def rows(path, width):
    out = []
    with open(path, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            parts = line.split()
            if not parts:
                continue
            if len(parts) != width:
                fail(f"{path}:{n}: expected {width} columns, found {len(parts)}")
            try:
                out.append([float(p) for p in parts])
            except ValueError:
                fail(f"{path}:{n}: not a number: {line.strip()}")
    return out


CRS84 = '"urn:ogc:def:crs:OGC:1.3:CRS84"'
UTM32N = '"urn:ogc:def:crs:EPSG::32632"'


def copy_layer(src, dst):
    """Copies a MapMaterial layer. Two of the repository's walkway networks (RouteEG, Route1OG) declare
    CRS84 (degrees) while their coordinates are UTM 32N metres like every other layer; driftcorr
    rejects that contradiction, so the copy declares UTM 32N, and says so."""
    with open(src, encoding="utf-8") as f:
        text = f.read()
    first = text.find('"coordinates"')
    numbers = text[first:first + 200].replace("[", " ").replace(",", " ").split()[1:3]
    try:
        metres = first >= 0 and any(abs(float(v)) > 180.0 for v in numbers)
    except ValueError:
        metres = False
    if CRS84 in text and metres:
        text = text.replace(CRS84, UTM32N, 1)
        print(f"make_zero2four: {os.path.basename(src)} declares CRS84 but its coordinates are "
              "UTM 32N metres; the copy declares EPSG:32632", file=sys.stderr)
    tmp = dst + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, dst)


def quat(yaw):
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    src, out = argv[1], argv[2]
    need = {n: os.path.join(src, n) for n in ("Zero2fourStepLengths.csv", "Zero2fourStepHeadigs.csv",
                                              "Zero2fourDeltaHeight.csv", "GroundTruthZero2Four.csv")}
    waypoint_files = glob.glob(os.path.join(src, "*Zero2fourWaypoints.csv"))  # name has a leading U+0650
    maps = {f"{kind}{fl}": os.path.join(src, "MapMaterial", f"{kind}{fl}.geojson")
            for kind in ("Plan", "Route") for fl, _ in FLOORS}
    missing = [p for p in list(need.values()) + list(maps.values()) if not os.path.isfile(p)]
    if len(waypoint_files) != 1:
        missing.append(os.path.join(src, "Zero2fourWaypoints.csv") +
                       (f" (found {len(waypoint_files)})" if waypoint_files else ""))
    if missing:
        fail("not an IPIN21Data clone: missing " + ", ".join(missing))

    length = [r[0] for r in rows(need["Zero2fourStepLengths.csv"], 1)]
    heading = [r[0] for r in rows(need["Zero2fourStepHeadigs.csv"], 1)]
    dz = [r[0] for r in rows(need["Zero2fourDeltaHeight.csv"], 1)]
    gt = rows(need["GroundTruthZero2Four.csv"], 3)   # t [ms], easting, northing
    wp = rows(waypoint_files[0], 4)                  # t [ms], easting, northing, height
    if not (len(length) == len(heading) == len(dz) == len(gt)) or len(gt) < 2 or len(wp) < 3:
        fail(f"inconsistent lengths: {len(length)} steps, {len(heading)} headings, {len(dz)} height "
             f"changes, {len(gt)} ground-truth rows, {len(wp)} waypoints")

    e0, n0, z0 = wp[0][1], wp[0][2], wp[0][3]
    h0 = math.atan2(wp[2][2] - n0, wp[2][1] - e0)

    def height(t_ms):
        if t_ms <= wp[0][0]:
            return wp[0][3]
        for a, b in zip(wp, wp[1:]):
            if a[0] <= t_ms <= b[0]:
                return a[3] + (b[3] - a[3]) * (t_ms - a[0]) / (b[0] - a[0]) if b[0] > a[0] else b[3]
        return wp[-1][3]

    est, ref = [], []
    x = y = z = 0.0
    px = py = 0.0
    for i, (t_ms, e, n) in enumerate(gt):
        yaw = h0 + heading[i]
        x += length[i] * math.cos(yaw)
        y += length[i] * math.sin(yaw)
        z += dz[i]
        t = t_ms / 1000.0
        est.append((t, x, y, z) + quat(yaw))
        gx, gy = e - e0, n - n0
        ref.append((t, gx, gy, height(t_ms) - z0) + quat(math.atan2(gy - py, gx - px)))
        px, py = gx, gy
    if any(b[0] <= a[0] for a, b in zip(est, est[1:])):
        fail("ground-truth timestamps are not increasing")

    os.makedirs(out, exist_ok=True)
    fmt = "%.3f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n"
    files = {"estimate.tum": est, "ground_truth.tum": ref}
    for name, poses in files.items():
        tmp = os.path.join(out, name + ".tmp")
        with open(tmp, "w", encoding="utf-8") as f:
            f.writelines(fmt % p for p in poses)
        os.replace(tmp, os.path.join(out, name))
    for name, path in maps.items():
        copy_layer(path, os.path.join(out, name + ".geojson"))
    layers = "".join(
        f"  - {{path: {kind}{fl}.geojson, format: geojson, role: {role}, floor_z_m: {z}}}\n"
        for fl, z in FLOORS for kind, role in (("Route", "walkways"), ("Plan", "floorplan")))
    yaml = (
        "# HCU Hamburg indoor pedestrian walk 'Zero2four' (IPIN 2021 data set, Samsung S10, "
        f"{len(est)} steps)\n"
        "# made by driftcorr datasets/ipin21/make_zero2four.py from Hossein-Shoushtari/IPIN21Data\n"
        "name: hcu-zero2four-pdr\nmode: indoor3d\n"
        "estimate: {path: estimate.tum, format: tum}\n"
        "ground_truth: {path: ground_truth.tum, format: tum}\n"
        "frame: enu\n"
        f"anchor: {{crs: EPSG:32632, easting_m: {e0}, northing_m: {n0}, yaw_deg: 0.0, z_m: {z0}}}\n"
        "map:\n" + layers)
    with open(os.path.join(out, "scenario.yaml.tmp"), "w", encoding="utf-8") as f:
        f.write(yaml)
    os.replace(os.path.join(out, "scenario.yaml.tmp"), os.path.join(out, "scenario.yaml"))
    print(f"hcu-zero2four-pdr: {len(est)} steps, initial heading {math.degrees(h0):.2f} deg, "
          f"height change {z:.2f} m (waypoints {wp[-1][3] - z0:.2f} m) -> {out}")


if __name__ == "__main__":
    main(sys.argv)
