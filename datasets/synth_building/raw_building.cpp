// The definitions of what raw_building.h declares.
#include "raw_building.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

#include "driftcorr/core/check.h"
#include "synth_common.h"

namespace driftcorr::synth {
namespace {

using Points = std::vector<Eigen::Vector3d>;

constexpr double kFootprintX_m = 60.0, kFootprintY_m = 30.0;  // as SampleSurface
constexpr double kRiserTarget_m = 0.18;     // the riser count is rounded to divide the rise
constexpr double kUndersideDepth_m = 0.25;  // flight underside below the stair line
constexpr double kLiftDoorHeight_m = 2.1;   // the open landing door at the cabin's level
constexpr double kMinRoomSide_m = 5.0;      // a slab at least this wide both ways is a room
constexpr double kDoorClearance_m = 1.5;    // furniture footprint to any door slab
constexpr double kFurnitureGap_m = 0.6;     // table footprint to cabinet footprint
constexpr double kTableWallMargin_m = 0.4;  // table footprint to the room's edges
constexpr double kCabinetWallGap_m = 0.02;  // cabinet back to its wall
constexpr double kTableLong_m = 1.2, kTableShort_m = 0.8, kLegInset_m = 0.05;
constexpr double kCabinetLong_m = 1.0, kCabinetDepth_m = 0.5;
constexpr double kHoleRadiusMin_m = 0.3, kHoleRadiusMax_m = 1.0;
constexpr int kMaxPlacementTries = 10000;
constexpr std::uint64_t kFurnitureStream = 1, kHoleStream = 2, kDropoutStream = 3;
constexpr std::uint64_t kNoiseStream = 4;

/// What a lattice cell is; the order is the priority of a boundary face's owner.
enum class Cell : unsigned char { kSolid, kSlab, kStair, kLift };

struct Lattice {
    double s = 0.0;
    int ni = 0, nj = 0;
    std::vector<Cell> cells;
    double C(int i) const { return s * (i + 0.5); }
    Cell At(int i, int j) const { return cells[std::size_t(j) * std::size_t(ni) + std::size_t(i)]; }
};

Cell CellAt(const BuildingLayout& b, double x, double y) {
    if (b.lift.Contains(x, y)) return Cell::kLift;
    if (b.stair.Contains(x, y)) return Cell::kStair;
    for (const Rect& r : b.slabs) {
        if (r.Contains(x, y)) return Cell::kSlab;
    }
    return Cell::kSolid;
}

Lattice MakeLattice(const BuildingLayout& b, double spacing_m) {
    Lattice lat;
    lat.s = spacing_m;
    lat.ni = int(std::lround(kFootprintX_m / spacing_m));
    lat.nj = int(std::lround(kFootprintY_m / spacing_m));
    lat.cells.reserve(std::size_t(lat.ni) * std::size_t(lat.nj));
    for (int j = 0; j < lat.nj; ++j) {
        for (int i = 0; i < lat.ni; ++i) lat.cells.push_back(CellAt(b, lat.C(i), lat.C(j)));
    }
    return lat;
}

/// Evenly spread samples strictly inside (lo, hi), about spacing_m apart (at least one).
std::vector<double> Samples(double lo, double hi, double spacing_m) {
    if (!(hi > lo)) return {};
    const int n = std::max(1, int(std::lround((hi - lo) / spacing_m)));
    std::vector<double> v(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) v[std::size_t(k)] = lo + (k + 0.5) * (hi - lo) / n;
    return v;
}

void AddVerticalLine(double x, double y, double z_lo, double z_hi, double s, Points& out) {
    for (double z : Samples(z_lo, z_hi, s)) out.emplace_back(x, y, z);
}

void AddHorizontalRect(const Rect& r, double z, double s, Points& out) {
    for (double y : Samples(r.y0, r.y1, s)) {
        for (double x : Samples(r.x0, r.x1, s)) out.emplace_back(x, y, z);
    }
}

/// The four vertical sides of a box over `r` from z_lo to z_hi.
void AddBoxSides(const Rect& r, double z_lo, double z_hi, double s, Points& out) {
    for (double x : Samples(r.x0, r.x1, s)) {
        AddVerticalLine(x, r.y0, z_lo, z_hi, s, out);
        AddVerticalLine(x, r.y1, z_lo, z_hi, s, out);
    }
    for (double y : Samples(r.y0, r.y1, s)) {
        AddVerticalLine(r.x0, y, z_lo, z_hi, s, out);
        AddVerticalLine(r.x1, y, z_lo, z_hi, s, out);
    }
}

double RectGap(const Rect& a, const Rect& b) {
    const double dx = std::max({0.0, a.x0 - b.x1, b.x0 - a.x1});
    const double dy = std::max({0.0, a.y0 - b.y1, b.y0 - a.y1});
    return std::hypot(dx, dy);
}

double CeilingZ(const BuildingLayout& b, const RawScanConfig& cfg, std::size_t f) {
    return f + 1 == b.floor_z_m.size() ? cfg.roof_z_m : b.floor_z_m[f] + cfg.ceiling_height_m;
}

/// One flight as treads and risers: n risers of height h over a run of n treads of depth d,
/// tread k centred at x0 + k d at height z0 + k h (half treads at both ends), so the clean
/// flight's line passes through the tread centres.
struct Flight {
    double x0 = 0.0, x1 = 0.0, z0 = 0.0, d = 0.0, h = 0.0;
    int n = 0;

    Flight(const BuildingLayout& b, int f) : x0(b.stair.x0), x1(b.stair.x1), z0(b.floor_z_m[f]) {
        const double rise_m = b.floor_z_m[f + 1] - z0;
        n = std::max(1, int(std::lround(rise_m / kRiserTarget_m)));
        d = (x1 - x0) / n;
        h = rise_m / n;
    }
    double TreadZ(double x) const {
        return z0 + h * std::clamp(double(std::lround((x - x0) / d)), 0.0, double(n));
    }
    double LineZ(double x) const { return z0 + h * (x - x0) / d; }
};

// ---------------------------------------------------------------- furniture

std::vector<Rect> DoorsOf(const BuildingLayout& b, std::size_t room) {
    std::vector<Rect> doors;
    for (std::size_t k = 0; k < b.slabs.size(); ++k) {
        if (k != room && RectGap(b.slabs[room], b.slabs[k]) <= 1e-9) doors.push_back(b.slabs[k]);
    }
    return doors;
}

bool ClearOf(const Rect& r, const std::vector<Rect>& doors) {
    for (const Rect& door : doors) {
        if (RectGap(r, door) < kDoorClearance_m) return false;
    }
    return true;
}

Rect CentredRect(double cx, double cy, double wx, double wy) {
    return {cx - 0.5 * wx, cy - 0.5 * wy, cx + 0.5 * wx, cy + 0.5 * wy};
}

Rect PlaceTable(const Rect& room, const std::vector<Rect>& doors, UniformSampler& random) {
    for (int t = 0; t < kMaxPlacementTries; ++t) {
        const bool long_along_x = random.Next01() < 0.5;
        const double wx = long_along_x ? kTableLong_m : kTableShort_m;
        const double wy = long_along_x ? kTableShort_m : kTableLong_m;
        const double mx = kTableWallMargin_m + 0.5 * wx, my = kTableWallMargin_m + 0.5 * wy;
        const Rect table = CentredRect(random.Range(room.x0 + mx, room.x1 - mx),
                                       random.Range(room.y0 + my, room.y1 - my), wx, wy);
        if (ClearOf(table, doors)) return table;
    }
    DRIFTCORR_CHECK(false, "PlaceTable: no place 1.5 m from the doors");
    return {};
}

/// A cabinet with its back kCabinetWallGap_m off one of the room's four walls, its long side
/// along that wall, at least 0.1 m from the corners.
Rect CabinetAtWall(const Rect& room, int wall, UniformSampler& random) {
    const double g = kCabinetWallGap_m, dep = kCabinetDepth_m, m = 0.1 + 0.5 * kCabinetLong_m;
    if (wall < 2) {  // south or north wall: long side along x
        const double cx = random.Range(room.x0 + m, room.x1 - m);
        const double cy = wall == 0 ? room.y0 + g + 0.5 * dep : room.y1 - g - 0.5 * dep;
        return CentredRect(cx, cy, kCabinetLong_m, dep);
    }
    const double cy = random.Range(room.y0 + m, room.y1 - m);
    const double cx = wall == 2 ? room.x0 + g + 0.5 * dep : room.x1 - g - 0.5 * dep;
    return CentredRect(cx, cy, dep, kCabinetLong_m);
}

Rect PlaceCabinet(const Rect& room, const std::vector<Rect>& doors, const Rect& table,
                  UniformSampler& random) {
    for (int t = 0; t < kMaxPlacementTries; ++t) {
        const Rect cabinet = CabinetAtWall(room, int(random.Index(4)), random);
        if (ClearOf(cabinet, doors) && RectGap(cabinet, table) >= kFurnitureGap_m) return cabinet;
    }
    DRIFTCORR_CHECK(false, "PlaceCabinet: no place at a wall 1.5 m from the doors");
    return {};
}

void AddFurniture(const BuildingLayout& b, const RoomFurniture& f, double s, Points& out) {
    const double z = b.floor_z_m[std::size_t(f.floor)];
    const Rect& t = f.table;
    AddHorizontalRect(t, z + kTableTopHeight_m, s, out);
    for (double x : {t.x0 + kLegInset_m, t.x1 - kLegInset_m}) {
        for (double y : {t.y0 + kLegInset_m, t.y1 - kLegInset_m}) {
            AddVerticalLine(x, y, z, z + kTableTopHeight_m, s, out);
        }
    }
    AddHorizontalRect(f.cabinet, z + kCabinetHeight_m, s, out);
    AddBoxSides(f.cabinet, z, z + kCabinetHeight_m, s, out);
}

// ---------------------------------------------------------------- floors, ceilings, lift

bool UnderCabinet(const std::vector<RoomFurniture>& furniture, std::size_t f, double x, double y) {
    for (const RoomFurniture& rf : furniture) {
        if (std::size_t(rf.floor) == f && rf.cabinet.Contains(x, y)) return true;
    }
    return false;
}

/// Slab floor points of every floor, none under a cabinet.
Points SlabFloors(const BuildingLayout& b, const Lattice& lat,
                  const std::vector<RoomFurniture>& furniture) {
    Points out;
    for (std::size_t f = 0; f < b.floor_z_m.size(); ++f) {
        for (int j = 0; j < lat.nj; ++j) {
            for (int i = 0; i < lat.ni; ++i) {
                if (lat.At(i, j) != Cell::kSlab) continue;
                if (UnderCabinet(furniture, f, lat.C(i), lat.C(j))) continue;
                out.emplace_back(lat.C(i), lat.C(j), b.floor_z_m[f]);
            }
        }
    }
    return out;
}

void AddCeilingsAndCabin(const BuildingLayout& b, const RawScanConfig& cfg, const Lattice& lat,
                         Points& out) {
    const std::size_t top = b.floor_z_m.size() - 1;
    for (std::size_t f = 0; f <= top; ++f) {
        for (int j = 0; j < lat.nj; ++j) {
            for (int i = 0; i < lat.ni; ++i) {
                const Cell c = lat.At(i, j);
                if (c == Cell::kSlab || (f == top && c != Cell::kSolid)) {
                    out.emplace_back(lat.C(i), lat.C(j), CeilingZ(b, cfg, f));
                }
            }
        }
    }
    for (int j = 0; j < lat.nj; ++j) {  // the cabin floor at the lowest floor only
        for (int i = 0; i < lat.ni; ++i) {
            if (lat.At(i, j) == Cell::kLift) out.emplace_back(lat.C(i), lat.C(j), b.floor_z_m[0]);
        }
    }
}

// ---------------------------------------------------------------- walls

/// The coordinate (along `axis`) of the edge of the region of `owner`, whose cell centre is
/// `p`, towards +axis (`positive`) or -axis: the rectangle's edge, for slabs the farthest edge
/// among the slabs that contain p.
double FaceCoordinate(const BuildingLayout& b, Cell owner, const Eigen::Vector2d& p, int axis,
                      bool positive) {
    auto edge = [&](const Rect& r) {
        return axis == 0 ? (positive ? r.x1 : r.x0) : (positive ? r.y1 : r.y0);
    };
    if (owner == Cell::kLift) return edge(b.lift);
    if (owner == Cell::kStair) return edge(b.stair);
    double best = positive ? -1e300 : 1e300;
    for (const Rect& r : b.slabs) {
        if (!r.Contains(p.x(), p.y())) continue;
        best = positive ? std::max(best, edge(r)) : std::min(best, edge(r));
    }
    return best;
}

/// Height intervals of the face between a cell of `owner` and one of `other` (owner > other).
std::vector<std::pair<double, double>> FaceSpans(const BuildingLayout& b, const RawScanConfig& cfg,
                                                 Cell owner, Cell other) {
    const double z_lo = b.floor_z_m.front();
    if (owner == Cell::kSlab) {  // other is solid: a wall on every floor
        std::vector<std::pair<double, double>> spans;
        for (std::size_t f = 0; f < b.floor_z_m.size(); ++f) {
            spans.emplace_back(b.floor_z_m[f], CeilingZ(b, cfg, f));
        }
        return spans;
    }
    if (owner == Cell::kLift && other == Cell::kSlab) {  // landing doors, open at the cabin
        return {{z_lo + kLiftDoorHeight_m, cfg.roof_z_m}};
    }
    if (owner == Cell::kStair && other == Cell::kSlab) return {};  // open; see AddStringers
    return {{z_lo, cfg.roof_z_m}};                                 // stairwell and shaft walls
}

void AddWalls(const BuildingLayout& b, const RawScanConfig& cfg, const Lattice& lat, Points& out) {
    for (int j = 0; j < lat.nj; ++j) {
        for (int i = 0; i < lat.ni; ++i) {
            for (int axis = 0; axis < 2; ++axis) {
                const int i2 = i + (axis == 0), j2 = j + (axis == 1);
                if (i2 >= lat.ni || j2 >= lat.nj) continue;
                const Cell a = lat.At(i, j), c = lat.At(i2, j2);
                if (a == c) continue;
                const bool first_owns = a > c;  // the owner's region ends at the face
                const Cell owner = first_owns ? a : c;
                const Eigen::Vector2d p = first_owns ? Eigen::Vector2d(lat.C(i), lat.C(j))
                                                     : Eigen::Vector2d(lat.C(i2), lat.C(j2));
                Eigen::Vector2d q = p;
                q[axis] = FaceCoordinate(b, owner, p, axis, first_owns);
                for (const auto& [lo, hi] : FaceSpans(b, cfg, owner, first_owns ? c : a)) {
                    AddVerticalLine(q.x(), q.y(), lo, hi, lat.s, out);
                }
            }
        }
    }
}

// ---------------------------------------------------------------- stairs

void AddFlight(const BuildingLayout& b, const Lattice& lat, int f, Points& out) {
    const Flight fl(b, f);
    const double z_ground = b.floor_z_m.front();
    for (int j = 0; j < lat.nj; ++j) {
        for (int i = 0; i < lat.ni; ++i) {
            if (lat.At(i, j) != Cell::kStair) continue;
            const double x = lat.C(i), y = lat.C(j);
            out.emplace_back(x, y, fl.TreadZ(x));
            const double z_under = fl.LineZ(x) - kUndersideDepth_m;
            if (z_under > z_ground) out.emplace_back(x, y, z_under);
        }
    }
    for (int k = 0; k < fl.n; ++k) {
        const double x_riser = fl.x0 + (k + 0.5) * fl.d;
        for (int j = 0; j < lat.nj; ++j) {
            if (!b.stair.Contains(x_riser, lat.C(j))) continue;
            AddVerticalLine(x_riser, lat.C(j), fl.z0 + k * fl.h, fl.z0 + (k + 1) * fl.h, lat.s,
                            out);
        }
    }
}

/// The side face of every flight (from its underside, or the lowest floor, up to the tread)
/// where the stair borders a slab across y (an open side; the landings at its ends are open).
void AddStringers(const BuildingLayout& b, const Lattice& lat, Points& out) {
    const double z_ground = b.floor_z_m.front();
    for (int j = 0; j < lat.nj; ++j) {
        for (int i = 0; i < lat.ni; ++i) {
            if (lat.At(i, j) != Cell::kStair) continue;
            for (int dj : {-1, 1}) {
                if (j + dj < 0 || j + dj >= lat.nj || lat.At(i, j + dj) != Cell::kSlab) continue;
                const double y = dj > 0 ? b.stair.y1 : b.stair.y0, x = lat.C(i);
                for (int f = 0; f + 1 < int(b.floor_z_m.size()); ++f) {
                    const Flight fl(b, f);
                    const double z_lo = std::max(z_ground, fl.LineZ(x) - kUndersideDepth_m);
                    AddVerticalLine(x, y, z_lo, fl.TreadZ(x), lat.s, out);
                }
            }
        }
    }
}

// ---------------------------------------------------------------- holes, dropout, noise

/// Removes discs (radius uniform in [0.3, 1.0] m, centred on a random floor point, on that
/// point's floor) until at least `share` of the points are gone.
Points CutHoles(const Points& floor, double share, UniformSampler& random) {
    std::vector<char> removed(floor.size(), 0);
    const auto target = std::size_t(std::ceil(share * double(floor.size())));
    std::size_t count = 0;
    while (count < target) {
        const Eigen::Vector3d& c = floor[random.Index(floor.size())];
        const double r = random.Range(kHoleRadiusMin_m, kHoleRadiusMax_m);
        for (std::size_t k = 0; k < floor.size(); ++k) {
            if (removed[k] || floor[k].z() != c.z()) continue;
            if ((floor[k] - c).head<2>().squaredNorm() > r * r) continue;
            removed[k] = 1;
            ++count;
        }
    }
    Points kept;
    kept.reserve(floor.size() - count);
    for (std::size_t k = 0; k < floor.size(); ++k) {
        if (!removed[k]) kept.push_back(floor[k]);
    }
    return kept;
}

Points DropAndPerturb(const Points& points, const RawScanConfig& cfg) {
    UniformSampler dropout(cfg.seed, kDropoutStream);
    NormalSampler noise(cfg.seed * 0x9E3779B97F4A7C15ULL + kNoiseStream);
    Points out;
    out.reserve(points.size());
    for (const Eigen::Vector3d& p : points) {
        if (dropout.Next01() < cfg.dropout) continue;
        const Eigen::Vector3d n(noise.Next(), noise.Next(), noise.Next());
        out.push_back(p + cfg.noise_sigma_m * n);
    }
    return out;
}

}  // namespace

std::string RawScanConfig::Validate() const {
    if (!(spacing_m > 0.01 && spacing_m <= 0.5)) return "spacing_m: must be in (0.01, 0.5]";
    if (!(noise_sigma_m >= 0.0 && noise_sigma_m <= 0.1)) {
        return "noise_sigma_m: must be in [0, 0.1]";
    }
    if (!(dropout >= 0.0 && dropout < 1.0)) return "dropout: must be in [0, 1)";
    if (!(hole_share >= 0.0 && hole_share <= 0.5)) return "hole_share: must be in [0, 0.5]";
    if (!(ceiling_height_m >= 2.2 && ceiling_height_m <= 10.0)) {
        return "ceiling_height_m: must be in [2.2, 10]";
    }
    if (!std::isfinite(roof_z_m)) return "roof_z_m: must be finite";
    return "";
}

std::vector<RoomFurniture> PlaceFurniture(const BuildingLayout& b, const RawScanConfig& config) {
    DRIFTCORR_CHECK(config.Validate().empty(), "PlaceFurniture: invalid config");
    UniformSampler random(config.seed, kFurnitureStream);
    std::vector<RoomFurniture> furniture;
    for (std::size_t f = 0; f < b.floor_z_m.size(); ++f) {
        for (std::size_t k = 0; k < b.slabs.size(); ++k) {
            const Rect& room = b.slabs[k];
            if (room.x1 - room.x0 < kMinRoomSide_m || room.y1 - room.y0 < kMinRoomSide_m) continue;
            const std::vector<Rect> doors = DoorsOf(b, k);
            RoomFurniture rf;
            rf.floor = int(f);
            rf.room = room;
            rf.table = PlaceTable(room, doors, random);
            rf.cabinet = PlaceCabinet(room, doors, rf.table, random);
            furniture.push_back(rf);
        }
    }
    return furniture;
}

std::vector<Eigen::Vector3d> SampleRawBuilding(const BuildingLayout& b,
                                               const RawScanConfig& config) {
    DRIFTCORR_CHECK(config.Validate().empty(), "SampleRawBuilding: invalid config");
    DRIFTCORR_CHECK(!b.floor_z_m.empty(), "SampleRawBuilding: no floor");
    for (std::size_t f = 0; f + 1 < b.floor_z_m.size(); ++f) {
        DRIFTCORR_CHECK(b.floor_z_m[f + 1] - b.floor_z_m[f] > config.ceiling_height_m,
                        "SampleRawBuilding: floors must ascend by more than the ceiling height");
    }
    DRIFTCORR_CHECK(config.roof_z_m > b.floor_z_m.back() + 2.2,
                    "SampleRawBuilding: roof_z_m must be more than 2.2 m above the top floor");
    const Lattice lat = MakeLattice(b, config.spacing_m);
    const std::vector<RoomFurniture> furniture = PlaceFurniture(b, config);
    UniformSampler hole_random(config.seed, kHoleStream);
    Points points = CutHoles(SlabFloors(b, lat, furniture), config.hole_share, hole_random);
    AddCeilingsAndCabin(b, config, lat, points);
    AddWalls(b, config, lat, points);
    for (int f = 0; f + 1 < int(b.floor_z_m.size()); ++f) AddFlight(b, lat, f, points);
    AddStringers(b, lat, points);
    for (const RoomFurniture& rf : furniture) AddFurniture(b, rf, config.spacing_m, points);
    return DropAndPerturb(points, config);
}

}  // namespace driftcorr::synth
