#pragma once
// GeoJSON (RFC 7946, WGS84 lon/lat) output of tracks for GIS tools.
#include <string>
#include <utility>
#include <vector>

#include "driftcorr/mapping/geodesy.h"

namespace driftcorr::io {

struct GeoTrack {
    std::string name;  ///< becomes properties.name, e.g. "estimate", "corrected"
    std::vector<GeoPoint> points;
    /// Further properties of the feature: key and its value as JSON text (written verbatim),
    /// e.g. {"verdict", "\"ok\""} or a per-vertex array.
    std::vector<std::pair<std::string, std::string>> json_properties;
};

/// `text` as a JSON string literal (quoted and escaped).
std::string JsonString(const std::string& text);

/// Writes a FeatureCollection with one LineString Feature per track (coordinates [lon, lat],
/// 8 decimals), atomically (AtomicFile). A track with a single point becomes a Point, an empty
/// one a null geometry. Throws std::runtime_error naming the path on failure or on a non-finite
/// coordinate (before anything is written).
void WriteGeoJsonTracks(const std::string& path, const std::vector<GeoTrack>& tracks);

}  // namespace driftcorr::io
