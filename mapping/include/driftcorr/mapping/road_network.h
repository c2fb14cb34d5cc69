#pragma once
// The road network in the local East-North plane, and its rasterisation into a TraversableField.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

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

    /// Empty if valid, else a message naming the bad field.
    std::string Validate() const;
    /// The effective class -> half-width table.
    std::map<std::string, double> Table() const;
};

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

    Eigen::AlignedBox2d Bounds() const;
    double TotalLengthM() const;
};

/// Projects the OSM ways into East-North with `to_en` and keeps the traversable ones.
RoadNetwork BuildRoadNetwork(const OsmRoads& osm,
                             const std::function<Eigen::Vector2d(const GeoPoint&)>& to_en,
                             const RoadClassConfig& config);

struct RoadFieldConfig {
    double resolution_m = 0.5;      ///< grid spacing [m]
    double margin_m = 300.0;        ///< grid extends this far around the region of interest [m]
    double truncation_m = 40.0;     ///< distances are capped at this value [m]
    double exact_band_m = 6.0;      ///< exact point-to-segment distances within this band
                                    ///< beyond the corridor edge; EDT beyond [m]
    double max_memory_mb = 1024.0;  ///< refuse fields larger than this

    std::string Validate() const;
};

/// Rasterises the network over `region_en` grown by margin_m (and clipped to the network's
/// bounds grown by truncation_m): exact distances near the roads, an exact EDT beyond, both
/// truncated, then B-spline interpolated. Throws std::invalid_argument when the grid would exceed
/// max_memory_mb (the message says which resolution would fit) or the network is empty.
TraversableField RasteriseRoads(const RoadNetwork& network, const Eigen::AlignedBox2d& region_en,
                                const RoadFieldConfig& config);

}  // namespace driftcorr
