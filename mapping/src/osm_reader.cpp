// OpenStreetMap XML reader on expat (linked PRIVATE; no expat type leaves this file).
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

namespace driftcorr {
namespace {

constexpr std::size_t kReadBlockBytes = 64 * 1024;

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

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

/// [begin, end) of `s` without leading and trailing whitespace.
std::pair<const char*, const char*> Trim(const char* s) {
    const char* begin = s;
    const char* end = s + std::strlen(s);
    while (begin < end && IsSpace(*begin)) ++begin;
    while (end > begin && IsSpace(end[-1])) --end;
    return {begin, end};
}

/// Locale-independent parse of the whole (trimmed) string as T; false on any trailing junk.
template <typename T>
bool ParseWhole(const char* s, T* out) {
    const auto [begin, end] = Trim(s);
    if (begin == end) return false;
    const auto result = std::from_chars(begin, end, *out);
    return result.ec == std::errc() && result.ptr == end;
}

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
    std::unordered_map<std::int64_t, LatLon> nodes_;
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
    if (std::strcmp(key, "highway") == 0) {
        way_.has_highway = true;
        way_.highway = value;
    } else if (std::strcmp(key, "width") == 0) {
        way_.width_m = ParseWidthM(value);
    } else if (std::strcmp(key, "lanes") == 0) {
        way_.lanes = ParseLanes(value);
    } else if (std::strcmp(key, "area") == 0) {
        way_.is_area = std::strcmp(value, "yes") == 0;
    }
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
    OsmRoads roads;
    roads.report = report_;
    roads.ways.reserve(highway_ways_.size());
    for (RawWay& raw : highway_ways_) {
        OsmWay way;
        way.id = raw.id;
        way.highway = std::move(raw.highway);
        way.width_m = raw.width_m;
        way.lanes = raw.lanes;
        way.is_area = raw.is_area;
        way.nodes.reserve(raw.refs.size());
        for (const std::int64_t ref : raw.refs) {
            const auto it = nodes_.find(ref);
            if (it == nodes_.end()) {
                ++roads.report.missing_node_refs;
                continue;
            }
            way.nodes.push_back(GeoPoint{it->second.lat_deg, it->second.lon_deg, 0.0});
        }
        if (way.nodes.size() < 2) {
            ++roads.report.ways_too_short;
            continue;
        }
        roads.ways.push_back(std::move(way));
    }
    roads.report.ways_highway = roads.ways.size();
    return roads;
}

}  // namespace

OsmRoads ReadOsmRoads(const std::string& path) {
    OsmParser parser(path);
    parser.Run();
    return parser.TakeResult();
}

}  // namespace driftcorr
