// The definitions of what driftcorr/mapping/walkable_surface.h declares.
#include "driftcorr/mapping/walkable_surface.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include "driftcorr/core/format.h"

namespace driftcorr {
namespace {

// Extents beyond which a cloud cannot be a building in metres.
constexpr double kMaxExtentM = 5000.0, kMinExtentM = 1.0;

struct DisjointSets {
    std::vector<int> parent;
    explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
    int Find(int a) {
        while (parent[a] != a) a = parent[a] = parent[parent[a]];
        return a;
    }
    void Join(int a, int b) {
        a = Find(a), b = Find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

// The voxel grid, aligned to multiples of the resolution (so that the columns of two clouds
// binned at the same resolution coincide), one bit per voxel, a column of words per (i, j).
struct Grid {
    double res = 0.0;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    int nx = 0, ny = 0, nz = 0, words = 0;
    std::vector<std::uint64_t> bits;

    int Column(int i, int j) const { return j * nx + i; }
    bool Occupied(int column, int k) const {
        return k >= 0 && k < nz &&
               (bits[std::size_t(column) * words + k / 64] >> (k % 64) & 1u) != 0;
    }
    void Set(int column, int k) { bits[std::size_t(column) * words + k / 64] |= 1ull << (k % 64); }
    Eigen::Vector3i Index(const Eigen::Vector3d& p) const {
        return ((p - origin) / res).array().floor().cast<int>();
    }
    Eigen::Vector2d Centre(int i, int j) const {
        return origin.head<2>() + res * Eigen::Vector2d(i + 0.5, j + 0.5);
    }
};

Grid MakeGrid(const std::vector<Eigen::Vector3d>& cloud, const WalkableSurfaceConfig& c) {
    Eigen::Vector3d lo = cloud.front(), hi = cloud.front();
    for (const Eigen::Vector3d& p : cloud) {
        if (!p.allFinite()) throw std::invalid_argument("a point is not finite");
        lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    }
    Grid g;
    g.res = c.resolution_m;
    g.origin = ((lo / g.res).array().floor() - 1.0).matrix() * g.res;
    const Eigen::Vector3d n = ((hi - g.origin) / g.res).array().floor() + 2.0;
    const double columns = n.x() * n.y(), words = std::ceil(n.z() / 64.0);
    const double mb = columns * words * 8.0 / 1e6;
    if (!(mb <= c.max_memory_mb) || n.maxCoeff() > 2e9) {
        const Eigen::Vector3d extent = hi - lo;
        throw std::invalid_argument(
            "the cloud spans " + FormatFixed(extent.x(), 1) + " x " + FormatFixed(extent.y(), 1) +
            " x " + FormatFixed(extent.z(), 1) + " m: its voxels at " + FormatFixed(g.res, 2) +
            " m would take " + FormatFixed(mb, 0) + " MB (max_memory_mb " +
            FormatFixed(c.max_memory_mb, 0) + "); crop it or coarsen the resolution");
    }
    g.nx = int(n.x()), g.ny = int(n.y()), g.nz = int(n.z()), g.words = int(words);
    g.bits.assign(std::size_t(g.nx) * g.ny * g.words, 0);
    for (const Eigen::Vector3d& p : cloud) {
        const Eigen::Vector3i v = g.Index(p);
        g.Set(g.Column(v.x(), v.y()), v.z());
    }
    return g;
}

// A standing place: the top voxel of a run of occupied voxels in a column, under headroom_m of
// free space (up to the next run) or under nothing at all. `open` marks the second kind when the
// run also hangs headroom_m or more above the run below it: a ceiling or roof seen from below
// looks like that (free space under it, nothing above), and so does a top floor whose ceiling
// the scan did not capture.
struct Place {
    int i, j, k;
    bool open;
};

// The standing places, column by column (bottom to top in a column); first[c] .. first[c + 1]
// are column c's.
std::vector<Place> StandingPlaces(const Grid& g, const WalkableSurfaceConfig& c,
                                  std::vector<int>& first, std::size_t& occupied) {
    const int head = int(std::ceil(c.headroom_m / g.res - 1e-9));
    std::vector<Place> places;
    first.assign(std::size_t(g.nx) * g.ny + 1, 0);
    occupied = 0;
    std::vector<std::pair<int, int>> runs;  // [bottom, top] of each run, bottom up
    for (int j = 0; j < g.ny; ++j) {
        for (int i = 0; i < g.nx; ++i) {
            const int col = g.Column(i, j);
            first[col] = int(places.size());
            runs.clear();
            for (int w = 0; w < g.words; ++w) {
                std::uint64_t word = g.bits[std::size_t(col) * g.words + w];
                while (word != 0) {
                    const int k = 64 * w + __builtin_ctzll(word);
                    word &= word - 1;
                    ++occupied;
                    if (!runs.empty() && runs.back().second == k - 1) {
                        runs.back().second = k;
                    } else {
                        runs.emplace_back(k, k);
                    }
                }
            }
            for (std::size_t r = 0; r < runs.size(); ++r) {
                const auto [bottom, top] = runs[r];
                if (r + 1 < runs.size()) {
                    if (runs[r + 1].first - top - 1 >= head) places.push_back({i, j, top, false});
                } else {
                    const bool hangs = r > 0 && bottom - runs[r - 1].second - 1 >= head;
                    places.push_back({i, j, top, hangs});
                }
            }
        }
    }
    first.back() = int(places.size());
    return places;
}

// The regions of the places: neighbouring columns' places at most step_m apart in height.
struct Regions {
    std::vector<int> of;  ///< per place
    std::vector<WalkableRegion> list;
    std::vector<std::size_t> open_places, all_places;  ///< per region
    bool MostlyOpen(std::size_t r) const { return 2 * open_places[r] > all_places[r]; }
};

Regions FindRegions(const Grid& g, const WalkableSurfaceConfig& c, const std::vector<Place>& places,
                    const std::vector<double>& height, const std::vector<int>& first) {
    DisjointSets sets(places.size());
    for (std::size_t n = 0; n < places.size(); ++n) {
        const Place& p = places[n];
        for (const auto& [di, dj] : {std::pair{1, 0}, {0, 1}, {1, 1}, {-1, 1}}) {
            const int i = p.i + di, j = p.j + dj;
            if (i < 0 || i >= g.nx || j >= g.ny) continue;
            const int col = g.Column(i, j);
            for (int m = first[col]; m < first[col + 1]; ++m) {
                if (std::abs(height[m] - height[n]) <= c.step_m) sets.Join(int(n), m);
            }
        }
    }
    Regions out;
    out.of.resize(places.size());
    std::unordered_map<int, int> index_of_root;
    const double cell_m2 = g.res * g.res;
    for (std::size_t n = 0; n < places.size(); ++n) {
        auto [it, added] = index_of_root.try_emplace(sets.Find(int(n)), int(out.list.size()));
        if (added) {
            out.list.push_back({});
            out.list.back().z_min_m = 1e300, out.list.back().z_max_m = -1e300;
            out.open_places.push_back(0), out.all_places.push_back(0);
        }
        const int r = it->second;
        out.open_places[r] += places[n].open ? 1 : 0;
        ++out.all_places[r];
        out.of[n] = r;
        WalkableRegion& reg = out.list[r];
        reg.area_m2 += cell_m2;
        reg.z_min_m = std::min(reg.z_min_m, height[n]),
        reg.z_max_m = std::max(reg.z_max_m, height[n]);
    }
    return out;
}

// Closes the gaps of a scan (holes in a floor, a doorway lost to a hole) up to fill_gap_m long:
// between two places at most step_m apart in height, along one of four directions, across
// columns with no place near that height and no occupied voxel from step_m below it to
// headroom_m above it (so never through a wall, under a table or into furniture). The new places
// get heights interpolated along the gap; `places`, `height` and the column index `first` are
// rebuilt with them. Returns how many were added.
std::size_t FillGaps(const Grid& g, const WalkableSurfaceConfig& c, std::vector<Place>& places,
                     std::vector<double>& height, std::vector<int>& first) {
    if (!(c.fill_gap_m > 0.0)) return 0;
    // Only floors close gaps: places of regions of at least min_region_m2 that are not mostly
    // open (a ceiling seen from below, scattered tops of clutter are not bridged).
    const Regions before = FindRegions(g, c, places, height, first);
    std::vector<bool> floor(places.size());
    for (std::size_t n = 0; n < places.size(); ++n) {
        const int r = before.of[n];
        floor[n] = before.list[r].area_m2 >= c.min_region_m2 && !before.MostlyOpen(r);
    }
    const int head = int(std::ceil(c.headroom_m / g.res - 1e-9));
    const int step = int(std::floor(c.step_m / g.res + 1e-9));
    auto near = [&](int col, double z) {  // any place near z, or -1
        for (int m = first[col]; m < first[col + 1]; ++m) {
            if (std::abs(height[m] - z) <= c.step_m) return m;
        }
        return -1;
    };
    auto clear = [&](int col, int k) {
        for (int kk = std::max(0, k - step); kk <= std::min(g.nz - 1, k + head); ++kk) {
            if (g.Occupied(col, kk)) return false;
        }
        return true;
    };
    struct Fill {
        int i, j, k;
        double z;
    };
    std::vector<Fill> fills;
    std::unordered_map<std::int64_t, int> filled;  // (column, k) already filled
    const std::size_t given = places.size();
    for (std::size_t n = 0; n < given; ++n) {
        if (!floor[n]) continue;
        const Place p = places[n];
        for (const auto& [di, dj] : {std::pair{1, 0}, {0, 1}, {1, 1}, {-1, 1}}) {
            const int reach = int(std::floor(c.fill_gap_m / (g.res * std::hypot(di, dj))));
            const int i1 = p.i + di, j1 = p.j + dj;
            if (i1 < 0 || i1 >= g.nx || j1 >= g.ny || near(g.Column(i1, j1), height[n]) >= 0) {
                continue;  // no gap next to this place in this direction
            }
            for (int t = 1; t <= reach + 1; ++t) {
                const int i = p.i + t * di, j = p.j + t * dj;
                if (i < 0 || i >= g.nx || j >= g.ny) break;
                const int col = g.Column(i, j);
                const int end = near(col, height[n]);
                if (end >= 0 && !floor[end]) break;  // clutter or a ceiling: no bridge
                if (end >= 0) {                      // the far side: fill cells 1 .. t - 1
                    for (int u = 1; u < t; ++u) {
                        const double z = height[n] + (height[end] - height[n]) * u / t;
                        const int fi = p.i + u * di, fj = p.j + u * dj;
                        const int k = int(std::floor((z - g.origin.z()) / g.res));
                        const std::int64_t key = std::int64_t(g.Column(fi, fj)) * g.nz + k;
                        if (filled.emplace(key, 1).second) fills.push_back({fi, fj, k, z});
                    }
                    break;
                }
                if (t > reach) break;
                const int k = int(std::floor((height[n] - g.origin.z()) / g.res));
                if (!clear(col, k)) break;
            }
        }
    }
    if (fills.empty()) return 0;
    std::vector<std::pair<Place, double>> all;
    all.reserve(places.size() + fills.size());
    for (std::size_t n = 0; n < places.size(); ++n) all.emplace_back(places[n], height[n]);
    for (const Fill& f : fills) all.push_back({{f.i, f.j, f.k, false}, f.z});
    std::stable_sort(all.begin(), all.end(), [&](const auto& a, const auto& b) {
        const int ca = g.Column(a.first.i, a.first.j), cb = g.Column(b.first.i, b.first.j);
        return ca != cb ? ca < cb : a.first.k < b.first.k;
    });
    places.clear();
    height.clear();
    std::fill(first.begin(), first.end(), 0);
    for (const auto& [p, z] : all) {
        ++first[g.Column(p.i, p.j) + 1];
        places.push_back(p);
        height.push_back(z);
    }
    for (std::size_t col = 1; col < first.size(); ++col) first[col] += first[col - 1];
    return fills.size();
}

}  // namespace

std::string WalkableSurfaceConfig::Validate() const {
    auto positive = [](const char* key, double v) {
        return std::isfinite(v) && v > 0.0
                   ? std::string()
                   : std::string(key) + ": must be > 0 (got " + FormatFixed(v, 3) + ")";
    };
    for (const auto& [key, v] : {std::pair<const char*, double>{"resolution_m", resolution_m},
                                 {"headroom_m", headroom_m},
                                 {"step_m", step_m},
                                 {"lift_level_step_m", lift_level_step_m},
                                 {"max_memory_mb", max_memory_mb}}) {
        if (std::string m = positive(key, v); !m.empty()) return m;
    }
    if (!(std::isfinite(min_region_m2) && min_region_m2 >= 0.0))
        return "min_region_m2: must be >= 0";
    if (!(std::isfinite(lift_reach_m) && lift_reach_m >= 0.0)) return "lift_reach_m: must be >= 0";
    if (!(std::isfinite(fill_gap_m) && fill_gap_m >= 0.0)) return "fill_gap_m: must be >= 0";
    for (const LiftShaft& l : lifts) {
        if (!(l.x1 > l.x0 && l.y1 > l.y0)) return "lifts: a shaft needs x1 > x0 and y1 > y0";
    }
    return "";
}

WalkableSurface ExtractWalkableSurface(const std::vector<Eigen::Vector3d>& cloud,
                                       const WalkableSurfaceConfig& config) {
    if (std::string m = config.Validate(); !m.empty()) throw std::invalid_argument(m);
    if (cloud.empty()) throw std::invalid_argument("the cloud has no point");
    const Grid g = MakeGrid(cloud, config);
    WalkableSurface out;
    out.input_points = cloud.size();
    std::vector<int> first;
    std::vector<Place> places = StandingPlaces(g, config, first, out.occupied_voxels);
    out.standing_places = places.size();

    // Each place's height: the mean height of the cloud's points in its voxel.
    auto key = [&](int i, int j, int k) {
        return (std::int64_t(k) * g.ny + j) * std::int64_t(g.nx) + i;
    };
    std::unordered_map<std::int64_t, int> place_of_voxel;
    place_of_voxel.reserve(places.size());
    for (std::size_t n = 0; n < places.size(); ++n) {
        place_of_voxel.emplace(key(places[n].i, places[n].j, places[n].k), int(n));
    }
    std::vector<double> height(places.size(), 0.0);
    std::vector<int> height_count(places.size(), 0);
    for (const Eigen::Vector3d& p : cloud) {
        const Eigen::Vector3i v = g.Index(p);
        const auto it = place_of_voxel.find(key(v.x(), v.y(), v.z()));
        if (it == place_of_voxel.end()) continue;
        height[it->second] += p.z();
        ++height_count[it->second];
    }
    for (std::size_t n = 0; n < places.size(); ++n) height[n] /= std::max(height_count[n], 1);
    out.filled_places = FillGaps(g, config, places, height, first);

    const Regions found = FindRegions(g, config, places, height, first);
    const std::vector<int>& region_of = found.of;
    std::vector<WalkableRegion> regions = found.list;
    auto mostly_open = [&](std::size_t r) { return found.MostlyOpen(r); };
    // Lifts join the large regions that come within lift_reach_m of their shaft (floors, not
    // ceilings seen from below) and span the heights of their places there.
    const int reach = int(std::ceil(config.lift_reach_m / g.res));
    DisjointSets groups(regions.size());
    std::vector<std::pair<double, double>> lift_span(config.lifts.size(), {1e300, -1e300});
    for (std::size_t l = 0; l < config.lifts.size(); ++l) {
        const LiftShaft& s = config.lifts[l];
        const Eigen::Vector3i a = g.Index({s.x0, s.y0, g.origin.z()});
        const Eigen::Vector3i b = g.Index({s.x1, s.y1, g.origin.z()});
        int joined = -1;
        for (int j = std::max(0, a.y() - reach); j <= std::min(g.ny - 1, b.y() + reach); ++j) {
            for (int i = std::max(0, a.x() - reach); i <= std::min(g.nx - 1, b.x() + reach); ++i) {
                const int col = g.Column(i, j);
                for (int m = first[col]; m < first[col + 1]; ++m) {
                    const int r = region_of[m];
                    if (regions[r].area_m2 < config.min_region_m2 || mostly_open(r)) continue;
                    const double z = height[m];
                    lift_span[l].first = std::min(lift_span[l].first, z);
                    lift_span[l].second = std::max(lift_span[l].second, z);
                    if (joined >= 0) groups.Join(joined, r);
                    joined = r;
                }
            }
        }
    }
    // The kept group: the largest total area of regions of at least min_region_m2, among the
    // groups with a region that is mostly not open (a floor under a ceiling) when there is one.
    std::unordered_map<int, double> group_area;
    std::unordered_map<int, bool> group_floored;
    for (std::size_t r = 0; r < regions.size(); ++r) {
        if (regions[r].area_m2 < config.min_region_m2) continue;
        const int grp = groups.Find(int(r));
        group_area[grp] += regions[r].area_m2;
        group_floored[grp] = group_floored[grp] || !mostly_open(r);
    }
    int kept_group = -1;
    double kept_area = 0.0;
    bool kept_floored = false;
    for (const auto& [grp, area] : group_area) {
        const bool floored = group_floored[grp];
        if (std::make_pair(floored, area) > std::make_pair(kept_floored, kept_area) ||
            (floored == kept_floored && area == kept_area && grp < kept_group)) {
            kept_group = grp, kept_area = area, kept_floored = floored;
        }
    }
    for (std::size_t r = 0; r < regions.size(); ++r) {
        WalkableRegion& reg = regions[r];
        if (reg.area_m2 < config.min_region_m2) {
            reg.why_dropped = "smaller than " + FormatFixed(config.min_region_m2, 1) + " m^2";
        } else if (groups.Find(int(r)) == kept_group) {
            reg.kept = true;
            out.area_m2 += reg.area_m2;
        } else if (mostly_open(r) && kept_floored) {
            reg.why_dropped =
                "a ceiling or roof seen from below (nothing above it, free space under it), not "
                "connected to the floors by steps or a declared lift";
        } else {
            reg.why_dropped =
                "not connected to the largest walkable region by steps or a declared lift";
        }
    }

    // Regions largest first; points in place order.
    std::vector<int> order(regions.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return regions[a].area_m2 > regions[b].area_m2; });
    std::vector<int> rank(regions.size());
    for (std::size_t r = 0; r < order.size(); ++r) rank[order[r]] = int(r);
    for (std::size_t n = 0; n < places.size(); ++n) {
        if (!regions[region_of[n]].kept) continue;
        const Eigen::Vector2d c = g.Centre(places[n].i, places[n].j);
        out.points.emplace_back(c.x(), c.y(), height[n]);
        out.region.push_back(rank[region_of[n]]);
    }
    for (int r : order) out.regions.push_back(regions[r]);

    // The declared lifts: their footprint at every lift level between the regions they touch.
    for (std::size_t l = 0; l < config.lifts.size(); ++l) {
        const auto [z_lo, z_hi] = lift_span[l];
        if (!(z_hi >= z_lo)) continue;
        const LiftShaft& s = config.lifts[l];
        const int levels = int(std::lround((z_hi - z_lo) / config.lift_level_step_m));
        for (int level = 0; level <= levels; ++level) {
            const double z = z_lo + level * config.lift_level_step_m;
            for (double y = s.y0 + 0.5 * g.res; y < s.y1; y += g.res) {
                for (double x = s.x0 + 0.5 * g.res; x < s.x1; x += g.res) {
                    out.points.emplace_back(x, y, z);
                    out.region.push_back(-1);
                    ++out.lift_points;
                }
            }
        }
    }
    return out;
}

std::optional<std::string> CheckCloudExtent(const std::vector<Eigen::Vector3d>& cloud) {
    if (cloud.empty()) return std::nullopt;
    Eigen::Vector3d lo = cloud.front(), hi = cloud.front();
    for (const Eigen::Vector3d& p : cloud) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    const Eigen::Vector3d extent = hi - lo;
    const std::string spans = FormatFixed(extent.x(), 1) + " x " + FormatFixed(extent.y(), 1) +
                              " x " + FormatFixed(extent.z(), 1) + " m";
    if (extent.maxCoeff() > kMaxExtentM) {
        return "the cloud spans " + spans +
               ": not a building in metres (millimetres or centimetres? scale it to metres)";
    }
    if (extent.maxCoeff() < kMinExtentM)
        return "the cloud spans " + spans + ": not a building in metres";
    return std::nullopt;
}

SurfaceAgreement CompareSurfaces(const std::vector<Eigen::Vector3d>& extracted,
                                 const std::vector<Eigen::Vector3d>& truth, double resolution_m,
                                 double tolerance_m) {
    auto column = [&](const Eigen::Vector3d& p) {
        const std::int64_t i = std::int64_t(std::floor(p.x() / resolution_m));
        const std::int64_t j = std::int64_t(std::floor(p.y() / resolution_m));
        return (i << 32) ^ (j & 0xffffffff);
    };
    auto heights = [&](const std::vector<Eigen::Vector3d>& points) {
        std::unordered_map<std::int64_t, std::vector<double>> h;
        for (const Eigen::Vector3d& p : points) h[column(p)].push_back(p.z());
        return h;
    };
    auto share_matched = [&](const std::vector<Eigen::Vector3d>& points,
                             const std::unordered_map<std::int64_t, std::vector<double>>& other) {
        std::size_t matched = 0;
        for (const Eigen::Vector3d& p : points) {
            const auto it = other.find(column(p));
            if (it == other.end()) continue;
            for (double z : it->second) {
                if (std::abs(z - p.z()) <= tolerance_m) {
                    ++matched;
                    break;
                }
            }
        }
        return points.empty() ? 0.0 : double(matched) / double(points.size());
    };
    SurfaceAgreement a;
    a.extracted = extracted.size(), a.truth = truth.size();
    a.precision = share_matched(extracted, heights(truth));
    a.recall = share_matched(truth, heights(extracted));
    return a;
}

}  // namespace driftcorr
