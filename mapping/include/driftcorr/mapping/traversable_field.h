#pragma once
// The map prior as a field: where a platform can be. One interface serves the planar road mode
// (a one-slice grid) and the 3D indoor mode.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

#include "driftcorr/mapping/interpolated_field.h"

namespace driftcorr {

/// Two interpolated fields sampled together at a point (world ENU frame, metres):
///  - centre: distance to the nearest traversable centre (road centre line, walkway), truncated;
///  - corridor: signed distance to the traversable corridor's edge (negative inside the road or
///    walkable area, positive outside), truncated at +/- truncation.
struct TraversableSample {
    FieldSample centre;
    FieldSample corridor;
};

/// A lift shaft: its outline in the East-North plane [m]; it joins every floor of the map.
using ShaftOutline = std::vector<Eigen::Vector2d>;

/// Horizontal distance from p to the nearest of `shafts` (0 inside one, gradient and Hessian zero
/// there), as a sample over (east, north, up) whose up components are zero: the nearest outline
/// point's direction as gradient, Hessian zero along an edge and (I - g g^T) / d at a corner.
/// Precondition: !shafts.empty(), each with 3 or more corners.
FieldSample DistanceToShafts(const std::vector<ShaftOutline>& shafts, const Eigen::Vector3d& p);

class TraversableField {
public:
    /// One square tile of a tiled field: tile (ti, tj) covers the samples
    /// [ti * tile_cells, (ti + 1) * tile_cells) x [tj * tile_cells, (tj + 1) * tile_cells) of the
    /// field's grid; its own grid holds them plus two samples on every side (clipped to the
    /// field's grid), so that the B-spline support of any point of the tile fits.
    struct Tile {
        int ti = 0, tj = 0;
        InterpolatedField centre, corridor;
    };

    TraversableField() = default;
    /// One grid. Precondition: both fields share one GridSpec.
    TraversableField(InterpolatedField centre, InterpolatedField corridor, double truncation_m);
    /// A planar field held as tiles of `grid` (tile_cells samples a side); a tile that is absent
    /// is outside the map. Preconditions: grid.planar(), tile_cells >= 4, each tile's fields
    /// share one GridSpec aligned with `grid`, no tile twice.
    TraversableField(const GridSpec& grid, int tile_cells, std::vector<Tile> tiles,
                     double truncation_m);

    /// std::nullopt outside the grid (closer than one cell to its border) or in an absent tile.
    std::optional<TraversableSample> Query(const Eigen::Vector3d& p_enu) const;
    /// The centre distance alone (B-spline), std::nullopt where Query has none.
    std::optional<FieldSample> QueryCentre(const Eigen::Vector3d& p_enu) const;
    /// QueryCentre's value alone (the same number), without the derivatives.
    std::optional<double> CentreValue(const Eigen::Vector3d& p_enu) const;
    /// Query's corridor value alone (the same number), without the derivatives.
    std::optional<double> CorridorValue(const Eigen::Vector3d& p_enu) const;
    /// InterpolatedField::QueryBilinear of the centre / corridor distance (the paper's method).
    std::optional<FieldSample> QueryCentreBilinear(const Eigen::Vector3d& p_enu) const;
    std::optional<FieldSample> QueryCorridorBilinear(const Eigen::Vector3d& p_enu) const;

    /// The lift shafts of the map (the lifts of an indoor map's plans, or those a surface layer
    /// declares; none for roads): where a walker who rides a lift stands.
    const std::vector<ShaftOutline>& lift_shafts() const { return lift_shafts_; }
    /// Precondition: each shaft has 3 or more corners.
    void set_lift_shafts(std::vector<ShaftOutline> shafts);
    /// The heights a walker's device has on the map's floors (each floor's height plus the
    /// device's above it; an indoor map of floor plans; none for roads and surface maps) [m].
    const std::vector<double>& floor_heights_m() const { return floor_heights_m_; }
    void set_floor_heights_m(std::vector<double> heights) { floor_heights_m_ = std::move(heights); }

    /// The grid the field's samples lie on (for a tiled field: the grid its tiles are cut from).
    const GridSpec& spec() const { return grid_; }
    bool planar() const { return spec().planar(); }
    bool empty() const { return Samples() == 0; }
    bool tiled() const { return tile_cells_ > 0; }
    /// Samples held (a tiled field: in its tiles, including their borders).
    std::size_t Samples() const;
    double truncation_m() const { return truncation_m_; }
    /// The fields of a field held as one grid. Precondition: !tiled().
    const InterpolatedField& centre() const;
    const InterpolatedField& corridor() const;

private:
    /// The tile's index in tiles_ for p, or -1 (outside the grid or absent).
    int TileAt(const Eigen::Vector3d& p) const;
    template <typename Fn>
    std::optional<FieldSample> QueryOne(const Eigen::Vector3d& p, bool centre, Fn query) const;

    GridSpec grid_;
    InterpolatedField centre_;
    InterpolatedField corridor_;
    int tile_cells_ = 0;  ///< 0: one grid (centre_, corridor_)
    int tiles_x_ = 0, tiles_y_ = 0;
    std::vector<int> tile_index_;  ///< tiles_x_ * tiles_y_, index into tiles_ or -1
    std::vector<Tile> tiles_;
    double truncation_m_ = 0.0;
    std::vector<ShaftOutline> lift_shafts_;
    std::vector<double> floor_heights_m_;
};

/// Moves `p_enu` horizontally towards the corridor when its signed corridor distance `sample`
/// (the field's value at p_enu) exceeds slack_m: at most 3 Newton steps along the distance's
/// horizontal gradient to slack_m, each taken only where that slope is at least 0.5 (where the
/// distance falls mostly with height, between floors or on stairs, a step along a small slope
/// would be long; the excess over slack_m bounds a step at twice it) and kept only where it
/// lowers the distance.
void MoveIntoCorridor(const TraversableField& field, TraversableSample sample, double slack_m,
                      Eigen::Vector3d& p_enu);

/// How well a set of points lies on the traversable centres: the share of them farther than
/// reach_m from every centre (or outside the field), and their RMS distance, each capped at
/// reach_m (a negative interpolated distance counts as 0).
struct CentreFit {
    double rms_m = 0.0;
    double off_share = 0.0;
};

/// CentreFit of the n points point_of(0) .. point_of(n - 1) (East, North, Up) [m].
template <class PointOf>
CentreFit FitToCentres(const TraversableField& field, std::size_t n, double reach_m,
                       PointOf&& point_of) {
    double sum = 0.0;
    std::size_t off = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const std::optional<double> q = field.CentreValue(point_of(k));
        const double d = q ? std::min(std::max(*q, 0.0), reach_m) : reach_m;
        if (!q || *q > reach_m) ++off;
        sum += d * d;
    }
    const double count = double(std::max<std::size_t>(1, n));
    return {std::sqrt(sum / count), double(off) / count};
}

}  // namespace driftcorr
