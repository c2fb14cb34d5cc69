// The definitions of what driftcorr/io/geojson_writer.h declares.
#include "driftcorr/io/geojson_writer.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "driftcorr/mapping/atomic_file.h"

namespace driftcorr::io {

/// Quotes, backslashes and control characters escaped.
std::string JsonString(const std::string& text) {
    std::string out = "\"";
    for (const char c : text) {
        if (c == '"' || c == '\\') {
            out += '\\';
            out += c;
        } else if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof(buf), "\\u%04x", static_cast<unsigned>(c));
            out += buf;
        } else {
            out += c;
        }
    }
    return out + "\"";
}

namespace {

/// JSON has no NaN or infinity: reject them before anything is written.
void CheckFinite(const std::string& path, const std::vector<GeoTrack>& tracks) {
    for (const GeoTrack& track : tracks) {
        for (std::size_t i = 0; i < track.points.size(); ++i) {
            const GeoPoint& p = track.points[i];
            if (!std::isfinite(p.lat_deg) || !std::isfinite(p.lon_deg)) {
                throw std::runtime_error(path + ": track '" + track.name + "' point " +
                                         std::to_string(i) + " is not finite");
            }
        }
    }
}

/// RFC 7946 geometry: a LineString from two points on; a single point becomes a Point and an
/// empty track a null geometry, so that every track still appears as one Feature.
std::string Geometry(const std::vector<GeoPoint>& points) {
    if (points.empty()) return "null";
    char buf[64];
    std::string coords;
    for (std::size_t i = 0; i < points.size(); ++i) {
        std::snprintf(buf, sizeof(buf), "%s[%.8f,%.8f]", i == 0 ? "" : ",", points[i].lon_deg,
                      points[i].lat_deg);
        coords += buf;
    }
    if (points.size() == 1) return "{\"type\":\"Point\",\"coordinates\":" + coords + "}";
    return "{\"type\":\"LineString\",\"coordinates\":[" + coords + "]}";
}

}  // namespace

void WriteGeoJsonTracks(const std::string& path, const std::vector<GeoTrack>& tracks) {
    CheckFinite(path, tracks);
    AtomicFile file(path);
    std::ostream& out = file.stream();
    out << "{\"type\":\"FeatureCollection\",\"features\":[\n";
    for (std::size_t i = 0; i < tracks.size(); ++i) {
        out << "{\"type\":\"Feature\",\"properties\":{\"name\":" << JsonString(tracks[i].name);
        for (const auto& [key, json] : tracks[i].json_properties) {
            out << "," << JsonString(key) << ":" << json;
        }
        out << "},\"geometry\":" << Geometry(tracks[i].points) << "}"
            << (i + 1 < tracks.size() ? ",\n" : "\n");
    }
    out << "]}\n";
    if (!out) throw std::runtime_error(path + ": write failed");
    file.Commit();
}

}  // namespace driftcorr::io
