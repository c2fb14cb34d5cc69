// The definitions of what driftcorr/mapping/indoor_field.h declares.
#include "driftcorr/mapping/indoor_field.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <future>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "driftcorr/mapping/grid.h"
#include "voxel_corridor.h"

namespace driftcorr {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
using Mask = std::vector<std::uint8_t>;

// The horizontal plane of a 3D spec (nz = 1): slice k of the 3D grid is contiguous in memory and
// indexed like this plane.
GridSpec PlaneOf(const GridSpec& s) {
    GridSpec p = s;
    p.nz = 1;
    p.resolution_z_m = 0.0;
    return p;
}

// Scanline fill (even-odd rule over the outer ring and the holes) of the samples whose centre
// lies inside the polygon: one pass over the edges per row, no per-sample point-in-polygon test.
void FillPolygon(const GridSpec& s, const FloorPolygon& poly, std::uint8_t value, Mask& mask) {
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> edges;
    double y_lo = std::numeric_limits<double>::infinity(), y_hi = -y_lo;
    auto add_ring = [&](const std::vector<Eigen::Vector2d>& ring) {
        for (std::size_t k = 0; k < ring.size(); ++k) {
            const Eigen::Vector2d& a = ring[k];
            const Eigen::Vector2d& b = ring[(k + 1) % ring.size()];
            if (a.y() != b.y()) edges.emplace_back(a, b);
            y_lo = std::min(y_lo, a.y());
            y_hi = std::max(y_hi, a.y());
        }
    };
    add_ring(poly.outer_en);
    for (const auto& hole : poly.holes_en) add_ring(hole);
    if (edges.empty()) return;
    const double res = s.resolution_m, ox = s.origin_m.x(), oy = s.origin_m.y();
    // Samples on the boundary count as inside (the 1e-9 absorbs rounding of (x - origin) / res).
    const int j0 = std::max(0, int(std::ceil((y_lo - oy) / res - 1e-9)));
    const int j1 = std::min(s.ny - 1, int(std::floor((y_hi - oy) / res + 1e-9)));
    std::vector<double> xs;
    for (int j = j0; j <= j1; ++j) {
        const double y = oy + res * j;
        xs.clear();
        for (const auto& [a, b] : edges) {
            if ((a.y() <= y) != (b.y() <= y)) {
                xs.push_back(a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y()));
            }
        }
        std::sort(xs.begin(), xs.end());
        std::uint8_t* row = &mask[s.Index(0, j)];
        for (std::size_t q = 0; q + 1 < xs.size(); q += 2) {
            const int i0 = std::max(0, int(std::ceil((xs[q] - ox) / res - 1e-9)));
            const int i1 = std::min(s.nx - 1, int(std::floor((xs[q + 1] - ox) / res + 1e-9)));
            if (i1 >= i0) std::memset(row + i0, value, std::size_t(i1 - i0 + 1));
        }
    }
}

// Marks the samples within half_width of the segment as traversable and records exact
// distances within `reach` (>= half_width) in `exact`.
void RasteriseWalkway(const GridSpec& s, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                      double half_width, double reach, Mask& mask, std::vector<float>& exact) {
    const CellBox box = SegmentCells(s, a, b, reach);
    for (int j = box.j0; j <= box.j1; ++j) {
        int i0 = 0, i1 = -1;
        if (!SegmentRowCells(s, 0, 0, j, a, b, reach, box, i0, i1)) continue;
        for (int i = i0; i <= i1; ++i) {
            const double d = PointSegmentDistance(s.Position(i, j).head<2>(), a, b);
            if (d > reach) continue;
            const std::size_t idx = s.Index(i, j);
            exact[idx] = std::min(exact[idx], float(d));
            if (d <= half_width) mask[idx] = 1;
        }
    }
}

// One floor on the horizontal plane.
struct FloorRaster {
    double surface_z_m = 0.0;
    int k_surface = 0;                 // voxel layer nearest the surface
    int k_lo = 0, k_hi = 0;            // the walkable layer
    int k_conn_lo = 0, k_conn_hi = 0;  // the stair columns
    Mask walkable;                     // traversable on the layer
    Mask connector;                    // stairs
    Mask lift;                         // lift shafts
    std::vector<float> walkway_exact;  // exact distance to the walkway lines, kInf beyond the band
    bool has_walkways = false;
};

FloorRaster RasteriseFloor(const GridSpec& plane, const IndoorFloor& f,
                           const IndoorFieldConfig& c) {
    FloorRaster r;
    r.walkable.assign(plane.size(), 0);
    r.connector.assign(plane.size(), 0);
    r.lift.assign(plane.size(), 0);
    r.walkway_exact.assign(plane.size(), kInf);
    for (const auto& p : f.walkable) FillPolygon(plane, p, 1, r.walkable);
    for (const auto& p : f.walls) FillPolygon(plane, p, 0, r.walkable);
    for (const auto& p : f.doors) FillPolygon(plane, p, 1, r.walkable);
    for (const auto& p : f.stairs) FillPolygon(plane, p, 1, r.connector);
    for (const auto& p : f.lifts) FillPolygon(plane, p, 1, r.lift);
    const double reach = std::max(c.walkway_half_width_m, c.exact_band_m);
    for (const auto& line : f.walkways_en) {
        for (std::size_t k = 1; k < line.size(); ++k) {
            RasteriseWalkway(plane, line[k - 1], line[k], c.walkway_half_width_m, reach, r.walkable,
                             r.walkway_exact);
            r.has_walkways = true;
        }
    }
    for (std::size_t i = 0; i < plane.size(); ++i) r.walkable[i] |= r.connector[i] | r.lift[i];
    return r;
}

Eigen::AlignedBox2d FloorsBounds(const std::vector<IndoorFloor>& floors) {
    Eigen::AlignedBox2d box;
    auto add = [&box](const std::vector<FloorPolygon>& ps) {
        for (const auto& p : ps)
            for (const auto& q : p.outer_en) box.extend(q);
    };
    for (const auto& f : floors) {
        add(f.walkable);
        add(f.doors);
        add(f.stairs);
        add(f.lifts);
        for (const auto& l : f.walkways_en)
            for (const auto& q : l) box.extend(q);
    }
    return box;
}

GridSpec MakeSpec(const Eigen::AlignedBox2d& box, double z_lo, double z_hi,
                  const IndoorFieldConfig& c, const std::optional<std::pair<int, int>>& layers) {
    const Eigen::AlignedBox3d box3(Eigen::Vector3d(box.min().x(), box.min().y(), z_lo),
                                   Eigen::Vector3d(box.max().x(), box.max().y(), z_hi));
    return internal::VoxelGridSpec(
        box3, {c.resolution_m, c.resolution_z_m, c.margin_m, c.vertical_margin_m, c.max_memory_mb},
        "indoor", layers);
}

// The layers of `all` that give every value the whole building's field gives at `heights`:
// the interpolation reads two layers beyond them, and a voxel's distance within the truncation
// comes from a traversable voxel within it. Those are floor layers, whole here when they come
// within the truncation; or stair and lift columns, each continuous up to a floor's surface, so
// a column voxel beyond the kept layers has one at least as near in them: level with the voxel
// read, or at the floor surface where the column ends.
std::pair<int, int> KeptLayers(const GridSpec& all, const std::vector<FloorRaster>& rasters,
                               const HeightRange& heights, double truncation_m) {
    if (!(heights.lo_m <= heights.hi_m) || !std::isfinite(heights.lo_m) ||
        !std::isfinite(heights.hi_m)) {
        throw std::invalid_argument("the heights the indoor field serves are not a finite range");
    }
    const double dz = all.dz();
    const double g_lo = std::clamp((heights.lo_m - all.origin_m.z()) / dz, -1.0, double(all.nz));
    const double g_hi = std::clamp((heights.hi_m - all.origin_m.z()) / dz, -1.0, double(all.nz));
    const int read_lo = int(std::floor(g_lo)) - 2, read_hi = int(std::ceil(g_hi)) + 2;
    // The distance transforms' cap: the truncation and a cell.
    const int reach = int(std::ceil((truncation_m + all.resolution_m) / dz));
    int first = read_lo, last = read_hi;
    for (const FloorRaster& r : rasters) {
        if (r.k_hi < read_lo - reach || r.k_lo > read_hi + reach) continue;
        first = std::min(first, r.k_lo);
        last = std::max(last, r.k_hi);
    }
    return {std::clamp(first, 0, all.nz - 1), std::clamp(last, 0, all.nz - 1)};
}

}  // namespace

std::optional<ParamProblem> IndoorFieldConfig::FindProblem() const {
    if (auto problem = CheckRows(kIndoorFieldParams, *this)) return problem;
    return internal::ThinLayerProblem(vertical_tolerance_m, resolution_z_m);
}

std::string IndoorFieldConfig::Validate() const {
    return ToMessage(kIndoorFieldParams.section, FindProblem());
}

TraversableField BuildIndoorField(const std::vector<IndoorFloor>& floors,
                                  const IndoorFieldConfig& config, IndoorFieldStats* stats,
                                  const std::optional<HeightRange>& heights) {
    if (const std::string err = config.Validate(); !err.empty()) throw std::invalid_argument(err);
    if (floors.empty()) throw std::invalid_argument("the indoor map has no floor");
    const Eigen::AlignedBox2d box = FloorsBounds(floors);
    if (box.isEmpty()) throw std::invalid_argument("the indoor map has no walkable geometry");
    // Floors in ascending height.
    std::vector<std::size_t> order(floors.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return floors[a].floor_z_m < floors[b].floor_z_m;
    });
    const double z_lo = floors[order.front()].floor_z_m + config.device_height_m;
    const double z_hi = floors[order.back()].floor_z_m + config.device_height_m;
    // The layers of the whole building are numbered in `all`; the grid `s` holds those from k0
    // to k0 + s.nz - 1 (KeptLayers).
    IndoorFieldConfig whole = config;  // the memory cap applies to the layers built
    whole.max_memory_mb = std::numeric_limits<double>::infinity();
    const GridSpec all = MakeSpec(box, z_lo, z_hi, whole, std::nullopt);
    const GridSpec plane = PlaneOf(all);
    const double dz = all.dz();
    auto layer_of = [&](double z) {
        return std::clamp(int(std::lround((z - all.origin_m.z()) / dz)), 0, all.nz - 1);
    };

    std::vector<FloorRaster> rasters(floors.size());
    for (std::size_t n = 0; n < order.size(); ++n) {
        FloorRaster& r = rasters[n];
        r = RasteriseFloor(plane, floors[order[n]], config);
        r.surface_z_m = floors[order[n]].floor_z_m + config.device_height_m;
        r.k_surface = layer_of(r.surface_z_m);
        // The layer: voxels within vertical_tolerance_m of the surface, at least the nearest.
        const double g_lo = (r.surface_z_m - config.vertical_tolerance_m - all.origin_m.z()) / dz;
        const double g_hi = (r.surface_z_m + config.vertical_tolerance_m - all.origin_m.z()) / dz;
        r.k_lo = std::clamp(std::min(r.k_surface, int(std::ceil(g_lo - 1e-9))), 0, all.nz - 1);
        r.k_hi = std::clamp(std::max(r.k_surface, int(std::floor(g_hi + 1e-9))), 0, all.nz - 1);
    }
    for (std::size_t n = 0; n < rasters.size(); ++n) {
        rasters[n].k_conn_lo = n > 0 ? rasters[n - 1].k_surface : rasters[n].k_surface;
        rasters[n].k_conn_hi =
            n + 1 < rasters.size() ? rasters[n + 1].k_surface : rasters[n].k_surface;
    }
    std::optional<std::pair<int, int>> kept;
    if (heights) kept = KeptLayers(all, rasters, *heights, config.truncation_m);
    const GridSpec s = MakeSpec(box, z_lo, z_hi, config, kept);
    const int k0 = kept ? std::clamp(kept->first, 0, all.nz - 1) : 0;
    // The layers [a, b] of the whole building that the grid holds, as the grid's layers.
    auto held = [&](int a, int b) {
        return std::pair<int, int>(std::max(a, k0) - k0, std::min(b, k0 + s.nz - 1) - k0);
    };

    // The traversable set and the centre seeds.
    const std::size_t np = plane.size();
    Mask inside, seeds;
    AssignLarge(inside, s.size(), std::uint8_t(0));
    AssignLarge(seeds, s.size(), std::uint8_t(0));
    const float half = 0.5f * float(s.resolution_m);
    std::size_t connector_voxels = 0;
    for (const FloorRaster& r : rasters) {
        const auto [layer_lo, layer_hi] = held(r.k_lo, r.k_hi);
        for (int k = layer_lo; k <= layer_hi; ++k) {
            std::uint8_t* slice = &inside[s.Index(0, 0, k)];
            for (std::size_t i = 0; i < np; ++i) slice[i] |= r.walkable[i];
        }
        // Stairs join a floor to its neighbours; a lift is a shaft through every floor of the map
        // (plans mark a lift on some floors only: hcu_eight's 4th-floor lift is on no other plan).
        const std::pair<const Mask*, std::pair<int, int>> columns[] = {
            {&r.connector, {r.k_conn_lo, r.k_conn_hi}},
            {&r.lift, {rasters.front().k_surface, rasters.back().k_surface}}};
        for (const auto& [mask, range] : columns) {
            const auto [column_lo, column_hi] = held(range.first, range.second);
            for (int k = column_lo; k <= column_hi; ++k) {
                std::uint8_t* slice = &inside[s.Index(0, 0, k)];
                std::uint8_t* seed = &seeds[s.Index(0, 0, k)];
                const bool off_floor = k + k0 < r.k_lo || k + k0 > r.k_hi;
                for (std::size_t i = 0; i < np; ++i) {
                    if (!(*mask)[i]) continue;
                    connector_voxels += off_floor && !slice[i];
                    slice[i] = 1;
                    seed[i] = 1;
                }
            }
        }
        if (r.k_surface < k0 || r.k_surface >= k0 + s.nz) continue;
        std::uint8_t* seed = &seeds[s.Index(0, 0, r.k_surface - k0)];
        for (std::size_t i = 0; i < np; ++i) {
            seed[i] |= r.has_walkways ? std::uint8_t(r.walkway_exact[i] <= half) : r.walkable[i];
        }
    }
    const float trunc = float(config.truncation_m);
    // The two transforms side by side when a second thread is allowed; the walkable mask (a
    // byte a voxel) then stays until both are done: hcu_eight's peak 224 -> 241 MB.
    std::future<std::vector<float>> to_corridor =
        std::async(SecondThreadLaunch(config.threads),
                   [&s, &inside, trunc] { return internal::CorridorField(s, inside, trunc); });
    // Clamped to trunc below: beyond it the distances need not be exact.
    std::vector<float> centre = EuclideanDistanceTransform(s, seeds, trunc);
    seeds.clear();
    seeds.shrink_to_fit();
    std::vector<float> corridor = to_corridor.get();
    inside.clear();
    inside.shrink_to_fit();
    // Exact distances to the walkway lines near each floor's surface.
    const double band = config.exact_band_m;
    for (const FloorRaster& r : rasters) {
        if (!r.has_walkways) continue;
        for (int k = 0; k < s.nz; ++k) {
            const double dzk = all.origin_m.z() + (k + k0) * dz - r.surface_z_m;
            if (std::abs(dzk) > band) continue;
            float* slice = &centre[s.Index(0, 0, k)];
            for (std::size_t i = 0; i < np; ++i) {
                const float e = r.walkway_exact[i];
                if (e == kInf) continue;
                const float d = std::sqrt(e * e + float(dzk * dzk));
                if (d <= band) slice[i] = d;
            }
        }
    }
    for (float& v : centre) v = std::min(v, trunc);

    if (stats) {
        stats->voxels = s.size();
        stats->connector_voxels = connector_voxels;
        stats->walkable_area_m2.assign(floors.size(), 0.0);
        for (std::size_t n = 0; n < order.size(); ++n) {
            const auto& w = rasters[n].walkable;
            stats->walkable_area_m2[order[n]] =
                double(std::count(w.begin(), w.end(), std::uint8_t(1))) * s.resolution_m *
                s.resolution_m;
        }
    }
    TraversableField field(InterpolatedField(s, std::move(centre)),
                           InterpolatedField(s, std::move(corridor)), config.truncation_m);
    std::vector<ShaftOutline> shafts;
    for (const IndoorFloor& f : floors) {
        for (const FloorPolygon& lift : f.lifts) {
            if (lift.outer_en.size() >= 3) shafts.push_back(lift.outer_en);
        }
    }
    field.set_lift_shafts(std::move(shafts));
    return field;
}

}  // namespace driftcorr
