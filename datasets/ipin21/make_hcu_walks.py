#!/usr/bin/python3
"""Generates multi-floor pedestrian walks through the real HCU building, with a drifting PDR estimate.

The building is the one of ../shared/datasets/hcu_eight (IPIN 2021, HafenCity University Hamburg):
its walkway networks and floor plans of the ground, 1st and 4th floor. Each walk follows the walkway
network of a floor, changes floor 1-3 times by stairs or by lift where the plans have them, walks
80-200 m on the floors and at least 20 m after its last floor change. The map layers are copied next to each scenario
(they are not part of this repository).

    /usr/bin/python3 datasets/ipin21/make_hcu_walks.py <hcu scenario dir> <out dir> \
        [--seeds A-B] [--lift-share X] [--lift-poses-hz R] [--gait-sd S]

writes <out dir>/walk_<seed>/ (scenario.yaml, estimate.tum, ground_truth.tum, the map layers) for
every seed in A..B (default 1-10) and one summary line per walk. Same seed, same bytes (Python's
random.Random is a specified Mersenne Twister; only the math library's last bits could differ).

The walk (ground truth), in the scenario's local ENU frame (origin and heights of its anchor):
- on a floor, the shortest path along the walkway network between random nodes (vertices of the
  walkway lines merged within 0.3 m; a line end within 1.5 m of another line's vertex joins it);
  one pose a step, a walker's step 0.60-0.78 m at 1.6-2.0 steps/s, varied by its gait: a factor
  exp(g), g an AR(1) process from step to step with coefficient 0.92 and standard deviation
  --gait-sd S (default 0.09; the surveyed level steps of the real walks: log sd 0.05 on Eight,
  0.13 on Zero2four, autocorrelation 0.68 / 0.60 at five steps, 0.33 / 0.54 at ten), a leg
  taking as many steps as come nearest to its length, stretched together to end where it does.
  --gait-sd 0: the steps of a leg alike;
- stairs: a stair polygon of one floor joins it to the floor above or below (the map's rule) when
  both walkway networks come within 4 m of it and the floors are at most 7 m apart; the walker
  goes from the nearest walkway node into the polygon and climbs along its long axis, there and
  back where one run is shorter than the rise needs (0.29 m of run per 0.17 m of rise), one step
  per 0.17 m of rise, then leaves to the other floor's nearest node;
- lift: a lift polygon joins every pair of floors whose walkway networks come within 4 m of it;
  the walker waits 3-20 s at the door, rides at 1.0-1.6 m/s (plus 4 s of doors) and walks out.
  No step is taken in the cabin: the first step after the ride spans the whole wait and ride, as
  in the real walks; --lift-poses-hz R (default 0) adds a pose every 1/R s while the walker
  stands at the door and in the cabin, as a source that reports at a fixed rate would.
--lift-share X (default 0.5): the chance to take a lift where both stairs and a lift are at hand.

The estimate is pedestrian dead reckoning with the error kinds of the two real walks of the same
phone in this building (measured against their ground truth; Zero2four: datasets/ipin21/
make_zero2four.py, Eight: ../shared/datasets/hcu_eight):
- step length: the walker's steps, following half of its gait's log factor on level steps (the
  slope of the PDR's log step on the surveyed one is 0.86 on Eight and 0.17 on Zero2four:
  step_error_stats.py), divided by a scale drawn uniformly in [0.95, 1.45] (Eight's steps are 1.05x
  longer than the estimate's, Zero2four's 1.40x) and by a slowly varying factor exp(u), u an AR(1)
  process from step to step with coefficient 0.9 and a standard deviation that keeps the log
  ratio's at 0.10 with the gait's unfollowed half (0.089 at the default gait, 0.10 without it),
  with 4 % white noise: the log ratio of surveyed to PDR step length on the real walks' level steps
  has a standard deviation of 0.11 (Eight) and 0.13 (Zero2four) and an autocorrelation of 0.77 /
  0.70 at one step, 0.35 / 0.39 at five and 0.17 / 0.20 at twelve (the PDR's step length drifts
  with the gait: Eight's first 40 steps lengthen from 0.50 to 0.85 m while the surveyed ones stay
  0.67-0.73 m); on stairs the PDR step length is that of a level step (it does not know the step is
  a tread);
- heading: an initial error N(0, 6 deg) (Eight -4, Zero2four -11 deg), a heading-rate bias
  N(0, 0.04 deg/s) that random-walks with 0.005 deg/s per sqrt(s) (Eight drifts by about
  -0.08 deg/s), 1.0 deg white noise a step, and a jump N(0, 12 deg) during a lift ride (Zero2four's
  heading error changed by -15 deg in the lift);
- height (barometer): the true height through a first-order lag of 1-4 s, a gain error in
  [0.75, 1.1] on height changes (Zero2four's stairs read 0.78x, its lift 1.09x), a random walk of
  0.01 m per sqrt(s) and 0.08 m white noise a step (Eight's height error spreads about 0.15 m).
Python standard library only. Exit code 2 on a bad argument or input, nothing written then.
"""
import heapq
import json
import math
import os
import random
import re
import shutil
import sys

STAIR_TYPES = {"stairs", "staircase", "stairscase"}
LIFT_TYPES = {"lift", "elevator"}
SNAP_M = 0.3          # walkway vertices this close are one node
JOIN_M = 1.5          # a line end this close to another line's vertex joins it
REACH_M = 4.0         # a connector is usable from a floor whose network comes this close
MAX_STAIR_RISE_M = 7.0
# The PDR step length's error besides its scale (module docstring): a log factor that is AR(1)
# from step to step, and white noise.
STEP_LOG_AR = 0.9
STEP_LOG_SD = 0.10
STEP_WHITE = 0.04
# The walker's gait (module docstring): a log factor on its step, AR(1) from step to step, and the
# share of it the PDR's step length follows.
GAIT_AR = 0.92
GAIT_SD = 0.09
PDR_FOLLOWS_GAIT = 0.5
STAIR_TREAD_M, STAIR_RISE_M = 0.29, 0.17
SIM_DT_S = 0.05       # barometer simulation step


def fail(msg):
    print("make_hcu_walks: " + msg, file=sys.stderr)
    sys.exit(2)


# --- the building -------------------------------------------------------------------------------

def read_scenario(folder):
    path = os.path.join(folder, "scenario.yaml")
    try:
        text = open(path, encoding="utf-8").read()
    except OSError as e:
        fail(f"{path}: {e.strerror}")
    anchor = re.search(r"crs:\s*(EPSG:\d+).*?easting_m:\s*([-\d.]+).*?northing_m:\s*([-\d.]+)"
                       r".*?z_m:\s*([-\d.]+)", text, re.S)
    if not anchor:
        fail(f"{path}: no projected anchor (crs, easting_m, northing_m, z_m)")
    layers = re.findall(r"\{path:\s*([^,]+),\s*format:\s*geojson,\s*role:\s*(walkways|floorplan),"
                        r"\s*floor_z_m:\s*([-\d.]+)\}", text)
    floors = {}
    for name, role, z in layers:
        floors.setdefault(float(z), {})[role] = os.path.join(folder, name.strip())
    if len(floors) < 2 or any(len(v) != 2 for v in floors.values()):
        fail(f"{path}: needs a walkway network and a floor plan on each of at least two floors")
    return anchor.group(1), float(anchor.group(2)), float(anchor.group(3)), \
        float(anchor.group(4)), floors


def read_features(path, crs):
    try:
        doc = json.load(open(path, encoding="utf-8"))
    except (OSError, ValueError) as e:
        fail(f"{path}: {e}")
    declared = ((doc.get("crs") or {}).get("properties") or {}).get("name", "")
    if crs.split(":")[1] not in declared:
        fail(f"{path}: declares CRS '{declared}', the anchor is {crs}")
    return [f for f in doc.get("features", []) if f.get("geometry")]


class Floor:
    def __init__(self, z, route_path, plan_path, crs, e0, n0):
        self.z = z
        self.route_path, self.plan_path = route_path, plan_path
        self.nodes, self.adj = [], []
        index = {}

        def node(x, y):
            key = (round(x / SNAP_M), round(y / SNAP_M))
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    for k in index.get((key[0] + dx, key[1] + dy), []):
                        if math.dist(self.nodes[k], (x, y)) <= SNAP_M:
                            return k
            self.nodes.append((x, y))
            self.adj.append({})
            index.setdefault(key, []).append(len(self.nodes) - 1)
            return len(self.nodes) - 1

        ends = []
        for f in read_features(route_path, crs):
            g = f["geometry"]
            lines = [g["coordinates"]] if g["type"] == "LineString" else \
                g["coordinates"] if g["type"] == "MultiLineString" else []
            for line in lines:
                ids = [node(p[0] - e0, p[1] - n0) for p in line]
                for a, b in zip(ids, ids[1:]):
                    self.link(a, b)
                ends += [(ids[0], set(ids)), (ids[-1], set(ids))]
        for k, own in ends:  # T-junctions: a line that stops short of another line
            near = [j for j in range(len(self.nodes)) if j not in own and
                    math.dist(self.nodes[j], self.nodes[k]) <= JOIN_M]
            if near:
                self.link(k, min(near, key=lambda j: math.dist(self.nodes[j], self.nodes[k])))
        self.keep_largest_component()
        self.stairs, self.lifts = [], []
        for f in read_features(plan_path, crs):
            kind = str((f.get("properties") or {}).get("Type", "")).strip().lower()
            if f["geometry"]["type"] != "Polygon" or kind not in STAIR_TYPES | LIFT_TYPES:
                continue
            ring = [(p[0] - e0, p[1] - n0) for p in f["geometry"]["coordinates"][0]]
            (self.stairs if kind in STAIR_TYPES else self.lifts).append(ring)

    def link(self, a, b):
        if a != b:
            d = math.dist(self.nodes[a], self.nodes[b])
            self.adj[a][b] = self.adj[b][a] = d

    def keep_largest_component(self):
        seen, best = set(), []
        for s in range(len(self.nodes)):
            if s in seen:
                continue
            comp, todo = [], [s]
            seen.add(s)
            while todo:
                k = todo.pop()
                comp.append(k)
                for j in self.adj[k]:
                    if j not in seen:
                        seen.add(j)
                        todo.append(j)
            best = max(best, comp, key=len)
        self.alive = set(best)

    def nearest(self, p):
        k = min(self.alive, key=lambda j: math.dist(self.nodes[j], p))
        return k, math.dist(self.nodes[k], p)

    def path(self, a, b):
        """Dijkstra along the walkway network: the node sequence from a to b."""
        dist, prev, todo = {a: 0.0}, {}, [(0.0, a)]
        while todo:
            d, k = heapq.heappop(todo)
            if k == b:
                break
            if d > dist[k]:
                continue
            for j, w in self.adj[k].items():
                if d + w < dist.get(j, math.inf):
                    dist[j], prev[j] = d + w, k
                    heapq.heappush(todo, (d + w, j))
        out = [b]
        while out[-1] != a:
            out.append(prev[out[-1]])
        return [self.nodes[k] for k in reversed(out)]


def polygon_axis(ring):
    """The polygon's long axis as two points 0.3 m inside its ends (principal direction)."""
    pts = ring[:-1] if ring[0] == ring[-1] else ring
    cx = sum(p[0] for p in pts) / len(pts)
    cy = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - cx) ** 2 for p in pts)
    syy = sum((p[1] - cy) ** 2 for p in pts)
    sxy = sum((p[0] - cx) * (p[1] - cy) for p in pts)
    a = 0.5 * math.atan2(2 * sxy, sxx - syy)
    u = (math.cos(a), math.sin(a))
    t = [(p[0] - cx) * u[0] + (p[1] - cy) * u[1] for p in pts]
    lo, hi = min(t) + 0.3, max(t) - 0.3
    return (cx + lo * u[0], cy + lo * u[1]), (cx + hi * u[0], cy + hi * u[1]), (cx, cy)


def connectors(floors):
    """(kind, from floor, to floor, ring) for every stair and lift the map lets a walker use, both
    ways; a polygon drawn on both floors is listed twice (the walks draw from the list)."""
    out = []
    for i, f in enumerate(floors):
        for kind, rings in (("stairs", f.stairs), ("lift", f.lifts)):
            for ring in rings:
                c = polygon_axis(ring)[2]
                if f.nearest(c)[1] > REACH_M:
                    continue
                others = [j for j in (i - 1, i + 1) if 0 <= j < len(floors)] if kind == "stairs" \
                    else [j for j in range(len(floors)) if j != i]
                for j in others:
                    if floors[j].nearest(c)[1] > REACH_M:
                        continue
                    if kind == "stairs" and abs(floors[j].z - f.z) > MAX_STAIR_RISE_M:
                        continue
                    out += [(kind, i, j, ring), (kind, j, i, ring)]
    return out


# --- the walk -----------------------------------------------------------------------------------

class Walker:
    """Turns a plan (legs on floors, stairs, lifts) into timed samples of the true motion."""

    def __init__(self, rng, lift_poses_hz=0.0, gait_rng=None, gait_sd=0.0):
        self.rng = rng
        self.lift_poses_hz = lift_poses_hz
        self.step_m = rng.uniform(0.60, 0.78)
        # the gait's log factor on a level step (its own generator: gait_sd 0 draws nothing)
        self.gait_rng, self.gait_sd = gait_rng, gait_sd
        self.gait = gait_rng.gauss(0.0, gait_sd) if gait_sd > 0.0 else 0.0
        self.rate_hz = rng.uniform(1.6, 2.0)
        self.t = 0.0
        # (t, x, y, z, kind): kind "start", "step", or "wait" / "ride" / "cabin" in a lift (no
        # step taken; the heading jumps at the "ride" sample, the end of the ride)
        self.samples = []

    def at(self):
        return self.samples[-1][1:4]

    def walk(self, points, z, dz_total=0.0, tread=False):
        """Steps along the polyline `points`; the height goes from z to z + dz_total evenly."""
        length = sum(math.dist(a, b) for a, b in zip(points, points[1:]))
        if length < 1e-6:
            return
        step = length / max(1, round(abs(dz_total) / STAIR_RISE_M)) if tread else self.step_m
        n = max(1, round(length / step))
        ends = [length * k / n for k in range(1, n + 1)]
        if not tread and self.gait_sd > 0.0:
            ends = self.gait_steps(length)
        seg, acc = 0, 0.0
        for k, s in enumerate(ends, 1):
            while seg < len(points) - 2 and acc + math.dist(points[seg], points[seg + 1]) < s:
                acc += math.dist(points[seg], points[seg + 1])
                seg += 1
            a, b = points[seg], points[seg + 1]
            r = (s - acc) / max(math.dist(a, b), 1e-9)
            jitter = self.rng.gauss(0.0, 0.03)
            self.t += (1.0 + jitter) / (self.rate_hz * (0.85 if tread else 1.0))
            self.samples.append((self.t, a[0] + r * (b[0] - a[0]), a[1] + r * (b[1] - a[1]),
                                 z + dz_total * k / len(ends), "step"))

    def gait_steps(self, length):
        """Where the steps along `length` end: each step_m times the gait's factor, as many as
        come nearest to `length`, stretched together to end there."""
        steps = []
        while not steps or sum(steps) + 0.5 * steps[-1] < length:
            self.gait = (GAIT_AR * self.gait + math.sqrt(1.0 - GAIT_AR ** 2) * self.gait_sd
                         * self.gait_rng.gauss(0.0, 1.0))
            steps.append(self.step_m * math.exp(self.gait))
        stretch, ends, acc = length / sum(steps), [], 0.0
        for step in steps:
            acc += step * stretch
            ends.append(acc)
        ends[-1] = length
        return ends

    def ride(self, z_from, z_to, poses_hz=0.0):
        """Waits at the door, rides, steps out; with poses_hz > 0 also a pose every 1 / poses_hz
        while standing (a source that reports at a fixed rate)."""
        x, y = self.samples[-1][1:3]

        def standing(duration_s, z_of):
            if poses_hz > 0.0:
                for k in range(1, math.ceil(duration_s * poses_hz)):
                    self.samples.append((self.t + k / poses_hz, x, y, z_of(k / poses_hz / duration_s),
                                         "cabin"))
            self.t += duration_s

        standing(self.rng.uniform(3.0, 20.0), lambda _: z_from)
        self.samples.append((self.t, x, y, z_from, "wait"))
        speed = self.rng.uniform(1.0, 1.6)
        standing(2.0 + abs(z_to - z_from) / speed, lambda a: z_from + a * (z_to - z_from))
        self.samples.append((self.t, x, y, z_to, "ride"))
        standing(2.0, lambda _: z_to)
        self.samples.append((self.t, x, y, z_to, "wait"))


def stair_route(ring, start, dz):
    """Entry end nearest `start`, then along the axis (there and back) until the run fits dz."""
    a, b, _ = polygon_axis(ring)
    if math.dist(b, start) < math.dist(a, start):
        a, b = b, a
    run = abs(dz) / STAIR_RISE_M * STAIR_TREAD_M
    one = max(math.dist(a, b), 1.0)
    flights = max(1, math.ceil(run / one))
    pts = [a]
    for k in range(flights):
        pts.append(b if k % 2 == 0 else a)
    return pts


def walked_m(w):
    return sum(math.dist(a[1:3], b[1:3]) for a, b in zip(w.samples, w.samples[1:]))


def change_floor(w, floors, here, node, link):
    """Walks from `node` of floor `here` to the connector, through it, to the other floor's
    nearest walkway node; returns that node."""
    kind, _, to, ring = link
    f, g = floors[here], floors[to]
    c = polygon_axis(ring)[2]
    entry, _ = f.nearest(c)
    w.walk(f.path(node, entry), f.z)
    if kind == "lift":
        w.walk([w.at()[:2], c], f.z)
        w.ride(f.z, g.z, w.lift_poses_hz)
        exit_node, _ = g.nearest(c)
        w.walk([c, g.nodes[exit_node]], g.z)
    else:
        route = stair_route(ring, f.nodes[entry], g.z - f.z)
        w.walk([w.at()[:2], route[0]], f.z)
        w.walk(route, f.z, g.z - f.z, tread=True)
        exit_node, _ = g.nearest(route[-1])
        w.walk([route[-1], g.nodes[exit_node]], g.z)
    return exit_node


def plan_walk(rng, floors, links, lift_share, lift_poses_hz, gait_rng, gait_sd):
    """Legs along the walkway networks, 1-3 floor changes, 80-200 m on the floors, and at least
    20 m after the last floor change."""
    w = Walker(rng, lift_poses_hz, gait_rng, gait_sd)
    here = rng.choice(sorted({c[1] for c in links}))
    node = rng.choice(sorted(floors[here].alive))
    x, y = floors[here].nodes[node]
    w.samples.append((0.0, x, y, floors[here].z, "start"))
    target_m, changes_wanted = rng.uniform(80.0, 200.0), rng.randint(1, 3)
    used, since_change_m = [], 0.0
    for _ in range(40):
        f = floors[here]
        options = [c for c in links if c[1] == here]
        if len(used) >= changes_wanted and walked_m(w) >= target_m and since_change_m >= 20.0:
            break
        if options and len(used) < changes_wanted and since_change_m >= 20.0 and \
                rng.random() < 0.6:
            lifts = [c for c in options if c[0] == "lift"]
            stairs = [c for c in options if c[0] == "stairs"]
            pool = lifts if lifts and (not stairs or rng.random() < lift_share) else stairs
            link = rng.choice(pool)
            node = change_floor(w, floors, here, node, link)
            used.append(f"{link[0]} {f.z:.1f}->{floors[link[2]].z:.1f} m")
            here, since_change_m = link[2], 0.0
            continue
        far = [k for k in sorted(f.alive) if 15.0 < math.dist(f.nodes[k], f.nodes[node]) < 60.0]
        if not far:
            break
        before = walked_m(w)
        target = rng.choice(far)
        w.walk(f.path(node, target), f.z)
        node = target
        since_change_m += walked_m(w) - before
    return w, used


# --- the drifting estimate ----------------------------------------------------------------------

class Pdr:
    """Pedestrian dead reckoning errors (module docstring)."""

    def __init__(self, rng, level_step_m, gait_sd=0.0):
        self.rng = rng
        self.level_step_m = level_step_m
        # the share of the walker's gait the step length follows, and its own error's sd: the log
        # ratio of true to PDR step keeps STEP_LOG_SD whatever the gait
        self.follows = PDR_FOLLOWS_GAIT if gait_sd > 0.0 else 1.0
        self.own_sd = math.sqrt(STEP_LOG_SD ** 2 - ((1.0 - self.follows) * gait_sd) ** 2)
        self.scale = rng.uniform(0.95, 1.45)
        self.heading_err = math.radians(rng.gauss(0.0, 6.0))
        self.bias = math.radians(rng.gauss(0.0, 0.04))
        self.bias_rw = math.radians(0.005)
        self.tau_s = rng.uniform(1.0, 4.0)
        self.gain = rng.uniform(0.75, 1.1)
        self.baro_rw = 0.01
        # the step model's slowly varying error: log factor, AR(1) from step to step
        self.step_log = rng.gauss(0.0, self.own_sd)

    def run(self, samples):
        rng = self.rng
        t0, x0, y0, z0, _ = samples[0]
        est = [(t0, x0, y0, z0)]
        lag = z0
        drift = 0.0
        heading_err = self.heading_err
        x, y = x0, y0
        prev_yaw = None
        for (ta, xa, ya, za, _), (tb, xb, yb, zb, kind) in zip(samples, samples[1:]):
            # heading error and barometer between the two samples
            t = ta
            while t < tb - 1e-9:
                h = min(SIM_DT_S, tb - t)
                z_true = za + (zb - za) * ((t + h - ta) / (tb - ta))
                lag += (z_true - lag) * (1.0 - math.exp(-h / self.tau_s))
                drift += self.baro_rw * math.sqrt(h) * rng.gauss(0.0, 1.0)
                self.bias += self.bias_rw * math.sqrt(h) * rng.gauss(0.0, 1.0)
                heading_err += self.bias * h
                t += h
            if kind == "ride":
                heading_err += math.radians(rng.gauss(0.0, 12.0))
            dx, dy = xb - xa, yb - ya
            length = math.hypot(dx, dy)
            yaw = math.atan2(dy, dx) if length > 1e-6 else (prev_yaw or 0.0)
            prev_yaw = yaw
            if kind == "step":
                level_step = self.level_step_m
                if abs(zb - za) < 1e-6:  # a level step: the share of the gait the PDR follows
                    level_step = (length if self.follows == 1.0 else
                                  self.level_step_m * (length / self.level_step_m) ** self.follows)
                self.step_log = (STEP_LOG_AR * self.step_log + math.sqrt(1.0 - STEP_LOG_AR ** 2)
                                 * self.own_sd * rng.gauss(0.0, 1.0))
                measured = (level_step / (self.scale * math.exp(self.step_log))
                            * (1.0 + rng.gauss(0.0, STEP_WHITE)))
                heading = yaw + heading_err + math.radians(rng.gauss(0.0, 1.0))
                x += measured * math.cos(heading)
                y += measured * math.sin(heading)
            z_baro = z0 + self.gain * (lag - z0) + drift + rng.gauss(0.0, 0.08)
            est.append((tb, x, y, z_baro))
        return est, motion_yaws(est)


def motion_yaws(samples):
    """Each pose's heading: the direction of the next horizontal motion (the last one's, carried
    over stops and to the end)."""
    out, last = [], 0.0
    for a, b in zip(samples, samples[1:] + [None]):
        if b is not None and math.hypot(b[1] - a[1], b[2] - a[2]) > 1e-6:
            last = math.atan2(b[2] - a[2], b[1] - a[1])
        out.append(last)
    return out


# --- output -------------------------------------------------------------------------------------

def write_atomic(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def tum(poses, yaws, z_ref):
    t_base = 1000.0
    return "".join(f"{t_base + t:.3f} {x:.4f} {y:.4f} {z - z_ref:.4f} 0 0 "
                   f"{math.sin(yaw / 2):.9f} {math.cos(yaw / 2):.9f}\n"
                   for (t, x, y, z, *_), yaw in zip(poses, yaws))


def write_walk(out, seed, crs, e0, n0, floors, samples, est, est_yaws, used):
    os.makedirs(out, exist_ok=True)
    z_ref = samples[0][3]
    for f in floors:
        for p in (f.route_path, f.plan_path):
            shutil.copyfile(p, os.path.join(out, os.path.basename(p)))
    layers = "".join(f"  - {{path: {os.path.basename(p)}, format: geojson, role: {role}, "
                     f"floor_z_m: {f.z}}}\n" for f in floors
                     for p, role in ((f.route_path, "walkways"), (f.plan_path, "floorplan")))
    write_atomic(os.path.join(out, "estimate.tum"), tum(est, est_yaws, z_ref))
    write_atomic(os.path.join(out, "ground_truth.tum"), tum(samples, motion_yaws(samples), z_ref))
    write_atomic(os.path.join(out, "scenario.yaml"),
                 f"# generated by driftcorr datasets/ipin21/make_hcu_walks.py, seed {seed}: "
                 f"{', '.join(used)}\n"
                 f"name: hcu-walk-{seed}\nmode: indoor3d\n"
                 "estimate: {path: estimate.tum, format: tum}\n"
                 "ground_truth: {path: ground_truth.tum, format: tum}\n"
                 "frame: enu\n"
                 f"anchor: {{crs: {crs}, easting_m: {e0}, northing_m: {n0}, yaw_deg: 0.0, "
                 f"z_m: {z_ref}}}\n"
                 "map:\n" + layers)


def number_in(key, val, lo, hi):
    """The option's value as a number in [lo, hi], or exit 2 naming it."""
    try:
        x = float(val)
    except ValueError:
        fail(f"{key} {val}: not a number")
    if not lo <= x <= hi:
        fail(f"{key} {val}: outside [{lo:g}, {hi:g}]")
    return x


def parse_args(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    seeds, lift_share, lift_poses_hz, gait_sd = (1, 10), 0.5, 0.0, GAIT_SD
    rest = argv[3:]
    while rest:
        key = rest.pop(0)
        if not rest:
            fail(f"{key} needs a value")
        val = rest.pop(0)
        if key == "--seeds" and re.fullmatch(r"\d+-\d+", val):
            seeds = tuple(int(v) for v in val.split("-"))
            if seeds[1] < seeds[0]:
                fail(f"--seeds {val}: empty range")
        elif key == "--lift-share":
            lift_share = number_in(key, val, 0.0, 1.0)
        elif key == "--lift-poses-hz":
            lift_poses_hz = number_in(key, val, 0.0, 100.0)
        elif key == "--gait-sd":
            gait_sd = number_in(key, val, 0.0, 0.99 * STEP_LOG_SD / (1.0 - PDR_FOLLOWS_GAIT))
        else:
            fail(f"unknown option or bad value: {key} {val}")
    return argv[1], argv[2], seeds, lift_share, lift_poses_hz, gait_sd


def main(argv):
    src, out, seeds, lift_share, lift_poses_hz, gait_sd = parse_args(argv)
    crs, e0, n0, _, layers = read_scenario(src)
    floors = [Floor(z, v["walkways"], v["floorplan"], crs, e0, n0)
              for z, v in sorted(layers.items())]
    links = connectors(floors)
    if not links:
        fail(f"{src}: no stairs or lift joins two floors' walkway networks")
    for seed in range(seeds[0], seeds[1] + 1):
        rng = random.Random(seed)
        walker, used = plan_walk(rng, floors, links, lift_share, lift_poses_hz,
                                 random.Random(f"gait {seed}"), gait_sd)
        est, est_yaws = Pdr(rng, walker.step_m, gait_sd).run(walker.samples)
        folder = os.path.join(out, f"walk_{seed}")
        write_walk(folder, seed, crs, e0, n0, floors, walker.samples, est, est_yaws, used)
        s = walker.samples
        path = sum(math.dist(a[1:3], b[1:3]) for a, b in zip(s, s[1:]))
        end = math.dist(est[-1][1:3], s[-1][1:3])
        print(f"hcu-walk-{seed}: {len(s)} poses, {s[-1][0]:.0f} s, {path:.0f} m, "
              f"{', '.join(used)}; estimate ends {end:.1f} m off -> {folder}")


if __name__ == "__main__":
    main(sys.argv)
