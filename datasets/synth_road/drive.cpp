// The definitions of what drive.h declares.
#include "drive.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <queue>
#include <string>
#include <utility>

#include "driftcorr/core/angles.h"
#include "driftcorr/core/check.h"

namespace driftcorr::synth {
namespace {

// Speeds and accelerations of the car.
constexpr double kSecondarySpeed_mps = 14.0;
constexpr double kTertiarySpeed_mps = 12.5;
constexpr double kResidentialSpeed_mps = 8.5;  // 30 km/h zone
constexpr double kServiceSpeed_mps = 5.5;
constexpr double kMinCornerSpeed_mps = 5.0;    // floor of the curvature speed limit
constexpr double kMaxLateralAccel_mps2 = 2.5;  // v^2 * curvature stays below this (or v = 5)
constexpr double kMaxAccel_mps2 = 1.2;
constexpr double kMaxDecel_mps2 = 1.8;

// Geometry of the driven line.
constexpr double kTurnRadius_m = 12.0;  // centre-line fillet radius at junction turns
constexpr double kSharpTurn_rad = 20.0 * kPi / 180.0;  // turns above this use kTurnRadius_m
constexpr double kStopLineSetback_m = 5.0;  // the stop is this far before the turn starts
constexpr double kProfileStep_m = 0.5;      // grid of the speed profile
constexpr double kWaypointSnap_m = 1.0;     // a route waypoint must sit on a network node
constexpr int kMaxLaps = 200;

struct Waypoint {
    Eigen::Vector2d p_en;
    bool stop_before = false;  // the stop of the drive is just before this junction
};

/// One lap: the outbound meander from the south-west corner through the parallel street, the
/// tertiary and secondary through-roads and the curved road to the north-east corner, then back
/// along the north and west edges. The lap closes at its first waypoint. Every waypoint is a
/// junction of the network (East-North [m]); consecutive ones are joined by shortest paths.
std::vector<Waypoint> LapWaypoints(const NetworkLandmarks& marks) {
    const double parallel_y_m = marks.parallel_north_y_m;
    // clang-format off
    return {{{-620, -500}}, {{-505, -500}}, {{-505, -180}}, {{-290, -180}},  // south-west
            {{-290, 45}}, {{-190, 45}},                                       // across secondary
            {{-190, parallel_y_m}}, {{40, parallel_y_m}},                     // Parallelweg
            {{40, -60}, true},                      // tertiary south, stop before the secondary
            {{355, -60}}, {{355, -180}}, {{480, -180}},                       // secondary east
            {marks.curve_apex_en}, {{480, 150}},                              // curved road
            {{355, 150}}, {{355, 370}}, {{480, 370}}, {{480, 500}},           // to the north-east
            {{-620, 500}}};                                                   // back west
    // clang-format on
}

double ClassSpeed(const std::string& highway) {
    if (highway == "secondary") return kSecondarySpeed_mps;
    if (highway == "tertiary") return kTertiarySpeed_mps;
    if (highway == "service") return kServiceSpeed_mps;
    return kResidentialSpeed_mps;
}

struct Edge {
    int to = 0;
    double length_m = 0.0;
    double speed_mps = 0.0;
};
using Graph = std::vector<std::vector<Edge>>;

Graph VehicleGraph(const RoadNetwork& net) {
    Graph graph(net.nodes.size());
    for (const RoadWay& way : net.ways) {
        if (!IsVehicleRoad(way.highway)) continue;
        for (std::size_t i = 1; i < way.node_indices.size(); ++i) {
            const int a = way.node_indices[i - 1], b = way.node_indices[i];
            const double length_m = (net.nodes[b].p_en - net.nodes[a].p_en).norm();
            graph[a].push_back({b, length_m, ClassSpeed(way.highway)});
            graph[b].push_back({a, length_m, ClassSpeed(way.highway)});
        }
    }
    return graph;
}

int NearestVehicleNode(const RoadNetwork& net, const Graph& graph, const Eigen::Vector2d& p_en) {
    int best = -1;
    double best_m = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < net.nodes.size(); ++i) {
        const double d_m = (net.nodes[i].p_en - p_en).norm();
        if (!graph[i].empty() && d_m < best_m) best = static_cast<int>(i), best_m = d_m;
    }
    DRIFTCORR_CHECK(best >= 0 && best_m < kWaypointSnap_m,
                    "route waypoint is not a vehicle-road node");
    return best;
}

/// Dijkstra; returns the node sequence from `from` to `to` (both included). Ties resolve to the
/// lower node index, so the result is deterministic.
std::vector<int> ShortestPath(const Graph& graph, int from, int to) {
    std::vector<double> dist(graph.size(), std::numeric_limits<double>::infinity());
    std::vector<int> parent(graph.size(), -1);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    dist[from] = 0.0;
    queue.push({0.0, from});
    while (!queue.empty()) {
        const auto [d, u] = queue.top();
        queue.pop();
        if (d > dist[u]) continue;
        if (u == to) break;
        for (const Edge& e : graph[u]) {
            if (d + e.length_m < dist[e.to]) {
                dist[e.to] = d + e.length_m, parent[e.to] = u;
                queue.push({dist[e.to], e.to});
            }
        }
    }
    DRIFTCORR_CHECK(std::isfinite(dist[to]), "route leg has no path on vehicle roads");
    std::vector<int> path;
    for (int v = to; v != -1; v = parent[v]) path.push_back(v);
    std::reverse(path.begin(), path.end());
    return path;
}

/// A vertex of the route's centre line; `speed_mps` is the class speed of the segment leaving it.
struct RouteVertex {
    Eigen::Vector2d p_en;
    double speed_mps = 0.0;
    bool stop_before = false;
};

double EdgeSpeed(const Graph& graph, int a, int b) {
    for (const Edge& e : graph[a]) {
        if (e.to == b) return e.speed_mps;
    }
    DRIFTCORR_CHECK(false, "route edge missing");
    return 0.0;
}

/// The centre line of `laps` laps; only the first lap carries the stop.
std::vector<RouteVertex> RouteCentreLine(const RoadNetwork& net, int laps) {
    const Graph graph = VehicleGraph(net);
    const std::vector<Waypoint> lap = LapWaypoints(RoadNetworkLandmarks());
    std::vector<Waypoint> waypoints;
    for (int l = 0; l < laps; ++l) {
        for (Waypoint w : lap) waypoints.push_back({w.p_en, w.stop_before && l == 0});
    }
    waypoints.push_back(lap.front());
    std::vector<RouteVertex> route;
    int current = NearestVehicleNode(net, graph, waypoints.front().p_en);
    route.push_back({net.nodes[current].p_en, 0.0, false});
    for (std::size_t w = 1; w < waypoints.size(); ++w) {
        const int next = NearestVehicleNode(net, graph, waypoints[w].p_en);
        const std::vector<int> leg = ShortestPath(graph, current, next);
        for (std::size_t i = 1; i < leg.size(); ++i) {
            route.back().speed_mps = EdgeSpeed(graph, leg[i - 1], leg[i]);
            route.push_back({net.nodes[leg[i]].p_en, 0.0, false});
        }
        route.back().stop_before = waypoints[w].stop_before;
        current = next;
    }
    return route;
}

double Heading(const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
    return std::atan2(to.y() - from.y(), to.x() - from.x());
}

/// Drops vertices where the line goes straight on at the same speed (crossings, T-junctions), so
/// that fillets at real corners are not limited by nearby nodes.
std::vector<RouteVertex> MergeStraightRuns(const std::vector<RouteVertex>& in) {
    constexpr double kStraight_rad = 1e-9;
    std::vector<RouteVertex> out = {in.front()};
    for (std::size_t i = 1; i + 1 < in.size(); ++i) {
        const double turn =
            AngleDiff(Heading(in[i].p_en, in[i + 1].p_en), Heading(out.back().p_en, in[i].p_en));
        const bool keep = std::abs(turn) > kStraight_rad || in[i].stop_before ||
                          in[i].speed_mps != out.back().speed_mps;
        if (keep) out.push_back(in[i]);
    }
    out.push_back(in.back());
    return out;
}

/// A piece of the centre line: straight (curvature 0) or a circular arc, with its length along the
/// centre line and along the driven (offset) line.
struct Piece {
    Eigen::Vector2d start_en;
    double heading_rad = 0.0;      // at the start, unwrapped
    double curvature_pm = 0.0;     // signed, left positive [1/m]
    double length_m = 0.0;         // centre line
    double offset_length_m = 0.0;  // driven line
    double start_s_m = 0.0;        // arc length of the driven line at the start
    double speed_limit_mps = 0.0;
};

struct DrivenLine {
    std::vector<Piece> pieces;
    double length_m = 0.0;
    std::optional<double> stop_s_m;
};

/// Tangent length of the fillet at vertex i (0 at the ends and where the line goes straight).
double FilletTangent(const std::vector<RouteVertex>& v, std::size_t i) {
    if (i == 0 || i + 1 == v.size()) return 0.0;
    const double turn =
        std::abs(AngleDiff(Heading(v[i].p_en, v[i + 1].p_en), Heading(v[i - 1].p_en, v[i].p_en)));
    if (turn < 1e-9) return 0.0;
    const double prev_m = (v[i].p_en - v[i - 1].p_en).norm();
    const double next_m = (v[i + 1].p_en - v[i].p_en).norm();
    const double max_tangent_m =
        0.5 * std::min(i == 1 ? 2.0 * prev_m : prev_m, i + 2 == v.size() ? 2.0 * next_m : next_m);
    const double tan_half = std::tan(0.5 * turn);
    if (turn < kSharpTurn_rad) return max_tangent_m;
    return std::min(max_tangent_m, kTurnRadius_m * tan_half);
}

void AddPiece(DrivenLine& line, const Eigen::Vector2d& start_en, double heading_rad,
              double curvature_pm, double length_m, double class_speed_mps, double offset_m) {
    const double stretch = 1.0 + offset_m * curvature_pm;  // driven length / centre length
    DRIFTCORR_CHECK(stretch > 0.0, "fillet radius smaller than the lateral offset");
    const double driven_curvature_pm = std::abs(curvature_pm / stretch);
    double limit_mps = class_speed_mps;
    if (driven_curvature_pm > 0.0) {
        const double lateral_mps = std::sqrt(kMaxLateralAccel_mps2 / driven_curvature_pm);
        limit_mps = std::min(limit_mps, std::max(kMinCornerSpeed_mps, lateral_mps));
    }
    line.pieces.push_back({start_en, heading_rad, curvature_pm, length_m, length_m * stretch,
                           line.length_m, limit_mps});
    line.length_m += length_m * stretch;
}

/// Straight pieces along the route's segments, circular fillets at its corners.
DrivenLine BuildDrivenLine(const std::vector<RouteVertex>& v, double offset_m) {
    std::vector<double> tangent_m(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) tangent_m[i] = FilletTangent(v, i);
    DrivenLine line;
    double heading_rad = Heading(v[0].p_en, v[1].p_en);  // unwrapped along the route
    for (std::size_t i = 0; i + 1 < v.size(); ++i) {
        const Eigen::Vector2d dir = (v[i + 1].p_en - v[i].p_en).normalized();
        const double straight_m =
            (v[i + 1].p_en - v[i].p_en).norm() - tangent_m[i] - tangent_m[i + 1];
        DRIFTCORR_CHECK(straight_m > -1e-9, "fillets overlap");
        if (straight_m > 1e-9) {
            AddPiece(line, v[i].p_en + tangent_m[i] * dir, heading_rad, 0.0, straight_m,
                     v[i].speed_mps, offset_m);
        }
        if (v[i + 1].stop_before) line.stop_s_m = line.length_m - kStopLineSetback_m;
        if (i + 2 >= v.size()) break;
        const double turn_rad =
            AngleDiff(Heading(v[i + 1].p_en, v[i + 2].p_en), Heading(v[i].p_en, v[i + 1].p_en));
        if (tangent_m[i + 1] > 0.0) {
            const double radius_m = tangent_m[i + 1] / std::tan(0.5 * std::abs(turn_rad));
            AddPiece(line, v[i + 1].p_en - tangent_m[i + 1] * dir, heading_rad,
                     std::copysign(1.0 / radius_m, turn_rad), radius_m * std::abs(turn_rad),
                     std::min(v[i].speed_mps, v[i + 1].speed_mps), offset_m);
        }
        heading_rad += turn_rad;
    }
    return line;
}

/// Pose on the driven line at arc length s_m: position offset right of the centre line, heading.
DrivePose PoseAt(const DrivenLine& line, double s_m, double offset_m) {
    auto it = std::upper_bound(line.pieces.begin(), line.pieces.end(), s_m,
                               [](double s, const Piece& p) { return s < p.start_s_m; });
    const Piece& piece = it == line.pieces.begin() ? *it : *(it - 1);
    const double stretch = 1.0 + offset_m * piece.curvature_pm;
    const double sigma_m = std::clamp((s_m - piece.start_s_m) / stretch, 0.0, piece.length_m);
    const double h0 = piece.heading_rad;
    const double h = h0 + piece.curvature_pm * sigma_m;
    Eigen::Vector2d p_centre = piece.start_en;
    if (piece.curvature_pm == 0.0) {
        p_centre += sigma_m * Eigen::Vector2d(std::cos(h0), std::sin(h0));
    } else {
        p_centre += Eigen::Vector2d(std::sin(h) - std::sin(h0), std::cos(h0) - std::cos(h)) /
                    piece.curvature_pm;
    }
    DrivePose pose;
    pose.p_en = p_centre + offset_m * Eigen::Vector2d(std::sin(h), -std::cos(h));
    pose.yaw_rad = h;
    return pose;
}

/// One row of the time table: arc length, time since the start, speed.
struct ProfilePoint {
    double s_m = 0.0;
    double t_s = 0.0;
    double v_mps = 0.0;
};

/// Speed limit at each grid point s_j = j * step_m (road class and curvature of the pieces there).
std::vector<double> GridSpeedLimits(const DrivenLine& line, std::size_t n, double step_m) {
    std::vector<double> limit(n + 1, std::numeric_limits<double>::infinity());
    for (const Piece& p : line.pieces) {
        const double end_m = p.start_s_m + p.offset_length_m;
        const auto j0 = static_cast<std::size_t>(std::ceil(p.start_s_m / step_m));
        const auto j1 = std::min(n, static_cast<std::size_t>(std::floor(end_m / step_m)));
        const auto jm = std::min(
            n, static_cast<std::size_t>(std::lround(0.5 * (p.start_s_m + end_m) / step_m)));
        for (std::size_t j = j0; j <= j1; ++j) limit[j] = std::min(limit[j], p.speed_limit_mps);
        limit[jm] = std::min(limit[jm], p.speed_limit_mps);  // pieces shorter than a step
    }
    for (double l : limit) DRIFTCORR_CHECK(std::isfinite(l), "speed profile grid not covered");
    return limit;
}

/// Speed profile: limits, start from rest, the stop, then acceleration limits forward and backward
/// (v^2 changes by at most 2 a ds per step, so the acceleration is piecewise constant and bounded).
std::vector<ProfilePoint> TimeTable(const DrivenLine& line, const DriveConfig& config) {
    const auto n = static_cast<std::size_t>(std::ceil(line.length_m / kProfileStep_m));
    const double step_m = line.length_m / static_cast<double>(n);
    std::vector<double> v = GridSpeedLimits(line, n, step_m);
    v[0] = 0.0;
    std::optional<std::size_t> stop_j;
    if (line.stop_s_m) stop_j = static_cast<std::size_t>(std::lround(*line.stop_s_m / step_m));
    if (stop_j) v[*stop_j] = 0.0;
    for (std::size_t j = 1; j <= n; ++j) {
        v[j] = std::min(v[j], std::sqrt(v[j - 1] * v[j - 1] + 2.0 * kMaxAccel_mps2 * step_m));
    }
    for (std::size_t j = n; j-- > 0;) {
        v[j] = std::min(v[j], std::sqrt(v[j + 1] * v[j + 1] + 2.0 * kMaxDecel_mps2 * step_m));
    }
    std::vector<ProfilePoint> table = {{0.0, 0.0, 0.0}};
    for (std::size_t j = 1; j <= n; ++j) {
        const double t_s = table.back().t_s + 2.0 * step_m / (v[j - 1] + v[j]);
        table.push_back({step_m * static_cast<double>(j), t_s, v[j]});
        if (stop_j && j == *stop_j) {
            table.push_back({table.back().s_m, t_s + config.stop_duration_s, 0.0});
        }
    }
    return table;
}

/// Arc length at time t_s (constant acceleration between table rows).
double ArcLengthAt(const std::vector<ProfilePoint>& table, std::size_t& row, double t_s) {
    while (row + 2 < table.size() && table[row + 1].t_s <= t_s) ++row;
    const ProfilePoint& a = table[row];
    const ProfilePoint& b = table[row + 1];
    if (b.s_m == a.s_m) return a.s_m;  // standing still
    const double accel = (b.v_mps * b.v_mps - a.v_mps * a.v_mps) / (2.0 * (b.s_m - a.s_m));
    const double tau_s = t_s - a.t_s;
    return std::clamp(a.s_m + a.v_mps * tau_s + 0.5 * accel * tau_s * tau_s, a.s_m, b.s_m);
}

}  // namespace

std::string DriveConfig::Validate() const {
    if (!(duration_s > 0.0 && duration_s <= 100000.0)) return "duration_s: must be in (0, 100000]";
    if (!(rate_hz > 0.0 && rate_hz <= 1000.0)) return "rate_hz: must be in (0, 1000]";
    if (!std::isfinite(start_time_s)) return "start_time_s: must be finite";
    if (!(lateral_offset_m >= 0.0 && lateral_offset_m < 0.5 * kTurnRadius_m)) {
        return "lateral_offset_m: must be in [0, 6)";
    }
    if (!(stop_duration_s >= 0.0 && stop_duration_s <= 600.0)) {
        return "stop_duration_s: must be in [0, 600]";
    }
    return "";
}

std::vector<DrivePose> SimulateDrive(const RoadNetwork& net, const DriveConfig& config) {
    DRIFTCORR_CHECK(config.Validate().empty(), "invalid DriveConfig");
    const auto n_poses =
        static_cast<std::size_t>(std::floor(config.duration_s * config.rate_hz + 1e-9)) + 1;
    const double last_s = static_cast<double>(n_poses - 1) / config.rate_hz;
    for (int laps = 1; laps <= kMaxLaps; ++laps) {
        const DrivenLine line =
            BuildDrivenLine(MergeStraightRuns(RouteCentreLine(net, laps)), config.lateral_offset_m);
        const std::vector<ProfilePoint> table = TimeTable(line, config);
        if (table.back().t_s < last_s) {
            // Next, the laps that one lap's time says are needed (a long drive's hundred laps
            // without building every shorter route first).
            if (laps == 1 && table.back().t_s > 0.0) {
                laps = std::max(laps, static_cast<int>(std::floor(last_s / table.back().t_s)) - 1);
            }
            continue;
        }
        std::vector<DrivePose> poses;
        std::size_t row = 0;
        for (std::size_t k = 0; k < n_poses; ++k) {
            const double t_rel_s = static_cast<double>(k) / config.rate_hz;
            DrivePose pose =
                PoseAt(line, ArcLengthAt(table, row, t_rel_s), config.lateral_offset_m);
            pose.t_s = config.start_time_s + t_rel_s;
            poses.push_back(pose);
        }
        return poses;
    }
    DRIFTCORR_CHECK(false, "duration needs more laps than allowed");
    return {};
}

}  // namespace driftcorr::synth
