#pragma once
// Floor plans and walkway networks of an indoor scenario: the `Type` classifier for messy floor
// plans, and the loader that turns the scenario's GeoJSON map layers into IndoorFloors.
#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "driftcorr/mapping/geodesy.h"
#include "driftcorr/mapping/indoor_field.h"

namespace driftcorr {

enum class FloorClass { kWalkable, kStairs, kLift, kDoor, kWall, kIgnore };

const char* ToString(FloorClass c);

/// The class of a floor-plan polygon from its `Type` property (exact spelling, then case- and
/// whitespace-insensitive). `known` is set to false for a value not in the table (and for a
/// missing type); such polygons are kIgnore. The table is documented in floor_plan.cpp.
FloorClass ClassifyFloorType(const std::string* type, bool* known = nullptr);

/// Where a polygon ring crosses itself: the first point where two of its edges that do not share
/// a vertex cross (touching and collinear overlaps are not crossings), or nothing. The ring may
/// repeat its first point at its end. Time about linear in its edges (a sweep over x).
std::optional<Eigen::Vector2d> RingSelfCrossing(const std::vector<Eigen::Vector2d>& ring);

enum class IndoorLayerRole { kWalkways, kFloorplan };

/// One map layer of an indoor scenario (plain values: mapping does not read the scenario file).
struct IndoorLayerSpec {
    std::string path;  ///< GeoJSON file
    IndoorLayerRole role = IndoorLayerRole::kFloorplan;
    double floor_z_m = 0.0;
};

/// How layer coordinates reach the local East-North frame of the anchor.
struct IndoorFrame {
    /// The anchor's projected CRS ("EPSG:32632"), or empty for a lat/lon anchor.
    std::string anchor_crs;
    /// (easting, northing) in anchor_crs -> local East-North [m]. Used when anchor_crs is set.
    std::function<Eigen::Vector2d(const Eigen::Vector2d&)> anchor_crs_to_en;
    /// WGS84 -> local East-North [m]. Used when anchor_crs is empty.
    std::function<Eigen::Vector2d(const GeoPoint&)> geo_to_en;
};

/// What each layer contributed and what was left out.
struct IndoorLayerReport {
    std::string path;
    std::string crs;
    std::size_t features = 0;
    std::size_t lines = 0, polygons = 0;
    std::map<std::string, std::size_t> skipped;        ///< reader: reason -> count
    std::map<std::string, std::size_t> caveats;        ///< reader: kept with a caveat
    std::map<std::string, std::size_t> classes;        ///< floor plans: class -> polygon count
    std::map<std::string, std::size_t> unknown_types;  ///< Type value ("<missing>") -> count
    std::string Summary() const;
};

struct IndoorMap {
    std::vector<IndoorFloor> floors;  ///< one per distinct floor_z_m, ascending
    std::vector<IndoorLayerReport> layers;
};

/// Reads the layers, reprojects them into the local East-North frame (through PROJ when a
/// layer's CRS differs from the anchor's; OGC:CRS84 layers are read as lon/lat) and groups them
/// by floor_z_m. Throws InputError naming the file for unreadable layers, unknown CRSs,
/// CRS84 layers whose coordinates are not degrees, and floor plans without any walkable polygon.
IndoorMap LoadIndoorMap(const std::vector<IndoorLayerSpec>& layers, const IndoorFrame& frame);

}  // namespace driftcorr
