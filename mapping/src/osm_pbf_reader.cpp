// OpenStreetMap PBF reader on libosmium (header-only, compiled into this file only; no osmium
// type leaves it). It fills the same RawWay / node index as the XML reader and resolves them with
// the same code (osm_ways.h), so a PBF and the XML of one extract give the same OsmRoads.
//
// The file is read into memory and handed to libosmium as a buffer: the reader never opens a
// path itself (libosmium would fetch an "http:" name with curl) and the file is named in every
// error. libosmium decodes the blobs on its shared thread pool; each call has its own Reader, so
// concurrent calls from several threads are independent.
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <osmium/handler.hpp>
#include <osmium/io/pbf_input.hpp>
#include <osmium/osm/node.hpp>
#include <osmium/osm/way.hpp>
#include <osmium/visitor.hpp>
#include <protozero/exception.hpp>
#include <protozero/pbf_reader.hpp>
#include <string>

#include "driftcorr/core/check.h"
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

[[noreturn]] void NotPbf(const std::string& path, const std::string& why) {
    throw InputError(
        path, 0, "",
        "is neither OSM XML (it does not start with '<') nor a valid OSM PBF file: " + why);
}

// Walks the file's blob sequence as libosmium will: a 4-byte big-endian BlobHeader size (at most
// 64 KiB), the BlobHeader (field 1: its type, a non-empty string; field 3: the Blob's size,
// > 0), then that many bytes of Blob. libosmium compares the type with strncmp on a null pointer
// when the field is missing (undefined behaviour, found by fuzzing), so such a file is refused
// here, before libosmium sees it.
void CheckBlobHeaders(const std::string& bytes, const std::string& path) {
    constexpr std::size_t kMaxHeader = 64 * 1024;
    std::size_t off = 0;
    while (off < bytes.size()) {
        if (bytes.size() - off < 4) NotPbf(path, "the file ends inside a blob header's size");
        const auto byte = [&](std::size_t k) {
            return std::uint32_t(std::uint8_t(bytes[off + k]));
        };
        const std::uint32_t n = byte(0) << 24 | byte(1) << 16 | byte(2) << 8 | byte(3);
        off += 4;
        if (n == 0 || n > kMaxHeader || bytes.size() - off < n) {
            NotPbf(path, "a blob header of " + std::to_string(n) + " bytes at byte " +
                             std::to_string(off - 4) + " (empty, over 64 KiB or past the end)");
        }
        bool has_type = false;
        std::int64_t datasize = 0;
        try {
            protozero::pbf_reader header(bytes.data() + off, n);
            while (header.next()) {
                if (header.tag_and_type() ==
                    protozero::tag_and_type(1, protozero::pbf_wire_type::length_delimited)) {
                    has_type = !header.get_view().empty();
                } else if (header.tag_and_type() ==
                           protozero::tag_and_type(3, protozero::pbf_wire_type::varint)) {
                    datasize = header.get_int32();
                } else {
                    header.skip();
                }
            }
        } catch (const protozero::exception& e) {
            NotPbf(path, std::string("a blob header at byte ") + std::to_string(off - 4) + ": " +
                             e.what());
        }
        if (!has_type || datasize <= 0) {
            NotPbf(path, "the blob header at byte " + std::to_string(off - 4) +
                             " has no type or no data size");
        }
        off += n;
        if (bytes.size() - off < std::size_t(datasize)) {
            NotPbf(path, "the file ends inside the blob at byte " + std::to_string(off));
        }
        off += std::size_t(datasize);
    }
}

/// Collects node locations and highway ways, as OsmParser does for XML.
class RoadsHandler : public osmium::handler::Handler {
public:
    explicit RoadsHandler(const std::string& path) : path_(path) {}

    void node(const osmium::Node& node) {
        if (!node.visible()) return;  // a deleted node in a history file has no location
        const osmium::Location loc = node.location();
        if (!loc.valid()) {
            throw InputError(path_, 0, "",
                             "node " + std::to_string(node.id()) +
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
    CheckBlobHeaders(bytes, path);
    RoadsHandler handler(path);
    try {
        osmium::io::File file(bytes.data(), bytes.size(), "pbf");
        osmium::io::Reader reader(file,
                                  osmium::osm_entity_bits::node | osmium::osm_entity_bits::way);
        osmium::apply(reader, handler);
        reader.close();
    } catch (const InputError&) {
        throw;
    } catch (const InvariantError&) {
        throw;
    } catch (const std::exception& e) {
        // libosmium reports a truncated or foreign file as osmium::pbf_error / io_error.
        NotPbf(path, e.what());
    }
    return handler.TakeResult();
}

}  // namespace driftcorr::osm_internal
