#pragma once
// GeoJSON FeatureCollections of one floor (walkway networks, floor plans), read into plain
// structs in the file's own CRS coordinates. The JSON library stays in geojson_reader.cpp.
#include <Eigen/Core>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace driftcorr {

/// A line of a LineString or one part of a MultiLineString: (easting, northing) in the layer's
/// CRS [m] (or (lon, lat) [deg] for OGC:CRS84). At least two points.
struct GeoJsonLine {
    std::vector<Eigen::Vector2d> points;
    std::size_t feature_index = 0;  ///< position of the feature in the file's `features` array
};

/// One polygon of a Polygon or one part of a MultiPolygon. Rings are closed as in the file (the
/// first point repeated last) or not; the reader does not care. At least three distinct points.
struct GeoJsonPolygon {
    std::vector<Eigen::Vector2d> outer;
    std::vector<std::vector<Eigen::Vector2d>> holes;
    /// The feature's `Type` property: std::nullopt when missing, null, not a string, or the
    /// feature's properties are null.
    std::optional<std::string> type;
    std::size_t feature_index = 0;
};

/// What the reader could not use, counted by reason ("null geometry", "unsupported geometry
/// Point", "degenerate geometry", ...), and what it kept with a caveat ("null properties").
struct GeoJsonReport {
    std::size_t features = 0;  ///< features in the file
    std::map<std::string, std::size_t> skipped;
    std::map<std::string, std::size_t> caveats;

    std::size_t SkippedCount() const;
    /// "3 skipped (null geometry: 3); caveats: null properties: 1", or "nothing skipped".
    std::string Summary() const;
};

struct GeoJsonLayer {
    std::string path;
    std::string crs;           ///< normalised: "EPSG:<code>" or "OGC:CRS84"
    std::string crs_declared;  ///< as written in the file
    std::vector<GeoJsonLine> lines;
    std::vector<GeoJsonPolygon> polygons;
    GeoJsonReport report;
};

/// Reads a GeoJSON FeatureCollection. Features with a null geometry, an unsupported geometry
/// type (Point, GeometryCollection, ...) or degenerate coordinates are skipped and counted.
/// Throws InputError naming `path` when the file is missing or unreadable, is not valid JSON
/// (with the line), is not a FeatureCollection, or has no `crs` member or one that
/// NormaliseCrsName does not know.
GeoJsonLayer ReadGeoJson(const std::string& path);

/// Same, from text already in memory; `path` is only used in messages.
GeoJsonLayer ParseGeoJson(const std::string& text, const std::string& path);

}  // namespace driftcorr
