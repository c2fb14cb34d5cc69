#include "driftcorr/mapping/road_network.h"

#include <algorithm>
#include <iomanip>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "driftcorr/mapping/grid.h"

namespace driftcorr {
namespace {

// Half-widths [m] of the traversable part of each highway class: a carriageway's half-width,
// generous enough for a vehicle in its lane (the centre line is mapped, the car drives beside it).
const std::map<std::string, double>& VehicleTable() {
    static const std::map<std::string, double> kTable = {
        {"motorway", 8.0},      {"motorway_link", 5.0}, {"trunk", 7.0},
        {"trunk_link", 5.0},    {"primary", 6.5},       {"primary_link", 5.0},
        {"secondary", 6.0},     {"secondary_link", 4.5}, {"tertiary", 5.5},
        {"tertiary_link", 4.5}, {"unclassified", 4.5},  {"residential", 4.5},
        {"living_street", 4.0}, {"service", 3.5},       {"road", 4.5},
        {"track", 3.0},         {"busway", 4.0}};
    return kTable;
}

const std::map<std::string, double>& PedestrianTable() {
    static const std::map<std::string, double> kTable = {
        {"footway", 1.5},       {"path", 1.5},    {"cycleway", 1.5},     {"steps", 1.5},
        {"pedestrian", 4.0},    {"corridor", 1.5}, {"bridleway", 1.5},  {"living_street", 4.0},
        {"residential", 4.5},   {"service", 3.5}, {"track", 3.0},       {"unclassified", 4.5}};
    return kTable;
}

struct Raster {
    GridSpec spec;
    std::vector<float> centre_exact, corridor_exact;  // +inf outside every band
    std::vector<std::uint8_t> centre_seed, inside;
};

// Exact distances for the samples near one segment (within its half-width plus the band).
void RasteriseSegment(Raster& r, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double hw,
                      double band) {
    const GridSpec& s = r.spec;
    const double reach = hw + band, res = s.resolution_m;
    const auto [i0, j0, i1, j1] = SegmentCells(s, a, b, reach);
    for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
            const Eigen::Vector2d p = s.Position(i, j).head<2>();
            const double d = PointSegmentDistance(p, a, b);
            if (d > reach) continue;
            const std::size_t idx = s.Index(i, j);
            r.centre_exact[idx] = std::min(r.centre_exact[idx], float(d));
            r.corridor_exact[idx] = std::min(r.corridor_exact[idx], float(d - hw));
            if (d <= 0.5 * res) r.centre_seed[idx] = 1;
            if (d <= hw) r.inside[idx] = 1;
        }
    }
}

GridSpec MakeSpec(const Eigen::AlignedBox2d& box, const RoadFieldConfig& c) {
    GridSpec s;
    s.resolution_m = c.resolution_m;
    s.origin_m = Eigen::Vector3d(box.min().x(), box.min().y(), 0.0);
    s.nx = int(std::ceil(box.sizes().x() / c.resolution_m)) + 1;
    s.ny = int(std::ceil(box.sizes().y() / c.resolution_m)) + 1;
    s.nz = 1;
    const double mb = double(s.size()) * 14.0 / (1024.0 * 1024.0);  // bytes per sample, peak
    if (mb > c.max_memory_mb) {
        const double fit = c.resolution_m * std::sqrt(mb / c.max_memory_mb) * 1.01;
        std::ostringstream msg;
        msg << "distance field of " << s.nx << " x " << s.ny << " samples at "
            << c.resolution_m << " m needs about " << std::setprecision(2) << mb << std::setprecision(6) << " MB, more than max_memory_mb = "
            << c.max_memory_mb << "; a resolution of " << std::ceil(fit * 100.0) / 100.0
            << " m or coarser would fit (or shrink margin_m)";
        throw std::invalid_argument(msg.str());
    }
    return s;
}

}  // namespace

std::string RoadClassConfig::Validate() const {
    if (profile != "vehicle" && profile != "pedestrian" && profile != "all") {
        return "road_profile: must be vehicle, pedestrian or all (got '" + profile + "')";
    }
    for (const auto& [cls, hw] : half_width_overrides_m) {
        if (!(hw >= 0.0) || !std::isfinite(hw)) return "road_half_width_m." + cls + ": must be >= 0";
    }
    if (!(default_half_width_m > 0.0)) return "default_half_width_m: must be > 0";
    return "";
}

std::map<std::string, double> RoadClassConfig::Table() const {
    std::map<std::string, double> table;
    if (profile == "vehicle" || profile == "all") table = VehicleTable();
    if (profile == "pedestrian" || profile == "all") {
        for (const auto& [k, v] : PedestrianTable()) table.emplace(k, v);
    }
    for (const auto& [k, v] : half_width_overrides_m) table[k] = v;
    for (auto it = table.begin(); it != table.end();) it = it->second > 0 ? std::next(it) : table.erase(it);
    return table;
}

Eigen::AlignedBox2d RoadNetwork::Bounds() const {
    Eigen::AlignedBox2d box;
    for (const auto& r : roads) for (const auto& p : r.points_en) box.extend(p);
    return box;
}

double RoadNetwork::TotalLengthM() const {
    double len = 0.0;
    for (const auto& r : roads) {
        for (std::size_t i = 1; i < r.points_en.size(); ++i) len += (r.points_en[i] - r.points_en[i - 1]).norm();
    }
    return len;
}

RoadNetwork BuildRoadNetwork(const OsmRoads& osm,
                             const std::function<Eigen::Vector2d(const GeoPoint&)>& to_en,
                             const RoadClassConfig& config) {
    const auto table = config.Table();
    RoadNetwork net;
    for (const OsmWay& way : osm.ways) {
        if (way.is_area) { ++net.ways_area; continue; }
        auto it = table.find(way.highway);
        double hw = it != table.end() ? it->second : 0.0;
        if (it == table.end() && config.profile == "all") hw = config.default_half_width_m;
        if (hw <= 0.0) { ++net.ways_excluded_by_class; continue; }
        RoadPolyline road{way.id, way.highway, hw, {}};
        road.points_en.reserve(way.nodes.size());
        for (const GeoPoint& g : way.nodes) road.points_en.push_back(to_en(g));
        net.roads.push_back(std::move(road));
    }
    return net;
}

std::string RoadFieldConfig::Validate() const {
    if (!(resolution_m > 0.0)) return "field.resolution_m: must be > 0";
    if (!(margin_m >= 0.0)) return "field.margin_m: must be >= 0";
    if (!(truncation_m > 0.0)) return "field.truncation_m: must be > 0";
    if (!(exact_band_m >= 0.0)) return "field.exact_band_m: must be >= 0";
    if (!(max_memory_mb > 0.0)) return "field.max_memory_mb: must be > 0";
    return "";
}

TraversableField RasteriseRoads(const RoadNetwork& network, const Eigen::AlignedBox2d& region_en,
                                const RoadFieldConfig& config) {
    if (network.roads.empty()) throw std::invalid_argument("the road network is empty");
    Eigen::AlignedBox2d box = region_en;
    box.min().array() -= config.margin_m;
    box.max().array() += config.margin_m;
    Eigen::AlignedBox2d net = network.Bounds();
    net.min().array() -= config.truncation_m;
    net.max().array() += config.truncation_m;
    box = box.intersection(net);
    if (box.isEmpty()) box = region_en;  // no road near the drive: a field of "far" everywhere
    const float inf = std::numeric_limits<float>::infinity();
    Raster r;
    r.spec = MakeSpec(box, config);
    const std::size_t n = r.spec.size();
    r.centre_exact.assign(n, inf);
    r.corridor_exact.assign(n, inf);
    r.centre_seed.assign(n, 0);
    r.inside.assign(n, 0);
    for (const auto& road : network.roads) {
        for (std::size_t k = 1; k < road.points_en.size(); ++k) {
            RasteriseSegment(r, road.points_en[k - 1], road.points_en[k], road.half_width_m,
                             config.exact_band_m);
        }
    }
    std::vector<float> centre = EuclideanDistanceTransform(r.spec, r.centre_seed);
    std::vector<float> corridor = EuclideanDistanceTransform(r.spec, r.inside);
    const float trunc = float(config.truncation_m), half = float(0.5 * config.resolution_m);
    for (std::size_t i = 0; i < n; ++i) {
        const bool exact = r.centre_exact[i] < inf;
        centre[i] = std::min(trunc, exact ? r.centre_exact[i] : centre[i]);
        // Beyond the band: the distance to the nearest inside sample overestimates the distance
        // to the corridor edge (which lies between that sample and the next one) by up to one
        // cell; minus half a cell centres the error (same convention as SignedDistanceTransform).
        corridor[i] = std::min(trunc, exact ? r.corridor_exact[i] : corridor[i] - half);
    }
    return TraversableField(InterpolatedField(r.spec, std::move(centre)),
                            InterpolatedField(r.spec, std::move(corridor)), config.truncation_m);
}

}  // namespace driftcorr
