#pragma once
// The indoor map prior as a 3D field: where a person's device can be in a building of several
// floors. Built as voxel fields (exact 3D EDT), B-spline interpolated: value and gradient are
// continuous. The result is a TraversableField with nz > 1, the same interface as the planar
// road field (which is its one-slice case).
#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/params.h"
#include "driftcorr/mapping/traversable_field.h"

namespace driftcorr {

/// A polygon with holes in the local East-North frame [m].
struct FloorPolygon {
    std::vector<Eigen::Vector2d> outer_en;
    std::vector<std::vector<Eigen::Vector2d>> holes_en;
};

/// One floor of the building, in the local East-North frame [m].
struct IndoorFloor {
    /// Height of the floor in the map's height datum [m] (the scenario's `floor_z_m`).
    double floor_z_m = 0.0;
    std::vector<std::vector<Eigen::Vector2d>> walkways_en;  ///< walkway centre lines
    std::vector<FloorPolygon> walkable;  ///< rooms, corridors, balconies: a person can stand here
    std::vector<FloorPolygon> doors;     ///< walkable, and cut back into walls (doors join rooms)
    std::vector<FloorPolygon> stairs;    ///< walkable, and join this floor to its neighbours
    std::vector<FloorPolygon> lifts;     ///< walkable, and join this floor to its neighbours
    std::vector<FloorPolygon> walls;     ///< not walkable: cut out of the walkable polygons
};

/// Config of the indoor field. Heights: the traversable surface of floor f lies at
/// floor_z_m + device_height_m. The scenario's `floor_z_m` is the height at which the
/// trajectory runs on that floor (for hcu_eight the surveyed waypoint heights; its ground truth
/// keeps z = 19.6 m = floor_z_m of the 4OG throughout), so the default device_height_m is 0.
/// Set it to the height of the device above the floor when the layers give floor-slab heights.
struct IndoorFieldConfig {
    double resolution_m = 0.1;     ///< horizontal grid spacing [m]
    double resolution_z_m = 0.5;   ///< vertical grid spacing [m]
    double device_height_m = 0.0;  ///< traversable surface above floor_z_m [m]
    /// The walkable layer spans the surface +/- this [m] (PDR and barometric heights wander by
    /// about half a metre; a hand-held device is not always at one height). Must be >=
    /// resolution_z_m: the cubic B-spline at a sample height weighs the samples one layer above
    /// and below by 1/6 each, so a one-voxel layer would read about 2/3 of the horizontal
    /// distance at the surface; with at least three layers it reads the horizontal distance.
    double vertical_tolerance_m = 0.5;
    double walkway_half_width_m = 0.5;  ///< traversable within this distance of a walkway line [m]
    double margin_m = 2.0;              ///< grid extends this far around the map (horizontal) [m]
    double vertical_margin_m = 1.5;     ///< and this far below the lowest, above the highest floor
    double truncation_m = 5.0;          ///< distances are capped at this value [m]
    /// A corrected walk's field serves the heights of its estimate grown by half their range
    /// and by this (BuildIndoorField's `heights`); far beyond them it reads outside the map.
    /// Half the range: the floor hypotheses read a height change at most 1.4x; this margin: a
    /// level walk's corrected height stays within decimetres of its estimate [m]
    double height_margin_m = 3.0;
    double exact_band_m = 1.0;      ///< exact walkway distances within this band; EDT beyond [m]
    double max_memory_mb = 1024.0;  ///< refuse fields larger than this [MB]
    /// Threads of the map stage: with 2 or more, the two distance transforms (to the walkways
    /// and to the walkable area's edge) run side by side, and the pipeline reads the ground truth
    /// beside the estimate and checks the anchor beside the correction; 0: one per core the
    /// process may run on.
    int threads = 0;

    /// The first value kIndoorFieldParams or vertical_tolerance_m >= resolution_z_m does not
    /// allow.
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "indoor_field.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// Params.yaml section `indoor_field` (indoor3d GeoJSON floor plans).
inline constexpr Param<IndoorFieldConfig> kIndoorFieldParamRows[] = {
    {"resolution_m", Field<&IndoorFieldConfig::resolution_m>(), kPositive,
     "horizontal grid spacing"},
    {"resolution_z_m", Field<&IndoorFieldConfig::resolution_z_m>(), kPositive,
     "vertical grid spacing"},
    {"device_height_m", Field<&IndoorFieldConfig::device_height_m>(), kFinite,
     "traversable surface above floor_z_m"},
    {"vertical_tolerance_m", Field<&IndoorFieldConfig::vertical_tolerance_m>(), kPositive,
     "the walkable layer spans the surface +/- this; >= resolution_z_m"},
    {"walkway_half_width_m", Field<&IndoorFieldConfig::walkway_half_width_m>(), kNonNegative,
     "traversable within this distance of a walkway line"},
    {"margin_m", Field<&IndoorFieldConfig::margin_m>(), kNonNegative,
     "the grid extends this far around the map (horizontal)"},
    {"vertical_margin_m", Field<&IndoorFieldConfig::vertical_margin_m>(), kNonNegative,
     "and this far below the lowest, above the highest floor"},
    {"truncation_m", Field<&IndoorFieldConfig::truncation_m>(), kPositive,
     "distances are capped at this value"},
    {"height_margin_m", Field<&IndoorFieldConfig::height_margin_m>(), kNonNegative,
     "a walk's field spans its estimated heights grown by half their range and this"},
    {"exact_band_m", Field<&IndoorFieldConfig::exact_band_m>(), kNonNegative,
     "exact walkway distances within this band; EDT beyond"},
    {"max_memory_mb", Field<&IndoorFieldConfig::max_memory_mb>(), kPositive,
     "refuse fields larger than this"},
    {"threads", Field<&IndoorFieldConfig::threads>(), kNonNegative,
     "threads of the map stage (2: both distance transforms at once); 0: one per core"},
};
inline constexpr ParamTable<IndoorFieldConfig> kIndoorFieldParams{"indoor_field",
                                                                  kIndoorFieldParamRows};

/// What was built.
struct IndoorFieldStats {
    std::size_t voxels = 0;
    std::vector<double> walkable_area_m2;  ///< per floor (input order): traversable area of its
                                           ///< layer (polygons, walkway buffers, connectors)
    std::size_t connector_voxels = 0;      ///< stair and lift voxels between floors
};

/// Heights [m]: where a walk's field is read.
struct HeightRange {
    double lo_m = 0.0, hi_m = 0.0;
};

/// Builds the field over the floors' extent grown by margin_m; with `heights`, only the layers
/// within truncation_m plus two layers of them: at every height of `heights` the field gives the
/// whole building's values, beyond them up to that reach values at least as large, and beyond
/// the reach it reads outside the map. The memory cap applies to the layers built.
/// Traversable set: on each floor's layer (the voxels within vertical_tolerance_m of
/// floor_z_m + device_height_m, at least the nearest one), (walkable polygons minus walls) plus
/// doors, stairs, lifts, and every point within walkway_half_width_m of a walkway line. Stairs
/// of floor f are traversable over the whole vertical column from the next floor below to the
/// next floor above (a staircase is not ramped: the whole stairwell counts); a lift of any floor
/// over the column from the lowest to the highest floor (a shaft serves the building, while
/// plans often mark it on some floors only); nothing else joins floors.
///  - corridor: outside the set, the 3D distance to it; inside, minus the horizontal distance to
///    the set's edge at that height (as the planar road field: how far from the walls). Zero
///    level between the last inside and the first outside voxel; truncated at +/- truncation_m.
///  - centre: 3D distance to the nearest walkway centre line (on its floor's surface), exact
///    within exact_band_m; a floor without walkways contributes its walkable area at the surface
///    height instead;
///    stair and lift columns count as centres of vertical motion. Truncated at truncation_m.
/// The lifts' outlines (of every floor) are the field's lift_shafts().
/// Throws std::invalid_argument when the config is invalid, there is no floor, no floor has
/// anything traversable, or the grid would exceed max_memory_mb (the message names the
/// horizontal resolution that would fit).
TraversableField BuildIndoorField(const std::vector<IndoorFloor>& floors,
                                  const IndoorFieldConfig& config,
                                  IndoorFieldStats* stats = nullptr,
                                  const std::optional<HeightRange>& heights = std::nullopt);

}  // namespace driftcorr
