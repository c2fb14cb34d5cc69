#pragma once
// The road network in the local East-North plane, and its rasterisation into a TraversableField.
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/core/params.h"
#include "driftcorr/mapping/osm_reader.h"
#include "driftcorr/mapping/traversable_field.h"

namespace driftcorr {

/// Which OSM highway classes are traversable, and how wide. A class absent from the table is not
/// traversable for this profile.
struct RoadClassConfig {
    /// "vehicle" (carriageways, links, service roads, tracks), "pedestrian" (footways, paths,
    /// cycleways, steps, pedestrian zones, living streets, residential and service roads) or
    /// "all" (every class of both tables).
    std::string profile = "vehicle";
    /// Per-class half-widths [m] that override or extend the profile's table; 0 removes a class.
    std::map<std::string, double> half_width_overrides_m;
    /// Half-width [m] of a way whose class is in neither table, when profile == "all".
    double default_half_width_m = 3.0;

    /// The first value kRoadClassParams does not allow.
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "roads.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
    /// The effective class -> half-width table.
    std::map<std::string, double> Table() const;
};

/// Params.yaml section `roads`.
inline constexpr Param<RoadClassConfig> kRoadClassParamRows[] = {
    {"profile", Field<&RoadClassConfig::profile>(), kNoRange,
     "traversable OSM highway classes and their half-widths", "vehicle|pedestrian|all"},
    {"half_width_m", Field<&RoadClassConfig::half_width_overrides_m>(), kNonNegative,
     "per-class half-widths that override or extend the profile's; 0 removes a class"},
    {"default_half_width_m", Field<&RoadClassConfig::default_half_width_m>(), kPositive,
     "half-width of a class in neither table (profile all)"},
};
inline constexpr ParamTable<RoadClassConfig> kRoadClassParams{"roads", kRoadClassParamRows};

struct RoadPolyline {
    std::int64_t osm_id = 0;
    std::string highway;
    double half_width_m = 0.0;
    std::vector<Eigen::Vector2d> points_en;  ///< [m] in the local East-North plane
};

struct RoadNetwork {
    std::vector<RoadPolyline> roads;
    std::size_t ways_excluded_by_class = 0;  ///< highway ways not in the profile
    std::size_t ways_area = 0;               ///< area=yes ways, skipped
    /// Node references of highway ways the map file does not resolve (OsmReadReport): the ways
    /// are split there.
    std::size_t missing_node_refs = 0;
    /// (lon, lat) [deg] of the kept roads' nodes as the map file gives them; empty when the
    /// network was not built from a map with geographic coordinates.
    Eigen::AlignedBox2d lon_lat_deg;

    Eigen::AlignedBox2d Bounds() const;
    double TotalLengthM() const;
};

/// Projects the OSM ways into East-North with `to_en` and keeps the traversable ones.
RoadNetwork BuildRoadNetwork(const OsmRoads& osm,
                             const std::function<Eigen::Vector2d(const GeoPoint&)>& to_en,
                             const RoadClassConfig& config);

struct RoadFieldConfig {
    double resolution_m = 0.5;  ///< grid spacing [m]
    /// The grid extends this far around the region of interest; the pipeline's corridor field
    /// also keeps the tiles within this distance of every estimated pose: the drift (estimate
    /// to corrected track) the field allows for [m]
    double margin_m = 300.0;
    double truncation_m = 40.0;     ///< distances are capped at this value [m]
    double exact_band_m = 6.0;      ///< exact point-to-segment distances within this band
                                    ///< beyond the corridor edge; EDT beyond [m]
    double max_memory_mb = 1024.0;  ///< refuse fields larger than this
    /// The field is built and held in square tiles of about this side, one tile at a time
    /// (RasteriseRoadCorridor keeps only the tiles its corridor touches); 0: one grid [m]
    double tile_m = 256.0;
    /// Threads of the map stage: with 2 or more, the rasterisation splits its rows and the two
    /// distance transforms (to the centre lines and to the corridors) run side by side, and the
    /// pipeline reads the ground truth beside the estimate and checks the anchor beside the
    /// correction; 0: one per core the process may run on.
    int threads = 0;

    /// The first value kRoadFieldParams does not allow.
    std::optional<ParamProblem> FindProblem() const;
    /// Empty if valid, else "field.<key>: <rule> (got <value>)" for the first bad field.
    std::string Validate() const;
};

/// Params.yaml section `field`.
inline constexpr Param<RoadFieldConfig> kRoadFieldParamRows[] = {
    {"resolution_m", Field<&RoadFieldConfig::resolution_m>(), kPositive, "grid spacing"},
    {"margin_m", Field<&RoadFieldConfig::margin_m>(), kNonNegative,
     "the grid extends this far around the estimate: the drift the field allows for"},
    {"truncation_m", Field<&RoadFieldConfig::truncation_m>(), kPositive,
     "distances are capped at this value"},
    {"exact_band_m", Field<&RoadFieldConfig::exact_band_m>(), kNonNegative,
     "exact point-to-segment distances within this band beyond the corridor edge; EDT beyond"},
    {"max_memory_mb", Field<&RoadFieldConfig::max_memory_mb>(), kPositive,
     "refuse fields larger than this"},
    {"tile_m", Field<&RoadFieldConfig::tile_m>(), kNonNegative,
     "built and held in tiles of this side; 0: one grid over the bounding box"},
    {"threads", Field<&RoadFieldConfig::threads>(), kNonNegative,
     "threads of the map stage (2: both distance transforms at once); 0: one per core"},
};
inline constexpr ParamTable<RoadFieldConfig> kRoadFieldParams{"field", kRoadFieldParamRows};

/// Rasterises the network over `region_en` grown by margin_m (and clipped to the network's
/// bounds grown by truncation_m): exact distances near the roads, an exact EDT beyond, both
/// truncated, then B-spline interpolated. Throws std::invalid_argument when the grid would exceed
/// max_memory_mb (the message says which resolution would fit) or the network is empty.
TraversableField RasteriseRoads(const RoadNetwork& network, const Eigen::AlignedBox2d& region_en,
                                const RoadFieldConfig& config);

/// A disc of the world plane: centre [m, East-North] and radius [m].
struct FieldDisc {
    Eigen::Vector2d centre_en;
    double radius_m = 0.0;
};

/// The field of RasteriseRoads over `region_en`, held only in the tiles of config.tile_m that
/// come within a disc of `corridor` (e.g. a disc about every pose of a dead-reckoned track):
/// equal to RasteriseRoads' field wherever a tile is held (to float rounding), std::nullopt
/// (outside the map) elsewhere. When the tiles would hold more than half of the box's samples
/// and the box fits max_memory_mb, the box is built as one grid instead. Throws
/// std::invalid_argument when the tiles would exceed max_memory_mb or the network is empty.
/// Precondition: config.tile_m > 0.
TraversableField RasteriseRoadCorridor(const RoadNetwork& network,
                                       const Eigen::AlignedBox2d& region_en,
                                       const std::vector<FieldDisc>& corridor,
                                       const RoadFieldConfig& config);

}  // namespace driftcorr
