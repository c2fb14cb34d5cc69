// The definitions of what osm_ways.h declares.
#include "osm_ways.h"

#include <cmath>
#include <cstring>

namespace driftcorr::osm_internal {
namespace {

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

/// `width`: a number, optionally followed by the unit " m" (or "m"). Anything else -> 0.
double ParseWidthM(const char* s) {
    const auto [begin, end] = Trim(s);
    double width_m = 0.0;
    const auto result = std::from_chars(begin, end, width_m);
    if (result.ec != std::errc()) return 0.0;
    const char* rest = result.ptr;
    while (rest < end && IsSpace(*rest)) ++rest;
    if (rest < end && *rest == 'm') ++rest;
    if (rest != end || !std::isfinite(width_m) || width_m < 0.0) return 0.0;
    return width_m;
}

/// `lanes`: a non-negative integer. Anything else ("2;3", "two") -> 0.
int ParseLanes(const char* s) {
    int lanes = 0;
    return ParseWhole(s, &lanes) && lanes >= 0 ? lanes : 0;
}

}  // namespace

std::pair<const char*, const char*> Trim(const char* s) {
    const char* begin = s;
    const char* end = s + std::strlen(s);
    while (begin < end && IsSpace(*begin)) ++begin;
    while (end > begin && IsSpace(end[-1])) --end;
    return {begin, end};
}

void ApplyWayTag(const char* key, const char* value, RawWay& way) {
    if (std::strcmp(key, "highway") == 0) {
        way.has_highway = true;
        way.highway = value;
    } else if (std::strcmp(key, "width") == 0) {
        way.width_m = ParseWidthM(value);
    } else if (std::strcmp(key, "lanes") == 0) {
        way.lanes = ParseLanes(value);
    } else if (std::strcmp(key, "area") == 0) {
        way.is_area = std::strcmp(value, "yes") == 0;
    }
}

OsmRoads ResolveWays(std::vector<RawWay>& highway_ways, const NodeIndex& nodes,
                     const OsmReadReport& report) {
    OsmRoads roads;
    roads.report = report;
    roads.ways.reserve(highway_ways.size());
    for (RawWay& raw : highway_ways) {
        OsmWay way;
        way.id = raw.id;
        way.highway = std::move(raw.highway);
        way.width_m = raw.width_m;
        way.lanes = raw.lanes;
        way.is_area = raw.is_area;
        // A node the file does not hold (an extract cut at its edge) ends the piece before it:
        // the way is split there, not joined across the gap by a road that may not exist.
        std::vector<std::vector<GeoPoint>> pieces(1);
        for (const std::int64_t ref : raw.refs) {
            const auto it = nodes.find(ref);
            if (it == nodes.end()) {
                ++roads.report.missing_node_refs;
                if (!pieces.back().empty()) pieces.emplace_back();
                continue;
            }
            pieces.back().push_back(GeoPoint{it->second.lat_deg, it->second.lon_deg, 0.0});
        }
        std::size_t kept = 0;
        for (std::vector<GeoPoint>& piece : pieces) {
            if (piece.size() < 2) continue;
            OsmWay part = way;
            part.nodes = std::move(piece);
            roads.ways.push_back(std::move(part));
            ++kept;
        }
        if (kept == 0) ++roads.report.ways_too_short;
        if (kept > 1) roads.report.ways_split += kept - 1;
    }
    roads.report.ways_highway = roads.ways.size();
    return roads;
}

}  // namespace driftcorr::osm_internal
