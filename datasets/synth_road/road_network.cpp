// The definitions of what road_network.h declares.
#include "road_network.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>

#include "driftcorr/core/angles.h"

namespace driftcorr::synth {
namespace {

// Street grid lines (irregular spacing, 95-130 m, so the grid is not periodic).
constexpr std::array<double, 11> kGridEastings_m = {-620.0, -505.0, -410.0, -290.0, -190.0, -75.0,
                                                    40.0,   135.0,  250.0,  355.0,  480.0};
constexpr std::array<double, 10> kGridNorthings_m = {-500.0, -390.0, -295.0, -180.0, -60.0,
                                                     45.0,   150.0,  265.0,  370.0,  500.0};
constexpr std::array<const char*, 11> kNorthSouthNames = {
    "Ahornweg",     "Birkenweg", "Kastanienweg", "Lindenstrasse", "Eichenweg", "Ulmenweg",
    "Hauptstrasse", "Erlenweg",  "Eschenweg",    "Pappelweg",     "Weidenweg"};
constexpr std::array<const char*, 10> kEastWestNames = {
    "Am Suedrand", "Amselstrasse", "Drosselweg", "Finkenweg",    "Durlacher Allee",
    "Meisenweg",   "Lerchenweg",   "Starenweg",  "Schwalbenweg", "Am Nordrand"};
constexpr double kTertiaryEasting_m = 40.0;     // the north-south through-road
constexpr double kSecondaryNorthing_m = -60.0;  // the east-west through-road

// The close parallel pair: Starenweg (y = 265) and Parallelweg 25 m north of it.
constexpr double kParallelSouthNorthing_m = 265.0;
constexpr double kParallelNorthNorthing_m = 290.0;
constexpr double kParallelWest_m = -410.0;
constexpr double kParallelEast_m = 135.0;

// The curved road: a half ellipse east of the grid from (480, -180) to (480, 150).
constexpr double kCurveBaseEasting_m = 480.0;
constexpr double kCurveSouthNorthing_m = -180.0;
constexpr double kCurveNorthNorthing_m = 150.0;
constexpr double kCurveBulge_m = 110.0;  // semi-axis towards East
constexpr int kCurveSegments = 88;       // ~5 m between nodes; even, so the apex is a node

constexpr std::int64_t kFirstNodeId = 1000001;
constexpr std::int64_t kFirstWayId = 2001;
constexpr double kPositionKeyScale = 1000.0;  // node de-duplication at 1 mm

/// An axis-parallel way: a north-south one at easting `fixed_m` from northing lo_m to hi_m, or an
/// east-west one at northing `fixed_m` from easting lo_m to hi_m.
struct StraightWaySpec {
    bool north_south = false;
    double fixed_m = 0.0;
    double lo_m = 0.0;
    double hi_m = 0.0;
    std::string highway;
    std::string name;
};

class NetworkBuilder {
public:
    int NodeAt(const Eigen::Vector2d& p_en) {
        const std::pair<long long, long long> key{std::llround(p_en.x() * kPositionKeyScale),
                                                  std::llround(p_en.y() * kPositionKeyScale)};
        const auto it = index_by_key_.find(key);
        if (it != index_by_key_.end()) return it->second;
        const int index = static_cast<int>(net_.nodes.size());
        net_.nodes.push_back({kFirstNodeId + index, p_en});
        index_by_key_.emplace(key, index);
        return index;
    }
    void AddWay(const std::string& highway, const std::string& name, std::vector<int> nodes) {
        const auto id = kFirstWayId + static_cast<std::int64_t>(net_.ways.size());
        net_.ways.push_back({id, highway, name, std::move(nodes)});
    }
    void AddTaggedNode(const Eigen::Vector2d& p_en, const std::string& highway) {
        net_.tagged_nodes.push_back({NodeAt(p_en), highway});
    }
    RoadNetwork Take() { return std::move(net_); }

private:
    RoadNetwork net_;
    std::map<std::pair<long long, long long>, int> index_by_key_;
};

std::vector<StraightWaySpec> StraightWaySpecs() {
    const double west = kGridEastings_m.front(), east = kGridEastings_m.back();
    const double south = kGridNorthings_m.front(), north = kGridNorthings_m.back();
    std::vector<StraightWaySpec> specs;
    for (std::size_t i = 0; i < kGridEastings_m.size(); ++i) {
        const bool through = kGridEastings_m[i] == kTertiaryEasting_m;
        specs.push_back({true, kGridEastings_m[i], south, north,
                         through ? "tertiary" : "residential", kNorthSouthNames[i]});
    }
    for (std::size_t i = 0; i < kGridNorthings_m.size(); ++i) {
        const bool through = kGridNorthings_m[i] == kSecondaryNorthing_m;
        specs.push_back({false, kGridNorthings_m[i], west, east,
                         through ? "secondary" : "residential", kEastWestNames[i]});
    }
    specs.push_back({false, kParallelNorthNorthing_m, kParallelWest_m, kParallelEast_m,
                     "residential", "Parallelweg"});
    // Dead end into the block south of Finkenweg (y = -180).
    specs.push_back({true, -240.0, -240.0, -180.0, "service", "Hofzufahrt"});
    // Footway and cycleway ways beside roads (6.5-7 m from the road's centre line).
    specs.push_back(
        {true, kTertiaryEasting_m + 6.5, -390.0, 370.0, "footway", "Fussweg Hauptstrasse"});
    specs.push_back(
        {false, kSecondaryNorthing_m - 7.0, -505.0, 355.0, "cycleway", "Radweg Durlacher Allee"});
    specs.push_back({false, -295.0 - 7.0, -190.0, 250.0, "footway", "Fussweg Drosselweg"});
    return specs;
}

Eigen::Vector2d SpecPoint(const StraightWaySpec& spec, double along_m) {
    return spec.north_south ? Eigen::Vector2d(spec.fixed_m, along_m)
                            : Eigen::Vector2d(along_m, spec.fixed_m);
}

/// Stations (positions along the way) where `spec` starts, ends or meets a crossing way.
std::vector<double> Stations(const StraightWaySpec& spec, const std::vector<StraightWaySpec>& all) {
    std::vector<double> stations = {spec.lo_m, spec.hi_m};
    for (const StraightWaySpec& other : all) {
        if (other.north_south == spec.north_south) continue;
        const bool meets = other.fixed_m >= spec.lo_m && other.fixed_m <= spec.hi_m &&
                           spec.fixed_m >= other.lo_m && spec.fixed_m <= other.hi_m;
        if (meets) stations.push_back(other.fixed_m);
    }
    std::sort(stations.begin(), stations.end());
    stations.erase(std::unique(stations.begin(), stations.end()), stations.end());
    return stations;
}

Eigen::Vector2d CurvePoint(double t_rad) {
    const double centre_y = 0.5 * (kCurveSouthNorthing_m + kCurveNorthNorthing_m);
    const double half_span = 0.5 * (kCurveNorthNorthing_m - kCurveSouthNorthing_m);
    return {kCurveBaseEasting_m + kCurveBulge_m * std::sin(t_rad),
            centre_y - half_span * std::cos(t_rad)};
}

void AddCurvedRoad(NetworkBuilder& builder) {
    std::vector<int> nodes;
    for (int i = 0; i <= kCurveSegments; ++i) {
        nodes.push_back(builder.NodeAt(CurvePoint(kPi * i / kCurveSegments)));
    }
    builder.AddWay("residential", "Bogenstrasse", std::move(nodes));
}

}  // namespace

bool IsVehicleRoad(const std::string& highway) {
    return highway == "residential" || highway == "tertiary" || highway == "secondary" ||
           highway == "service";
}

RoadNetwork BuildRoadNetwork() {
    NetworkBuilder builder;
    const std::vector<StraightWaySpec> specs = StraightWaySpecs();
    for (const StraightWaySpec& spec : specs) {
        std::vector<int> nodes;
        for (double station : Stations(spec, specs)) {
            nodes.push_back(builder.NodeAt(SpecPoint(spec, station)));
        }
        builder.AddWay(spec.highway, spec.name, std::move(nodes));
    }
    AddCurvedRoad(builder);
    // A lamp 8 m north of the Durlacher Allee: a highway-tagged node that is not a way.
    builder.AddTaggedNode({100.0, kSecondaryNorthing_m + 8.0}, "street_lamp");
    return builder.Take();
}

NetworkLandmarks RoadNetworkLandmarks() {
    NetworkLandmarks marks;
    marks.curve_apex_en = CurvePoint(0.5 * kPi);
    marks.parallel_north_y_m = kParallelNorthNorthing_m;
    marks.parallel_south_y_m = kParallelSouthNorthing_m;
    return marks;
}

}  // namespace driftcorr::synth
