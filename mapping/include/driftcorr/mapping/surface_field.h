#pragma once
// The map prior from a sampled walkable surface (a point cloud of floors, stairs and lift cabin
// floors, or the floor voxels of an OctoMap): a 3D TraversableField, the same interface as the
// floor-plan field of indoor_field.h. Needs no PCL: the points come from any reader (see
// driftcorr_surface_io, surface_io.h).
#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/params.h"
#include "driftcorr/mapping/traversable_field.h"

namespace driftcorr {

/// Config of the surface field. Heights: a surface point at height z (map frame) is walked at
/// z + device_height_m. The default 0 matches scenarios whose trajectory heights are floor
/// heights (the synthetic building's ground truth runs at the floor's height); set it to the
/// device's height above the floor when the trajectory carries the device height.
struct SurfaceFieldConfig {
    /// Horizontal grid spacing [m]. The points must be at least about this dense (every
    /// resolution_m x resolution_m cell of a walkable area must hold a point), else the gaps read
    /// as holes; gaps wider than about 1.5 cells (walls) do read as not walkable.
    double resolution_m = 0.2;
    double resolution_z_m = 0.25;  ///< vertical grid spacing [m]
    double device_height_m = 0.0;  ///< walked surface above the sampled surface [m]
    /// A voxel is traversable when a surface point lies in its column (same horizontal cell)
    /// within this height [m] of the voxel centre. Must be >= resolution_z_m (at least three
    /// layers, so that the cubic B-spline reads the horizontal distance at the surface; see
    /// IndoorFieldConfig::vertical_tolerance_m) and should stay well under half the storey
    /// height, so that the space between floors is not traversable. Sloped surfaces (stairs,
    /// ramps) are traversable when the height step between neighbouring cells,
    /// slope * resolution_m, is under 2 * vertical_tolerance_m (always, for stairs).
    double vertical_tolerance_m = 0.5;
    /// A point cloud has no walkway centre lines, so `centre` is the distance to where a person
    /// walks: on the surface (vertically) and at least wall_clearance_m from the edge of the
    /// walkable area (horizontally): max(distance to the surface, wall_clearance_m + corridor),
    /// floored at 0. It is 0 in open space and grows towards walls and beyond them, so the map
    /// term keeps poses off walls and in the middle of narrow corridors. 0: surface only.
    double wall_clearance_m = 0.8;
    double margin_m = 2.0;           ///< grid extends this far around the points (horizontal) [m]
    double vertical_margin_m = 1.5;  ///< and this far below the lowest, above the highest point [m]
    double truncation_m = 5.0;       ///< distances are capped at this value [m]
    double max_memory_mb = 1024.0;   ///< refuse fields larger than this [MB]
    /// Threads of the map stage: with 2 or more, the two distance transforms (to the surface and
    /// to the traversable set's edge) run side by side, and the pipeline reads the ground truth
    /// beside the estimate and checks the anchor beside the correction; 0: one per core the
    /// process may run on.
    int threads = 0;

    /// The first value kSurfaceFieldParams or vertical_tolerance_m >= resolution_z_m does not
    /// allow.
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "surface_field.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// Params.yaml section `surface_field` (indoor3d point-cloud and OctoMap maps).
inline constexpr Param<SurfaceFieldConfig> kSurfaceFieldParamRows[] = {
    {"resolution_m", Field<&SurfaceFieldConfig::resolution_m>(), kPositive,
     "horizontal grid spacing; the points must be about this dense"},
    {"resolution_z_m", Field<&SurfaceFieldConfig::resolution_z_m>(), kPositive,
     "vertical grid spacing"},
    {"device_height_m", Field<&SurfaceFieldConfig::device_height_m>(), kFinite,
     "walked surface above the sampled surface"},
    {"vertical_tolerance_m", Field<&SurfaceFieldConfig::vertical_tolerance_m>(), kPositive,
     "traversable within this height of a surface point; >= resolution_z_m"},
    {"wall_clearance_m", Field<&SurfaceFieldConfig::wall_clearance_m>(), kNonNegative,
     "the map term keeps poses this far from the edge of the walkable area; 0: surface only"},
    {"margin_m", Field<&SurfaceFieldConfig::margin_m>(), kNonNegative,
     "the grid extends this far around the points (horizontal)"},
    {"vertical_margin_m", Field<&SurfaceFieldConfig::vertical_margin_m>(), kNonNegative,
     "and this far below the lowest, above the highest point"},
    {"truncation_m", Field<&SurfaceFieldConfig::truncation_m>(), kPositive,
     "distances are capped at this value"},
    {"max_memory_mb", Field<&SurfaceFieldConfig::max_memory_mb>(), kPositive,
     "refuse fields larger than this"},
    {"threads", Field<&SurfaceFieldConfig::threads>(), kNonNegative,
     "threads of the map stage (2: both distance transforms at once); 0: one per core"},
};
inline constexpr ParamTable<SurfaceFieldConfig> kSurfaceFieldParams{"surface_field",
                                                                    kSurfaceFieldParamRows};

/// What was built.
struct SurfaceFieldStats {
    std::size_t points = 0;              ///< surface points given
    std::size_t voxels = 0;              ///< grid size
    std::size_t surface_voxels = 0;      ///< voxels holding a surface point (the centre seeds)
    std::size_t traversable_voxels = 0;  ///< the traversable set
};

/// Builds the field over the points' bounding box grown by margin_m (and vertical_margin_m).
/// Each point p (map frame, metres) is lifted to p + device_height_m in z and falls into the
/// voxel column of its nearest horizontal sample; its surface voxel is the nearest layer.
///  - traversable set: the voxels of the point's column within vertical_tolerance_m of its
///    height (at least its surface voxel). Floors are layers, stairs sloped bands of layers, a
///    lift shaft sampled at many cabin heights a column; the space between floors is not
///    traversable.
///  - corridor: outside the set, the 3D distance to it; inside, minus the horizontal distance to
///    the set's edge at that height (walls are gaps in the points). Zero level between the last
///    inside and the first outside voxel; truncated at +/- truncation_m.
///  - centre: 3D distance to the nearest surface voxel, truncated at truncation_m.
/// Both are interpolated by the cubic B-spline of InterpolatedField (value and gradient
/// continuous). Throws std::invalid_argument when the config is invalid, there is no point, a
/// point is not finite, or the grid would exceed max_memory_mb (the message names the horizontal
/// resolution that would fit).
TraversableField BuildSurfaceField(const std::vector<Eigen::Vector3d>& surface_points_enu,
                                   const SurfaceFieldConfig& config,
                                   SurfaceFieldStats* stats = nullptr);

}  // namespace driftcorr
