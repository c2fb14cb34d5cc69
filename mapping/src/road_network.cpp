// The definitions of what driftcorr/mapping/road_network.h declares.
#include "driftcorr/mapping/road_network.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <iomanip>
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
        {"motorway", 8.0},      {"motorway_link", 5.0},  {"trunk", 7.0},
        {"trunk_link", 5.0},    {"primary", 6.5},        {"primary_link", 5.0},
        {"secondary", 6.0},     {"secondary_link", 4.5}, {"tertiary", 5.5},
        {"tertiary_link", 4.5}, {"unclassified", 4.5},   {"residential", 4.5},
        {"living_street", 4.0}, {"service", 3.5},        {"road", 4.5},
        {"track", 3.0},         {"busway", 4.0}};
    return kTable;
}

const std::map<std::string, double>& PedestrianTable() {
    static const std::map<std::string, double> kTable = {
        {"footway", 1.5},     {"path", 1.5},     {"cycleway", 1.5},  {"steps", 1.5},
        {"pedestrian", 4.0},  {"corridor", 1.5}, {"bridleway", 1.5}, {"living_street", 4.0},
        {"residential", 4.5}, {"service", 3.5},  {"track", 3.0},     {"unclassified", 4.5}};
    return kTable;
}

struct Raster {
    GridSpec spec;
    // Sample (i, j) of spec sits at sample (i + di, j + dj) of `whole` (a tile's samples are
    // placed as the whole grid's, to the last bit).
    GridSpec whole;
    int di = 0, dj = 0;
    std::vector<float> centre_exact, corridor_exact;  // +inf outside every band
    std::vector<std::uint8_t> centre_seed, inside;
};

// Exact distances for the samples of rows [j0, j1) near one segment (within its half-width plus
// the band). Each sample keeps the least distance over the segments and the flags of any, so
// the rows can be split between threads and the segments taken in any order.
void RasteriseSegment(Raster& r, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double hw,
                      double band, int j0, int j1) {
    const GridSpec& s = r.spec;
    const double reach = hw + band, res = s.resolution_m;
    const CellBox box = SegmentCells(s, a, b, reach);
    for (int j = std::max(box.j0, j0); j <= std::min(box.j1, j1 - 1); ++j) {
        int i0 = 0, i1 = -1;
        if (!SegmentRowCells(r.whole, r.di, r.dj, j, a, b, reach, box, i0, i1)) continue;
        for (int i = i0; i <= i1; ++i) {
            const Eigen::Vector2d p = r.whole.Position(i + r.di, j + r.dj).head<2>();
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

// Bytes a sample of a road field takes at the build's peak: the two distances (the exact band's,
// the transforms laid under them in place) and the two masks (4 + 4 + 1 + 1).
constexpr double kPeakBytesPerSample = 10.0;

// The grid over `box` (samples on box.min() + k * resolution), not yet checked against the cap.
GridSpec GridOver(const Eigen::AlignedBox2d& box, const RoadFieldConfig& c) {
    GridSpec s;
    s.resolution_m = c.resolution_m;
    s.origin_m = Eigen::Vector3d(box.min().x(), box.min().y(), 0.0);
    s.nx = int(std::ceil(box.sizes().x() / c.resolution_m)) + 1;
    s.ny = int(std::ceil(box.sizes().y() / c.resolution_m)) + 1;
    s.nz = 1;
    return s;
}

// Throws when `mb` exceeds the cap, saying which resolution would fit.
void CheckMemory(double mb, const std::string& what, const RoadFieldConfig& c) {
    if (mb <= c.max_memory_mb) return;
    const double fit = c.resolution_m * std::sqrt(mb / c.max_memory_mb) * 1.01;
    std::ostringstream msg;
    msg << what << " at " << c.resolution_m << " m needs about " << std::setprecision(2) << mb
        << std::setprecision(6) << " MB, more than max_memory_mb = " << c.max_memory_mb
        << "; a resolution of " << std::ceil(fit * 100.0) / 100.0
        << " m or coarser would fit (or shrink margin_m)";
    throw std::invalid_argument(msg.str());
}

GridSpec MakeSpec(const Eigen::AlignedBox2d& box, const RoadFieldConfig& c) {
    const GridSpec s = GridOver(box, c);
    const double mb = double(s.size()) * kPeakBytesPerSample / (1024.0 * 1024.0);
    std::ostringstream what;
    what << "distance field of " << s.nx << " x " << s.ny << " samples";
    CheckMemory(mb, what.str(), c);
    return s;
}

// The region's box: region_en grown by margin_m, clipped to the network's bounds grown by the
// truncation (the region itself when no road is near it: a field of "far" everywhere).
Eigen::AlignedBox2d FieldBox(const RoadNetwork& network, const Eigen::AlignedBox2d& region_en,
                             const RoadFieldConfig& config) {
    Eigen::AlignedBox2d box = region_en;
    box.min().array() -= config.margin_m;
    box.max().array() += config.margin_m;
    Eigen::AlignedBox2d net = network.Bounds();
    net.min().array() -= config.truncation_m;
    net.max().array() += config.truncation_m;
    box = box.intersection(net);
    return box.isEmpty() ? region_en : box;
}

// Rasterises the network on `spec`: exact distances within the band, the EDT beyond, truncated.
// `spec` is the sub-grid of `whole` from sample (di, dj) on.
std::pair<std::vector<float>, std::vector<float>> DistanceSamples(const RoadNetwork& network,
                                                                  const GridSpec& spec,
                                                                  const GridSpec& whole, int di,
                                                                  int dj,
                                                                  const RoadFieldConfig& config) {
    const float inf = std::numeric_limits<float>::infinity();
    Raster r;
    r.spec = spec;
    r.whole = whole;
    r.di = di;
    r.dj = dj;
    const std::size_t n = r.spec.size();
    const std::launch second = SecondThreadLaunch(config.threads);
    // Two threads: each allocates two of the four grids, then rasterises half the rows.
    auto centre_grids = std::async(second, [&r, n, inf] {
        AssignLarge(r.centre_exact, n, inf);
        AssignLarge(r.centre_seed, n, std::uint8_t(0));
    });
    AssignLarge(r.corridor_exact, n, inf);
    AssignLarge(r.inside, n, std::uint8_t(0));
    centre_grids.get();
    auto rasterise = [&](int j0, int j1) {
        for (const auto& road : network.roads) {
            for (std::size_t k = 1; k < road.points_en.size(); ++k) {
                RasteriseSegment(r, road.points_en[k - 1], road.points_en[k], road.half_width_m,
                                 config.exact_band_m, j0, j1);
            }
        }
    };
    const int mid = r.spec.ny / 2;
    auto upper_rows = std::async(second, [&] { rasterise(mid, r.spec.ny); });
    rasterise(0, mid);
    upper_rows.get();
    // Both fields are capped at the truncation; the corridor's takes half a cell off the
    // distance to an inside sample, so beyond truncation + a cell nothing is needed. Each
    // transform is laid under its exact band in place, in its own thread.
    const double cap = config.truncation_m + config.resolution_m;
    const float trunc = float(config.truncation_m), half = float(0.5 * config.resolution_m);
    // Beyond the band: the distance to the nearest inside sample overestimates the distance to
    // the corridor edge (which lies between that sample and the next one) by up to one cell;
    // minus half a cell centres the error (same convention as SignedDistanceTransform).
    auto corridor_done = std::async(second, [&r, cap, trunc, half] {
        MergeCappedDistanceTransform(r.spec, r.inside, cap, -half, trunc, r.corridor_exact);
    });
    MergeCappedDistanceTransform(r.spec, r.centre_seed, cap, 0.0f, trunc, r.centre_exact);
    corridor_done.get();
    return {std::move(r.centre_exact), std::move(r.corridor_exact)};
}

// The samples [i0, i1) x [j0, j1) of `from` (a sub-grid of the same resolution).
std::vector<float> Crop(const std::vector<float>& from, const GridSpec& from_spec, int di, int dj,
                        const GridSpec& to_spec) {
    std::vector<float> out(to_spec.size());
    for (int j = 0; j < to_spec.ny; ++j) {
        const float* row = from.data() + from_spec.Index(di, dj + j);
        std::copy(row, row + to_spec.nx, out.begin() + std::ptrdiff_t(to_spec.Index(0, j)));
    }
    return out;
}

// Samples [a, b) of `grid` along one axis grown by `grow` and clipped to [0, n).
std::pair<int, int> Span(int a, int b, int grow, int n) {
    return {std::max(0, a - grow), std::min(n, b + grow)};
}

GridSpec SubGrid(const GridSpec& grid, int i0, int i1, int j0, int j1) {
    GridSpec s = grid;
    s.origin_m = grid.Position(i0, j0);
    s.nx = i1 - i0;
    s.ny = j1 - j0;
    return s;
}

// One tile of `grid`: its samples and two more on every side, computed on a grid grown by the
// truncation and a cell (every sample that can be nearer than the truncation to a sample of the
// tile is in it), so the tile's samples equal those of the whole grid.
TraversableField::Tile MakeTile(const RoadNetwork& network, const GridSpec& grid, int tile_cells,
                                int ti, int tj, const RoadFieldConfig& config) {
    const int keep = 2;
    const int work =
        keep + int(std::ceil((config.truncation_m + config.resolution_m) / config.resolution_m)) +
        1;
    const auto [ki0, ki1] = Span(ti * tile_cells, (ti + 1) * tile_cells, keep, grid.nx);
    const auto [kj0, kj1] = Span(tj * tile_cells, (tj + 1) * tile_cells, keep, grid.ny);
    const auto [wi0, wi1] = Span(ti * tile_cells, (ti + 1) * tile_cells, work, grid.nx);
    const auto [wj0, wj1] = Span(tj * tile_cells, (tj + 1) * tile_cells, work, grid.ny);
    const GridSpec work_spec = SubGrid(grid, wi0, wi1, wj0, wj1);
    const GridSpec keep_spec = SubGrid(grid, ki0, ki1, kj0, kj1);
    auto [centre, corridor] = DistanceSamples(network, work_spec, grid, wi0, wj0, config);
    TraversableField::Tile tile;
    tile.ti = ti;
    tile.tj = tj;
    tile.centre =
        InterpolatedField(keep_spec, Crop(centre, work_spec, ki0 - wi0, kj0 - wj0, keep_spec));
    tile.corridor =
        InterpolatedField(keep_spec, Crop(corridor, work_spec, ki0 - wi0, kj0 - wj0, keep_spec));
    return tile;
}

// The tiles `chosen` of `grid` (tile_cells a side), built one after the other; the cap counts
// the samples they hold and one tile's work.
TraversableField BuildTiles(const RoadNetwork& network, const GridSpec& grid,
                            const std::vector<std::pair<int, int>>& chosen, int tile_cells,
                            const RoadFieldConfig& config) {
    const double tile_side = tile_cells + 4.0;
    const double work_side =
        tile_cells + 2.0 * (std::ceil(config.truncation_m / config.resolution_m) + 4.0);
    const double mb = (double(chosen.size()) * tile_side * tile_side * 8.0 +
                       work_side * work_side * kPeakBytesPerSample) /
                      (1024.0 * 1024.0);
    std::ostringstream what;
    what << "distance field of " << chosen.size() << " tiles of " << tile_cells << " x "
         << tile_cells << " samples";
    CheckMemory(mb, what.str(), config);
    std::vector<TraversableField::Tile> tiles;
    tiles.reserve(chosen.size());
    for (const auto& [ti, tj] : chosen)
        tiles.push_back(MakeTile(network, grid, tile_cells, ti, tj, config));
    return TraversableField(grid, tile_cells, std::move(tiles), config.truncation_m);
}

// RasteriseRoadCorridor builds tiles only when they hold at most this share of the box.
constexpr double kOneGridShare = 0.5;

int TileCells(const RoadFieldConfig& config) {
    return std::max(4, int(std::lround(config.tile_m / config.resolution_m)));
}

}  // namespace

std::optional<ParamProblem> RoadClassConfig::FindProblem() const {
    return CheckRows(kRoadClassParams, *this);
}

std::string RoadClassConfig::Validate() const {
    return ToMessage(kRoadClassParams.section, FindProblem());
}

std::map<std::string, double> RoadClassConfig::Table() const {
    std::map<std::string, double> table;
    if (profile == "vehicle" || profile == "all") table = VehicleTable();
    if (profile == "pedestrian" || profile == "all") {
        for (const auto& [k, v] : PedestrianTable()) table.emplace(k, v);
    }
    for (const auto& [k, v] : half_width_overrides_m) table[k] = v;
    for (auto it = table.begin(); it != table.end();)
        it = it->second > 0 ? std::next(it) : table.erase(it);
    return table;
}

Eigen::AlignedBox2d RoadNetwork::Bounds() const {
    Eigen::AlignedBox2d box;
    for (const auto& r : roads)
        for (const auto& p : r.points_en) box.extend(p);
    return box;
}

double RoadNetwork::TotalLengthM() const {
    double len = 0.0;
    for (const auto& r : roads) {
        for (std::size_t i = 1; i < r.points_en.size(); ++i)
            len += (r.points_en[i] - r.points_en[i - 1]).norm();
    }
    return len;
}

RoadNetwork BuildRoadNetwork(const OsmRoads& osm,
                             const std::function<Eigen::Vector2d(const GeoPoint&)>& to_en,
                             const RoadClassConfig& config) {
    const auto table = config.Table();
    RoadNetwork net;
    net.missing_node_refs = osm.report.missing_node_refs;
    for (const OsmWay& way : osm.ways) {
        if (way.is_area) {
            ++net.ways_area;
            continue;
        }
        auto it = table.find(way.highway);
        double hw = it != table.end() ? it->second : 0.0;
        if (it == table.end() && config.profile == "all") hw = config.default_half_width_m;
        if (hw <= 0.0) {
            ++net.ways_excluded_by_class;
            continue;
        }
        for (const GeoPoint& g : way.nodes)
            net.lon_lat_deg.extend(Eigen::Vector2d(g.lon_deg, g.lat_deg));
        RoadPolyline road{way.id, way.highway, hw, {}};
        road.points_en.reserve(way.nodes.size());
        for (const GeoPoint& g : way.nodes) road.points_en.push_back(to_en(g));
        net.roads.push_back(std::move(road));
    }
    return net;
}

std::optional<ParamProblem> RoadFieldConfig::FindProblem() const {
    return CheckRows(kRoadFieldParams, *this);
}

std::string RoadFieldConfig::Validate() const {
    return ToMessage(kRoadFieldParams.section, FindProblem());
}

TraversableField RasteriseRoads(const RoadNetwork& network, const Eigen::AlignedBox2d& region_en,
                                const RoadFieldConfig& config) {
    if (network.roads.empty()) throw std::invalid_argument("the road network is empty");
    const Eigen::AlignedBox2d box = FieldBox(network, region_en, config);
    if (config.tile_m <= 0.0) {
        const GridSpec spec = MakeSpec(box, config);
        auto [centre, corridor] = DistanceSamples(network, spec, spec, 0, 0, config);
        return TraversableField(InterpolatedField(spec, std::move(centre)),
                                InterpolatedField(spec, std::move(corridor)), config.truncation_m);
    }
    const GridSpec grid = GridOver(box, config);
    const int tile_cells = TileCells(config);
    std::vector<std::pair<int, int>> chosen;
    for (int tj = 0; tj * tile_cells < grid.ny; ++tj) {
        for (int ti = 0; ti * tile_cells < grid.nx; ++ti) chosen.emplace_back(ti, tj);
    }
    return BuildTiles(network, grid, chosen, tile_cells, config);
}

TraversableField RasteriseRoadCorridor(const RoadNetwork& network,
                                       const Eigen::AlignedBox2d& region_en,
                                       const std::vector<FieldDisc>& corridor,
                                       const RoadFieldConfig& config) {
    if (network.roads.empty()) throw std::invalid_argument("the road network is empty");
    const GridSpec grid = GridOver(FieldBox(network, region_en, config), config);
    const int tile_cells = TileCells(config);
    const double tile_m = tile_cells * config.resolution_m;
    const int tiles_x = (grid.nx + tile_cells - 1) / tile_cells;
    const int tiles_y = (grid.ny + tile_cells - 1) / tile_cells;
    std::vector<std::uint8_t> keep(std::size_t(tiles_x) * tiles_y, 0);
    for (const FieldDisc& d : corridor) {
        // Every tile whose square comes within the disc's radius of its centre.
        const Eigen::Vector2d c = d.centre_en - grid.origin_m.head<2>();
        const int i0 = std::max(0, int(std::floor((c.x() - d.radius_m) / tile_m)));
        const int i1 = std::min(tiles_x - 1, int(std::floor((c.x() + d.radius_m) / tile_m)));
        const int j0 = std::max(0, int(std::floor((c.y() - d.radius_m) / tile_m)));
        const int j1 = std::min(tiles_y - 1, int(std::floor((c.y() + d.radius_m) / tile_m)));
        for (int tj = j0; tj <= j1; ++tj) {
            for (int ti = i0; ti <= i1; ++ti) {
                const Eigen::Vector2d lo(ti * tile_m, tj * tile_m);
                const Eigen::Vector2d nearest =
                    c.cwiseMax(lo).cwiseMin(lo + Eigen::Vector2d::Constant(tile_m));
                if ((nearest - c).norm() <= d.radius_m) keep[std::size_t(tj) * tiles_x + ti] = 1;
            }
        }
    }
    std::vector<std::pair<int, int>> chosen;
    for (int tj = 0; tj < tiles_y; ++tj) {
        for (int ti = 0; ti < tiles_x; ++ti) {
            if (keep[std::size_t(tj) * tiles_x + ti]) chosen.emplace_back(ti, tj);
        }
    }
    // A corridor that covers most of the box saves little and costs the tiles' overlap in build
    // time: then the one grid (when it fits the cap), whose samples are placed without the
    // tiles' sub-grid origins (the fields agree to float rounding, not to the last bit).
    const double held = double(chosen.size()) * tile_cells * tile_cells;
    const double whole_mb = double(grid.size()) * kPeakBytesPerSample / (1024.0 * 1024.0);
    if (held > kOneGridShare * double(grid.size()) && whole_mb <= config.max_memory_mb) {
        RoadFieldConfig one = config;
        one.tile_m = 0.0;
        return RasteriseRoads(network, region_en, one);
    }
    return BuildTiles(network, grid, chosen, tile_cells, config);
}

}  // namespace driftcorr
