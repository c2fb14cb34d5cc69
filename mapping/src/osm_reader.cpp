// OpenStreetMap XML reader on expat (linked PRIVATE; no expat type leaves this file), and the
// entry point that hands PBF files to osm_pbf_reader.cpp.
//
// One streaming pass collects every top-level <node> (id -> lat, lon) and every top-level <way>
// that carries a `highway` tag (its <nd ref> list and the tags we use). Node refs are resolved
// after the pass, because OSM files may list ways before the nodes they reference.
//
// Errors are raised inside expat callbacks, which are C frames: the callbacks never let an
// exception escape. They store it, stop the parser, and ReadOsmRoads rethrows it afterwards.
#include "driftcorr/mapping/osm_reader.h"

#include <expat.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "driftcorr/core/errors.h"
#include "osm_ways.h"

namespace driftcorr {
namespace {

constexpr std::size_t kReadBlockBytes = 64 * 1024;

using osm_internal::LatLon;
using osm_internal::ParseWhole;
using osm_internal::RawWay;

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

/// The value of attribute `name` in expat's null-terminated (name, value) array, or nullptr.
const char* FindAttribute(const XML_Char** atts, const char* name) {
    for (int i = 0; atts[i] != nullptr; i += 2) {
        if (std::strcmp(atts[i], name) == 0) return atts[i + 1];
    }
    return nullptr;
}

struct ParserDeleter {
    void operator()(XML_Parser parser) const { XML_ParserFree(parser); }
};
using ParserPtr = std::unique_ptr<std::remove_pointer_t<XML_Parser>, ParserDeleter>;

struct FileCloser {
    void operator()(std::FILE* file) const { std::fclose(file); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

class OsmParser {
public:
    explicit OsmParser(std::string path) : path_(std::move(path)) {}

    /// Parses the whole file; throws InputError on the first problem.
    void Run();
    /// Resolves node refs and builds the result. Call once, after Run().
    OsmRoads TakeResult();

private:
    static void XMLCALL OnStart(void* user_data, const XML_Char* name, const XML_Char** atts);
    static void XMLCALL OnEnd(void* user_data, const XML_Char* name);

    void Start(const char* name, const XML_Char** atts);
    void End(const char* name);
    void StartNode(const XML_Char** atts);
    void StartWay(const XML_Char** atts);
    void StartWayChild(const char* name, const XML_Char** atts);
    double ParseCoordinate(const XML_Char** atts, const char* key, double limit_deg,
                           std::int64_t node_id) const;
    std::int64_t ParseId(const XML_Char** atts, const char* key, const char* element) const;
    [[noreturn]] void Fail(const std::string& key, const std::string& message) const;
    void Feed(const char* data, int size, bool is_final);

    std::string path_;
    ParserPtr parser_;
    std::exception_ptr error_;  ///< set by a callback; rethrown by Feed()
    int depth_ = 0;             ///< number of currently open elements
    bool in_way_ = false;       ///< inside a top-level <way>
    RawWay way_;                ///< the way being read while in_way_
    osm_internal::NodeIndex nodes_;
    std::vector<RawWay> highway_ways_;
    OsmReadReport report_;
};

void OsmParser::Run() {
    FilePtr file(std::fopen(path_.c_str(), "rb"));
    if (!file) Fail("", std::string("cannot open: ") + std::strerror(errno));
    parser_.reset(XML_ParserCreate(nullptr));
    if (!parser_) throw std::bad_alloc();
    XML_SetUserData(parser_.get(), this);
    XML_SetElementHandler(parser_.get(), &OsmParser::OnStart, &OsmParser::OnEnd);

    std::vector<char> block(kReadBlockBytes);
    for (;;) {
        const std::size_t size = std::fread(block.data(), 1, block.size(), file.get());
        if (std::ferror(file.get())) Fail("", std::string("cannot read: ") + std::strerror(errno));
        const bool is_final = size < block.size();
        Feed(block.data(), static_cast<int>(size), is_final);
        if (is_final) break;
    }
}

void OsmParser::Feed(const char* data, int size, bool is_final) {
    if (XML_Parse(parser_.get(), data, size, is_final ? XML_TRUE : XML_FALSE) == XML_STATUS_OK) {
        return;
    }
    if (error_) std::rethrow_exception(error_);
    const XML_Error code = XML_GetErrorCode(parser_.get());
    const long line = static_cast<long>(XML_GetCurrentLineNumber(parser_.get()));
    const long column = static_cast<long>(XML_GetCurrentColumnNumber(parser_.get()));
    throw InputError(path_, line, "",
                     std::string("malformed XML: ") + XML_ErrorString(code) + " (column " +
                         std::to_string(column) + ")");
}

void XMLCALL OsmParser::OnStart(void* user_data, const XML_Char* name, const XML_Char** atts) {
    auto* self = static_cast<OsmParser*>(user_data);
    if (self->error_) return;  // expat may still deliver a few events after XML_StopParser
    try {
        self->Start(name, atts);
    } catch (...) {
        self->error_ = std::current_exception();
        XML_StopParser(self->parser_.get(), XML_FALSE);
    }
}

void XMLCALL OsmParser::OnEnd(void* user_data, const XML_Char* name) {
    auto* self = static_cast<OsmParser*>(user_data);
    if (self->error_) return;
    try {
        self->End(name);
    } catch (...) {
        self->error_ = std::current_exception();
        XML_StopParser(self->parser_.get(), XML_FALSE);
    }
}

void OsmParser::Start(const char* name, const XML_Char** atts) {
    if (depth_ == 0 && std::strcmp(name, "osm") != 0) {
        Fail("", std::string("root element is <") + name + ">, expected <osm>");
    }
    if (depth_ == 1) {
        if (std::strcmp(name, "node") == 0) {
            StartNode(atts);
        } else if (std::strcmp(name, "way") == 0) {
            StartWay(atts);
        }
    } else if (depth_ == 2 && in_way_) {
        StartWayChild(name, atts);
    }
    ++depth_;
}

void OsmParser::End(const char* name) {
    --depth_;
    if (depth_ != 1 || !in_way_) return;
    in_way_ = false;
    if (way_.has_highway) highway_ways_.push_back(std::move(way_));
    way_ = RawWay{};
}

void OsmParser::StartNode(const XML_Char** atts) {
    // A deleted node in a history/diff file (visible="false") legitimately has no coordinates.
    const char* visible = FindAttribute(atts, "visible");
    if (visible != nullptr && std::strcmp(visible, "false") == 0) return;
    const std::int64_t id = ParseId(atts, "id", "node");
    LatLon coords;
    coords.lat_deg = ParseCoordinate(atts, "lat", 90.0, id);
    coords.lon_deg = ParseCoordinate(atts, "lon", 180.0, id);
    nodes_[id] = coords;
    ++report_.nodes_total;
}

void OsmParser::StartWay(const XML_Char** atts) {
    ++report_.ways_total;
    in_way_ = true;
    way_ = RawWay{};
    way_.id = ParseId(atts, "id", "way");
}

void OsmParser::StartWayChild(const char* name, const XML_Char** atts) {
    if (std::strcmp(name, "nd") == 0) {
        way_.refs.push_back(ParseId(atts, "ref", "nd"));
        return;
    }
    if (std::strcmp(name, "tag") != 0) return;
    const char* key = FindAttribute(atts, "k");
    const char* value = FindAttribute(atts, "v");
    if (key == nullptr || value == nullptr) return;
    osm_internal::ApplyWayTag(key, value, way_);
}

double OsmParser::ParseCoordinate(const XML_Char** atts, const char* key, double limit_deg,
                                  std::int64_t node_id) const {
    const std::string where = "node " + std::to_string(node_id) + ": ";
    const char* text = FindAttribute(atts, key);
    if (text == nullptr) Fail(key, where + "attribute missing");
    double value = 0.0;
    if (!ParseWhole(text, &value)) Fail(key, where + "'" + text + "' is not a number");
    if (!std::isfinite(value)) Fail(key, where + "'" + text + "' is not finite");
    if (value < -limit_deg || value > limit_deg) {
        const std::string limit = std::to_string(static_cast<int>(limit_deg));
        Fail(key, where + "'" + text + "' is outside [-" + limit + ", " + limit + "] degrees");
    }
    return value;
}

std::int64_t OsmParser::ParseId(const XML_Char** atts, const char* key, const char* element) const {
    const char* text = FindAttribute(atts, key);
    std::int64_t id = 0;
    if (text == nullptr) Fail(key, std::string("<") + element + "> has no " + key + " attribute");
    if (!ParseWhole(text, &id)) {
        Fail(key, std::string("<") + element + "> " + key + " '" + text + "' is not an integer");
    }
    return id;
}

void OsmParser::Fail(const std::string& key, const std::string& message) const {
    const long line = parser_ ? static_cast<long>(XML_GetCurrentLineNumber(parser_.get())) : 0;
    throw InputError(path_, line, key, message);
}

OsmRoads OsmParser::TakeResult() {
    return osm_internal::ResolveWays(highway_ways_, nodes_, report_);
}

/// An OSM XML file starts with '<' (after any whitespace or a UTF-8 byte order mark); anything
/// else that is not empty is taken for PBF (whose reader says so when it is not). A file that
/// cannot be opened goes to the XML reader, which names the error.
bool LooksLikePbf(const std::string& path) {
    FilePtr file(std::fopen(path.c_str(), "rb"));
    if (!file) return false;
    char head[64];
    const std::size_t size = std::fread(head, 1, sizeof(head), file.get());
    std::size_t i = 0;
    if (size >= 3 && std::memcmp(head, "\xEF\xBB\xBF", 3) == 0) i = 3;
    while (i < size && IsSpace(head[i])) ++i;
    return i < size && head[i] != '<';
}

}  // namespace

OsmRoads ReadOsmRoads(const std::string& path) {
    if (LooksLikePbf(path)) return osm_internal::ReadOsmPbf(path);
    OsmParser parser(path);
    parser.Run();
    return parser.TakeResult();
}

}  // namespace driftcorr
