// OpenStreetMap PBF reader on libosmium (header-only, compiled into this file only; no osmium
// type leaves it). It fills the same RawWay / node index as the XML reader and resolves them with
// the same code (osm_ways.h), so a PBF and the XML of one extract give the same OsmRoads.
//
// The file is read into memory and handed to libosmium as a buffer: the reader never opens a
// path itself (libosmium would fetch an "http:" name with curl) and the file is named in every
// error. libosmium decodes the blobs on its shared thread pool; each call has its own Reader, so
// concurrent calls from several threads are independent.
#include <osmium/handler.hpp>
#include <osmium/io/pbf_input.hpp>
#include <osmium/osm/node.hpp>
#include <osmium/osm/way.hpp>
#include <osmium/visitor.hpp>

#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "driftcorr/core/errors.h"
#include "osm_ways.h"

namespace driftcorr::osm_internal {
namespace {

std::string ReadWholeFile(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        throw InputError(path, 0, "", "is a folder, expected an OSM file");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "", "cannot open file");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw InputError(path, 0, "", "read error");
    return bytes;
}

/// Collects node locations and highway ways, as OsmParser does for XML.
class RoadsHandler : public osmium::handler::Handler {
public:
    explicit RoadsHandler(const std::string& path) : path_(path) {}

    void node(const osmium::Node& node) {
        if (!node.visible()) return;  // a deleted node in a history file has no location
        const osmium::Location loc = node.location();
        if (!loc.valid()) {
            throw InputError(path_, 0, "", "node " + std::to_string(node.id()) +
                                               ": location is missing or outside [-90, 90] x "
                                               "[-180, 180] degrees");
        }
        nodes_[node.id()] = LatLon{loc.lat(), loc.lon()};
        ++report_.nodes_total;
    }

    void way(const osmium::Way& way) {
        ++report_.ways_total;
        RawWay raw;
        raw.id = way.id();
        for (const osmium::Tag& tag : way.tags()) ApplyWayTag(tag.key(), tag.value(), raw);
        if (!raw.has_highway) return;
        raw.refs.reserve(way.nodes().size());
        for (const osmium::NodeRef& ref : way.nodes()) raw.refs.push_back(ref.ref());
        highway_ways_.push_back(std::move(raw));
    }

    OsmRoads TakeResult() { return ResolveWays(highway_ways_, nodes_, report_); }

private:
    std::string path_;
    NodeIndex nodes_;
    std::vector<RawWay> highway_ways_;
    OsmReadReport report_;
};

}  // namespace

OsmRoads ReadOsmPbf(const std::string& path) {
    const std::string bytes = ReadWholeFile(path);
    RoadsHandler handler(path);
    try {
        osmium::io::File file(bytes.data(), bytes.size(), "pbf");
        osmium::io::Reader reader(file, osmium::osm_entity_bits::node | osmium::osm_entity_bits::way);
        osmium::apply(reader, handler);
        reader.close();
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        // libosmium reports a truncated or foreign file as osmium::pbf_error / io_error.
        throw InputError(path, 0, "",
                         std::string("is neither OSM XML (it does not start with '<') nor a valid "
                                     "OSM PBF file: ") + e.what());
    }
    return handler.TakeResult();
}

}  // namespace driftcorr::osm_internal
