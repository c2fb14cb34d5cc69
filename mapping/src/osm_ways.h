#pragma once
// What the OpenStreetMap XML and PBF readers share (internal to driftcorr_mapping): the way as
// read, the tags used, and the resolution of node refs into OsmRoads. Both readers feed these,
// so an XML file and the PBF of the same extract give the same OsmRoads.
#include <charconv>
#include <cstdint>
#include <string>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

#include "driftcorr/mapping/osm_reader.h"

namespace driftcorr::osm_internal {

/// A way as written in the file, before its node refs are resolved.
struct RawWay {
    std::int64_t id = 0;
    std::vector<std::int64_t> refs;
    std::string highway;
    bool has_highway = false;
    double width_m = 0.0;
    int lanes = 0;
    bool is_area = false;
};

struct LatLon {
    double lat_deg = 0.0;
    double lon_deg = 0.0;
};

using NodeIndex = std::unordered_map<std::int64_t, LatLon>;

/// [begin, end) of `s` without leading and trailing whitespace.
std::pair<const char*, const char*> Trim(const char* s);

/// Locale-independent parse of the whole (trimmed) string as T; false on any trailing junk.
template <typename T>
bool ParseWhole(const char* s, T* out) {
    const auto [begin, end] = Trim(s);
    if (begin == end) return false;
    const auto result = std::from_chars(begin, end, *out);
    return result.ec == std::errc() && result.ptr == end;
}

/// Applies one tag of a way: `highway`, `width` (a number, optionally " m"; else 0), `lanes` (a
/// non-negative integer; else 0), `area=yes`. Other tags are ignored.
void ApplyWayTag(const char* key, const char* value, RawWay& way);

/// Resolves the node refs of the highway ways (missing refs counted and dropped, ways with fewer
/// than two resolved nodes counted and dropped), in the order the ways were read.
OsmRoads ResolveWays(std::vector<RawWay>& highway_ways, const NodeIndex& nodes,
                     const OsmReadReport& report);

/// Reads an OSM PBF file (osm_pbf_reader.cpp). Throws InputError naming the file when it cannot
/// be read, is not PBF, is truncated or holds a node outside [-90, 90] x [-180, 180].
OsmRoads ReadOsmPbf(const std::string& path);

}  // namespace driftcorr::osm_internal
