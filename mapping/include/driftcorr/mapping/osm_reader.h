#pragma once
// OpenStreetMap XML reader: ways with a `highway` tag (the traversable network).
#include <cstdint>
#include <string>
#include <vector>

#include "driftcorr/mapping/geodesy.h"

namespace driftcorr {

struct OsmWay {
    std::int64_t id = 0;
    std::string highway;          ///< value of the highway tag, e.g. "residential"
    std::vector<GeoPoint> nodes;  ///< resolved node coordinates in way order (alt_m = 0)
    double width_m = 0.0;         ///< from a parseable `width` tag, else 0
    int lanes = 0;                ///< from a parseable `lanes` tag, else 0
    bool is_area = false;         ///< `area=yes` (a pedestrian square etc.)
};

struct OsmReadReport {
    std::size_t nodes_total = 0;   ///< <node> elements with valid coordinates
    std::size_t ways_total = 0;    ///< all <way> elements
    std::size_t ways_highway = 0;  ///< highway ways returned (a split way counts per piece)
    /// <nd ref> (in highway ways) with no <node>: the way is split there (not joined across)
    std::size_t missing_node_refs = 0;
    std::size_t ways_split = 0;      ///< extra pieces made by those splits (`ways` holds each)
    std::size_t ways_too_short = 0;  ///< highway ways with no piece of >= 2 resolved nodes, dropped
};

struct OsmRoads {
    std::vector<OsmWay> ways;
    OsmReadReport report;
};

/// Reads an OSM XML file (.osm). Throws InputError (file, line) for a missing/unreadable file,
/// malformed XML, or node coordinates that are not finite / out of range. Returns an empty `ways`
/// vector when the file has no highway ways (the caller decides whether that is an error).
OsmRoads ReadOsmRoads(const std::string& path);

}  // namespace driftcorr
