// GeoJSON adapter: nlohmann::json is used here only (linked PRIVATE).
#include "driftcorr/mapping/geojson_reader.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/geodesy.h"

namespace driftcorr {
namespace {

using Json = nlohmann::json;

long LineOfByte(const std::string& text, std::size_t byte) {
    const std::size_t end = std::min(byte, text.size());
    return 1 + static_cast<long>(std::count(text.begin(), text.begin() + end, '\n'));
}

// A coordinate that is not a number (a quoted or null value): an error in the file, not a
// degenerate geometry to skip. `value` is the JSON text of the coordinate.
struct NonNumericCoordinate {
    std::string value;
};

// A position array [x, y] or [x, y, z] -> (x, y); false if not two finite numbers. Throws
// NonNumericCoordinate when x or y is present but not a number.
bool ReadPosition(const Json& j, Eigen::Vector2d& out) {
    if (!j.is_array() || j.size() < 2) return false;
    for (int k = 0; k < 2; ++k) {
        if (!j[k].is_number()) throw NonNumericCoordinate{j[k].dump()};
    }
    out = Eigen::Vector2d(j[0].get<double>(), j[1].get<double>());
    return std::isfinite(out.x()) && std::isfinite(out.y());
}

bool ReadPositions(const Json& j, std::vector<Eigen::Vector2d>& out, std::size_t min_points) {
    if (!j.is_array()) return false;
    out.clear();
    out.reserve(j.size());
    for (const Json& p : j) {
        Eigen::Vector2d v;
        if (!ReadPosition(p, v)) return false;
        out.push_back(v);
    }
    return out.size() >= min_points;
}

// Polygon coordinates: [outer ring, hole, ...]. A ring needs three distinct points.
bool ReadPolygon(const Json& rings, GeoJsonPolygon& out) {
    if (!rings.is_array() || rings.empty()) return false;
    if (!ReadPositions(rings[0], out.outer, 3)) return false;
    for (std::size_t r = 1; r < rings.size(); ++r) {
        std::vector<Eigen::Vector2d> hole;
        if (!ReadPositions(rings[r], hole, 3)) return false;
        out.holes.push_back(std::move(hole));
    }
    return true;
}

std::optional<std::string> TypeProperty(const Json& feature, GeoJsonReport& report) {
    auto it = feature.find("properties");
    if (it == feature.end() || it->is_null()) {
        ++report.caveats["null properties"];
        return std::nullopt;
    }
    if (!it->is_object()) {
        ++report.caveats["properties not an object"];
        return std::nullopt;
    }
    auto t = it->find("Type");
    if (t == it->end() || !t->is_string()) return std::nullopt;
    return t->get<std::string>();
}

// Adds the geometry of one feature; returns the skip reason, or "" when used.
std::string AddFeature(const Json& feature, std::size_t index, GeoJsonLayer& layer) {
    if (!feature.is_object()) return "feature not an object";
    auto g = feature.find("geometry");
    if (g == feature.end() || g->is_null()) return "null geometry";
    if (!g->is_object() || !g->contains("type") || !(*g)["type"].is_string()) {
        return "malformed geometry";
    }
    const std::string type = (*g)["type"].get<std::string>();
    const Json* coords = g->contains("coordinates") ? &(*g)["coordinates"] : nullptr;
    if (type == "LineString" || type == "MultiLineString") {
        if (!coords || !coords->is_array()) return "degenerate geometry";
        std::vector<GeoJsonLine> parts;
        const bool multi = type == "MultiLineString";
        for (std::size_t p = 0; p < (multi ? coords->size() : 1); ++p) {
            GeoJsonLine line{{}, index};
            if (!ReadPositions(multi ? (*coords)[p] : *coords, line.points, 2)) {
                return "degenerate geometry";
            }
            parts.push_back(std::move(line));
        }
        for (auto& l : parts) layer.lines.push_back(std::move(l));
        return "";
    }
    if (type == "Polygon" || type == "MultiPolygon") {
        if (!coords || !coords->is_array()) return "degenerate geometry";
        const std::optional<std::string> t = TypeProperty(feature, layer.report);
        std::vector<GeoJsonPolygon> parts;
        const bool multi = type == "MultiPolygon";
        for (std::size_t p = 0; p < (multi ? coords->size() : 1); ++p) {
            GeoJsonPolygon poly;
            poly.type = t;
            poly.feature_index = index;
            if (!ReadPolygon(multi ? (*coords)[p] : *coords, poly)) return "degenerate geometry";
            parts.push_back(std::move(poly));
        }
        for (auto& p : parts) layer.polygons.push_back(std::move(p));
        return "";
    }
    return "unsupported geometry " + type;
}

std::string CrsMember(const Json& root, const std::string& path) {
    auto it = root.find("crs");
    if (it == root.end() || it->is_null()) {
        throw InputError(path, 0, "crs",
                         "no `crs` member: a GeoJSON map layer must declare its projected CRS "
                         "(e.g. \"crs\": {\"type\": \"name\", \"properties\": {\"name\": "
                         "\"urn:ogc:def:crs:EPSG::32632\"}})");
    }
    const Json* name = nullptr;
    if (it->is_object() && it->contains("properties") && (*it)["properties"].is_object() &&
        (*it)["properties"].contains("name")) {
        name = &(*it)["properties"]["name"];
    }
    if (!name || !name->is_string()) {
        throw InputError(path, 0, "crs", "the `crs` member has no properties.name string");
    }
    return name->get<std::string>();
}

}  // namespace

std::size_t GeoJsonReport::SkippedCount() const {
    std::size_t n = 0;
    for (const auto& [reason, count] : skipped) n += count;
    return n;
}

std::string GeoJsonReport::Summary() const {
    std::ostringstream out;
    if (skipped.empty())
        out << "nothing skipped";
    else
        out << SkippedCount() << " skipped";
    auto list = [&out](const std::map<std::string, std::size_t>& m) {
        bool first = true;
        for (const auto& [reason, count] : m) {
            out << (first ? "" : ", ") << reason << ": " << count;
            first = false;
        }
    };
    if (!skipped.empty()) {
        out << " (";
        list(skipped);
        out << ")";
    }
    if (!caveats.empty()) {
        out << "; caveats: ";
        list(caveats);
    }
    return out.str();
}

namespace {

GeoJsonLayer ParseGeoJsonUnchecked(const std::string& text, const std::string& path) {
    Json root = Json::parse(text);
    if (!root.is_object() || !root.contains("type") || root["type"] != "FeatureCollection") {
        throw InputError(path, 0, "type", "not a GeoJSON FeatureCollection");
    }
    GeoJsonLayer layer;
    layer.path = path;
    layer.crs_declared = CrsMember(root, path);
    layer.crs = NormaliseCrsName(layer.crs_declared);
    if (layer.crs.empty()) {
        throw InputError(path, 0, "crs",
                         "unknown CRS '" + layer.crs_declared +
                             "' (expected EPSG:<code>, urn:ogc:def:crs:EPSG::<code> or CRS84)");
    }
    auto features = root.find("features");
    if (features == root.end() || !features->is_array()) {
        throw InputError(path, 0, "features", "a FeatureCollection needs a `features` array");
    }
    layer.report.features = features->size();
    for (std::size_t i = 0; i < features->size(); ++i) {
        try {
            const std::string reason = AddFeature((*features)[i], i, layer);
            if (!reason.empty()) ++layer.report.skipped[reason];
        } catch (const NonNumericCoordinate& bad) {
            throw InputError(path, 0, "features[" + std::to_string(i) + "].geometry.coordinates",
                             "a coordinate is not a number (" + bad.value.substr(0, 40) + ")");
        }
    }
    return layer;
}

}  // namespace

GeoJsonLayer ParseGeoJson(const std::string& text, const std::string& path) {
    try {
        return ParseGeoJsonUnchecked(text, path);
    } catch (const Json::parse_error& e) {
        throw InputError(path, LineOfByte(text, e.byte), "",
                         "invalid JSON at byte " + std::to_string(e.byte) + ": " + e.what());
    } catch (const Json::exception& e) {  // e.g. out_of_range: a number too large for a double
        throw InputError(path, 0, "", std::string("invalid GeoJSON: ") + e.what());
    }
}

GeoJsonLayer ReadGeoJson(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "", "cannot open the GeoJSON file");
    std::ostringstream buf;
    buf << in.rdbuf();
    if (in.bad()) throw InputError(path, 0, "", "cannot read the GeoJSON file");
    return ParseGeoJson(buf.str(), path);
}

}  // namespace driftcorr
