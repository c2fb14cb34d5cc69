// The definitions of what driftcorr/mapping/traversable_field.h declares.
#include "driftcorr/mapping/traversable_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "driftcorr/core/check.h"

namespace driftcorr {

TraversableField::TraversableField(InterpolatedField centre, InterpolatedField corridor,
                                   double truncation_m)
    : grid_(centre.spec()),
      centre_(std::move(centre)),
      corridor_(std::move(corridor)),
      truncation_m_(truncation_m) {
    DRIFTCORR_CHECK(centre_.spec().size() == corridor_.spec().size(), "fields must share one grid");
}

TraversableField::TraversableField(const GridSpec& grid, int tile_cells, std::vector<Tile> tiles,
                                   double truncation_m)
    : grid_(grid), tile_cells_(tile_cells), tiles_(std::move(tiles)), truncation_m_(truncation_m) {
    DRIFTCORR_CHECK(grid_.planar() && tile_cells_ >= 4,
                    "a tiled field is planar, tiles >= 4 cells");
    tiles_x_ = (grid_.nx + tile_cells_ - 1) / tile_cells_;
    tiles_y_ = (grid_.ny + tile_cells_ - 1) / tile_cells_;
    tile_index_.assign(std::size_t(tiles_x_) * std::size_t(tiles_y_), -1);
    for (std::size_t k = 0; k < tiles_.size(); ++k) {
        const Tile& t = tiles_[k];
        DRIFTCORR_CHECK(t.ti >= 0 && t.ti < tiles_x_ && t.tj >= 0 && t.tj < tiles_y_,
                        "tile off the grid");
        int& slot = tile_index_[std::size_t(t.tj) * tiles_x_ + t.ti];
        DRIFTCORR_CHECK(slot < 0, "a tile given twice");
        slot = int(k);
    }
}

std::size_t TraversableField::Samples() const {
    if (!tiled()) return centre_.spec().size();
    std::size_t n = 0;
    for (const Tile& t : tiles_) n += t.centre.spec().size();
    return n;
}

const InterpolatedField& TraversableField::centre() const {
    DRIFTCORR_CHECK(!tiled(), "centre() of a tiled field");
    return centre_;
}

const InterpolatedField& TraversableField::corridor() const {
    DRIFTCORR_CHECK(!tiled(), "corridor() of a tiled field");
    return corridor_;
}

int TraversableField::TileAt(const Eigen::Vector3d& p) const {
    const double tile_m = tile_cells_ * grid_.resolution_m;
    const double gx = std::floor((p.x() - grid_.origin_m.x()) / tile_m);
    const double gy = std::floor((p.y() - grid_.origin_m.y()) / tile_m);
    if (!(gx >= 0.0 && gx < tiles_x_ && gy >= 0.0 && gy < tiles_y_)) return -1;
    return tile_index_[std::size_t(gy) * tiles_x_ + std::size_t(gx)];
}

std::optional<TraversableSample> TraversableField::Query(const Eigen::Vector3d& p_enu) const {
    const InterpolatedField *centre = &centre_, *corridor = &corridor_;
    if (tiled()) {
        const int k = TileAt(p_enu);
        if (k < 0) return std::nullopt;
        centre = &tiles_[k].centre;
        corridor = &tiles_[k].corridor;
    }
    TraversableSample out;
    if (!InterpolatedField::QueryPair(*centre, *corridor, p_enu, out.centre, out.corridor)) {
        return std::nullopt;
    }
    return out;
}

template <typename Fn>
std::optional<FieldSample> TraversableField::QueryOne(const Eigen::Vector3d& p, bool centre,
                                                      Fn query) const {
    if (!tiled()) return query(centre ? centre_ : corridor_, p);
    const int k = TileAt(p);
    if (k < 0) return std::nullopt;
    return query(centre ? tiles_[k].centre : tiles_[k].corridor, p);
}

std::optional<FieldSample> TraversableField::QueryCentre(const Eigen::Vector3d& p_enu) const {
    return QueryOne(p_enu, true, [](const InterpolatedField& f, const Eigen::Vector3d& p) {
        return f.Query(p);
    });
}

std::optional<double> TraversableField::CentreValue(const Eigen::Vector3d& p_enu) const {
    if (!tiled()) return centre_.Value(p_enu);
    const int k = TileAt(p_enu);
    if (k < 0) return std::nullopt;
    return tiles_[k].centre.Value(p_enu);
}

std::optional<double> TraversableField::CorridorValue(const Eigen::Vector3d& p_enu) const {
    if (!tiled()) return corridor_.Value(p_enu);
    const int k = TileAt(p_enu);
    if (k < 0) return std::nullopt;
    return tiles_[k].corridor.Value(p_enu);
}

std::optional<FieldSample> TraversableField::QueryCentreBilinear(
    const Eigen::Vector3d& p_enu) const {
    return QueryOne(p_enu, true, [](const InterpolatedField& f, const Eigen::Vector3d& p) {
        return f.QueryBilinear(p);
    });
}

std::optional<FieldSample> TraversableField::QueryCorridorBilinear(
    const Eigen::Vector3d& p_enu) const {
    return QueryOne(p_enu, false, [](const InterpolatedField& f, const Eigen::Vector3d& p) {
        return f.QueryBilinear(p);
    });
}

void TraversableField::set_lift_shafts(std::vector<ShaftOutline> shafts) {
    for (const ShaftOutline& ring : shafts) {
        DRIFTCORR_CHECK(ring.size() >= 3, "a lift shaft needs 3 corners");
    }
    lift_shafts_ = std::move(shafts);
}

namespace {

// Even-odd rule.
bool Inside(const ShaftOutline& ring, const Eigen::Vector2d& p) {
    bool in = false;
    for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
        const Eigen::Vector2d& a = ring[i];
        const Eigen::Vector2d& b = ring[j];
        if ((a.y() > p.y()) != (b.y() > p.y()) &&
            p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
            in = !in;
        }
    }
    return in;
}

}  // namespace

FieldSample DistanceToShafts(const std::vector<ShaftOutline>& shafts,
                             const Eigen::Vector3d& p_enu) {
    const Eigen::Vector2d p = p_enu.head<2>();
    DRIFTCORR_CHECK(!shafts.empty(), "no lift shaft");
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector2d nearest = p;
    bool corner = false;
    for (const ShaftOutline& ring : shafts) {
        if (Inside(ring, p)) return FieldSample{};
        for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
            const Eigen::Vector2d& a = ring[j];
            const Eigen::Vector2d ab = ring[i] - a;
            const double len2 = ab.squaredNorm();
            const double u = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
            const Eigen::Vector2d q = a + u * ab;
            const double d = (p - q).norm();
            if (d < best) best = d, nearest = q, corner = u <= 0.0 || u >= 1.0;
        }
    }
    FieldSample out;
    out.value = best;
    if (!(best > 0.0)) return out;
    const Eigen::Vector2d g = (p - nearest) / best;
    out.gradient.head<2>() = g;
    if (corner) {
        out.hessian.topLeftCorner<2, 2>() =
            (Eigen::Matrix2d::Identity() - g * g.transpose()) / best;
    }
    return out;
}

void MoveIntoCorridor(const TraversableField& field, TraversableSample sample, double slack_m,
                      Eigen::Vector3d& p_enu) {
    constexpr double kMinSlope = 0.5;
    for (int k = 0; k < 3 && sample.corridor.value > slack_m; ++k) {
        const Eigen::Vector2d g = sample.corridor.gradient.head<2>();
        const double slope = g.norm();
        if (!(slope >= kMinSlope)) break;
        Eigen::Vector3d p = p_enu;
        p.head<2>() -= (sample.corridor.value - slack_m) / slope * (g / slope);
        const auto next = field.Query(p);
        if (!next || !(next->corridor.value < sample.corridor.value)) break;
        p_enu = p;
        sample = *next;
    }
}

}  // namespace driftcorr
