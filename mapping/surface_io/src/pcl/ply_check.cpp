// Validation of a PLY file before PCL reads it: see ply_check.h for why and what is accepted.
#include "ply_check.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include "driftcorr/core/errors.h"
#include "header_text.h"

namespace driftcorr::internal {
namespace {

constexpr long kMaxHeaderLines = 4096;
constexpr std::size_t kMaxHeaderLineChars = 4096;
constexpr unsigned long long kMaxCount = 1ULL << 40;  // elements and list lengths

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyType {
    int bytes = 0;
    bool is_float = false;
    bool is_signed = false;
};

// The PLY 1.0 type names and the sized names PCL also accepts.
std::optional<PlyType> TypeNamed(const std::string& name) {
    static const std::array<std::pair<const char*, PlyType>, 16> kTypes = {{
        {"char", {1, false, true}},
        {"int8", {1, false, true}},
        {"uchar", {1, false, false}},
        {"uint8", {1, false, false}},
        {"short", {2, false, true}},
        {"int16", {2, false, true}},
        {"ushort", {2, false, false}},
        {"uint16", {2, false, false}},
        {"int", {4, false, true}},
        {"int32", {4, false, true}},
        {"uint", {4, false, false}},
        {"uint32", {4, false, false}},
        {"float", {4, true, true}},
        {"float32", {4, true, true}},
        {"double", {8, true, true}},
        {"float64", {8, true, true}},
    }};
    for (const auto& [type_name, type] : kTypes) {
        if (name == type_name) return type;
    }
    return std::nullopt;
}

struct Property {
    std::string name;
    std::string type_name;  // as written, for the colour rule (PCL special-cases uchar)
    PlyType type;
    bool is_list = false;
    PlyType count_type;  // lists only
};

struct Element {
    std::string name;
    unsigned long long count = 0;
    long line = 0;
    std::vector<Property> properties;
    bool HasList() const {
        return std::any_of(properties.begin(), properties.end(),
                           [](const Property& p) { return p.is_list; });
    }
};

struct Header {
    PlyFormat format = PlyFormat::kAscii;
    std::vector<Element> elements;
    long lines = 0;                                        // header lines, end_header included
    std::streamoff body_start = 0;                         // byte offset of the first body byte
    std::optional<unsigned long long> num_cols, num_rows;  // obj_info
    long obj_info_line = 0;
};

bool IsName(const std::string& s) {
    return !s.empty() && s.find_first_not_of(
                             "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                             "0123456789_-.") == std::string::npos;
}

class HeaderParser {
public:
    explicit HeaderParser(const std::string& path) : path_(path) {}

    Header Parse(std::istream& in) {
        std::string line;
        while (ReadLine(in, line)) {
            ++header_.lines;
            CheckCharacters(line);
            if (header_.lines == 1) {
                if (line != "ply") Bad("the first line must be 'ply'");
                continue;
            }
            if (header_.lines == 2) {
                ParseFormat(line);
                continue;
            }
            if (line == "end_header") {
                if (!line_ended_)
                    Bad("the file ends right after 'end_header' (no line end, no data)");
                header_.body_start = in.tellg();
                return header_;
            }
            ParseLine(line);
        }
        if (header_.lines == 0) Bad("the file is empty (a PLY file starts with a 'ply' line)");
        Bad("no 'end_header' line within the first " + std::to_string(kMaxHeaderLines) + " lines");
        return header_;
    }

private:
    [[noreturn]] void Bad(const std::string& what) const {
        throw InputError(path_, header_.lines, "", "PLY header: " + what);
    }

    bool ReadLine(std::istream& in, std::string& line) {
        if (header_.lines >= kMaxHeaderLines) return false;
        line.clear();
        line_ended_ = false;
        for (int c; (c = in.get()) != EOF;) {
            if (c == '\n') return line_ended_ = true;
            if (line.size() >= kMaxHeaderLineChars) {
                ++header_.lines;
                Bad("line longer than " + std::to_string(kMaxHeaderLineChars) + " characters");
            }
            line.push_back(char(c));
        }
        return !line.empty();
    }

    // PCL splits on blanks and compares words; it also hands an obj_info line to a callback that
    // asserts the line starts with the keyword. So: printable ASCII, no leading, trailing or
    // double blanks (comment text excepted), LF line ends.
    void CheckCharacters(const std::string& line) const {
        for (const char c : line) {
            if (c == '\r') Bad("CR before the line end (Windows line ends): PLY lines end with LF");
            if (c < 0x20 || c > 0x7e) Bad("a control or non-ASCII byte in the header");
        }
        const bool free_text = line.rfind("comment", 0) == 0 || line.rfind("obj_info", 0) == 0;
        if (line.empty() || line.front() == ' ' ||
            (!free_text && (line.back() == ' ' || line.find("  ") != std::string::npos))) {
            Bad("'" + line.substr(0, 60) +
                "': header lines are words separated by single blanks, without leading blanks");
        }
    }

    void ParseFormat(const std::string& line) {
        const std::vector<std::string> w = SplitWords(line);
        if (w.size() != 3 || w[0] != "format" || w[2] != "1.0") {
            Bad("the second line must be 'format <ascii|binary_little_endian|binary_big_endian> "
                "1.0'");
        }
        if (w[1] == "ascii") {
            header_.format = PlyFormat::kAscii;
        } else if (w[1] == "binary_little_endian") {
            header_.format = PlyFormat::kBinaryLittleEndian;
        } else if (w[1] == "binary_big_endian") {
            header_.format = PlyFormat::kBinaryBigEndian;
        } else {
            Bad("unknown format '" + w[1] + "'");
        }
    }

    void ParseLine(const std::string& line) {
        const std::vector<std::string> w = SplitWords(line);
        if (w[0] == "comment") return;
        if (w[0] == "obj_info") return ParseObjInfo(w);
        if (w[0] == "element") return ParseElement(w);
        if (w[0] == "property") return ParseProperty(w);
        Bad("unknown line '" + line.substr(0, 60) +
            "' (expected comment, obj_info, element, property or end_header)");
    }

    // PCL makes an organised cloud of num_cols x num_rows from these: they must describe the
    // vertices (checked once the vertex count is known).
    void ParseObjInfo(const std::vector<std::string>& w) {
        if (w.size() < 2 || (w[1] != "num_cols" && w[1] != "num_rows")) return;
        std::optional<unsigned long long>& slot =
            w[1] == "num_cols" ? header_.num_cols : header_.num_rows;
        unsigned long long value = 0;
        if (w.size() != 3 ||
            !ParseWholeNumber(w[2], std::numeric_limits<std::int32_t>::max(), value)) {
            Bad("obj_info " + w[1] + " must be followed by one whole number");
        }
        if (slot) Bad("obj_info " + w[1] + " given twice");
        slot = value;
        header_.obj_info_line = header_.lines;
    }

    void ParseElement(const std::vector<std::string>& w) {
        unsigned long long count = 0;
        if (w.size() != 3 || !IsName(w[1]) || !ParseWholeNumber(w[2], kMaxCount, count)) {
            Bad("an element line is 'element <name> <count>' (a name of letters, digits, '_', "
                "'-', '.', a whole count up to 2^40)");
        }
        for (const Element& e : header_.elements) {
            if (e.name == w[1]) Bad("element '" + w[1] + "' declared twice");
        }
        if (w[1] == "range_grid") {
            Bad("element 'range_grid' (a scanner's organised grid) is not supported: remove it");
        }
        header_.elements.push_back(Element{w[1], count, header_.lines, {}});
    }

    void ParseProperty(const std::vector<std::string>& w) {
        if (header_.elements.empty()) Bad("a property before the first element");
        Element& element = header_.elements.back();
        Property p;
        const bool list = w.size() == 5 && w[1] == "list";
        if (!list && w.size() != 3) {
            Bad("a property line is 'property <type> <name>' or 'property list <count type> <type> "
                "<name>'");
        }
        p.is_list = list;
        p.name = w.back();
        p.type_name = w[w.size() - 2];
        const std::optional<PlyType> type = TypeNamed(p.type_name);
        if (!type) Bad("unknown property type '" + p.type_name + "'");
        p.type = *type;
        if (list) {
            const std::optional<PlyType> count_type = TypeNamed(w[2]);
            if (!count_type || count_type->is_float) {
                Bad("a list's count type must be an integer type, not '" + w[2] + "'");
            }
            p.count_type = *count_type;
        }
        if (!IsName(p.name))
            Bad("property name '" + p.name + "' is not made of letters, digits, '_', '-', '.'");
        for (const Property& q : element.properties) {
            if (q.name == p.name)
                Bad("property '" + p.name + "' declared twice in '" + element.name + "'");
        }
        if (element.properties.size() >= 1024) Bad("more than 1024 properties in one element");
        element.properties.push_back(p);
    }

    const std::string& path_;
    Header header_;
    bool line_ended_ = false;
};

// PCL's colour handling on uchar vertex properties: `red` adds an rgb field, `blue` writes it,
// `alpha` turns it into rgba. Any other arrangement makes it write past the point or assert.
void CheckVertexColours(const std::string& path, const Element& vertex) {
    static const std::set<std::string> kColour = {
        "red", "green", "blue", "diffuse_red", "diffuse_green", "diffuse_blue", "alpha"};
    std::vector<std::string> seen;
    std::vector<std::size_t> at;
    for (std::size_t k = 0; k < vertex.properties.size(); ++k) {
        const Property& p = vertex.properties[k];
        if ((p.type_name == "uchar" || p.type_name == "uint8") && kColour.count(p.name)) {
            seen.push_back(p.name);
            at.push_back(k);
        }
    }
    if (seen.empty()) return;
    const std::vector<std::vector<std::string>> kAllowed = {
        {"red", "green", "blue"},
        {"red", "green", "blue", "alpha"},
        {"diffuse_red", "diffuse_green", "diffuse_blue"},
        {"diffuse_red", "diffuse_green", "diffuse_blue", "alpha"}};
    const bool consecutive = at.back() - at.front() + 1 == at.size();
    if (!consecutive || std::find(kAllowed.begin(), kAllowed.end(), seen) == kAllowed.end()) {
        throw InputError(path, vertex.line, "",
                         "PLY header: uchar colour properties of the vertex must be 'red green "
                         "blue' (or diffuse_*), one after the other, with an optional 'alpha' "
                         "after them");
    }
}

void CheckVertexElement(const std::string& path, const Header& header) {
    const auto vertex = std::find_if(header.elements.begin(), header.elements.end(),
                                     [](const Element& e) { return e.name == "vertex"; });
    if (vertex == header.elements.end()) {
        throw InputError(path, 0, "", "PLY header: no 'element vertex' (the points)");
    }
    for (const char* axis : {"x", "y", "z"}) {
        if (std::none_of(vertex->properties.begin(), vertex->properties.end(),
                         [&](const Property& p) { return p.name == axis; })) {
            throw InputError(path, vertex->line, "",
                             std::string("PLY file has no '") + axis + "' vertex property");
        }
    }
    for (const Property& p : vertex->properties) {
        if (p.is_list) {
            throw InputError(path, vertex->line, "",
                             "PLY header: list property '" + p.name +
                                 "' in the vertex element is not supported");
        }
    }
    CheckVertexColours(path, *vertex);
    if (vertex->count == 0) throw InputError(path, 0, "", "PLY file has no points");
    if (header.num_cols || header.num_rows) {
        if (!header.num_cols || !header.num_rows ||
            *header.num_cols * *header.num_rows != vertex->count) {
            throw InputError(path, header.obj_info_line, "",
                             "PLY header: obj_info num_cols and num_rows must both be given and "
                             "multiply to the vertex count (" +
                                 std::to_string(vertex->count) + ")");
        }
    }
    for (const Element& e : header.elements) {
        if (e.properties.empty() && e.count > 0) {
            throw InputError(
                path, e.line, "",
                "PLY header: element '" + e.name + "' has instances but no properties");
        }
    }
}

// One ASCII token of `type`: integers in the type's range, floats as strtod reads them whole.
bool AsciiValue(const std::string& token, const PlyType& type, long long* integer) {
    if (type.is_float) {
        char* end = nullptr;
        std::strtod(token.c_str(), &end);
        return end == token.c_str() + token.size() && !token.empty();
    }
    const std::size_t digits = (token[0] == '-' || token[0] == '+') ? 1 : 0;
    if (token.size() == digits || token.size() > 12 ||
        token.find_first_not_of("0123456789", digits) != std::string::npos) {
        return false;
    }
    const long long v = std::strtoll(token.c_str(), nullptr, 10);
    const int bits = 8 * type.bytes;
    const long long lo = type.is_signed ? -(1LL << (bits - 1)) : 0;
    const long long hi = type.is_signed ? (1LL << (bits - 1)) - 1 : (1LL << bits) - 1;
    if (integer) *integer = v;
    return v >= lo && v <= hi;
}

void CheckAsciiBody(const std::string& path, std::istream& in, const Header& header) {
    long n = header.lines;
    std::string line;
    for (const Element& e : header.elements) {
        for (unsigned long long i = 0; i < e.count; ++i) {
            ++n;
            if (!std::getline(in, line)) {
                throw InputError(path, n, "",
                                 "PLY data: the file ends in element '" + e.name + "' after " +
                                     std::to_string(i) + " of " + std::to_string(e.count) +
                                     " lines");
            }
            auto bad = [&](const std::string& what) {
                throw InputError(path, n, "", "PLY data: " + what + " (element '" + e.name + "')");
            };
            for (const char c : line) {
                if (c != '\t' && (c < 0x20 || c > 0x7e)) bad("a control or non-ASCII byte");
            }
            const std::vector<std::string> tokens = SplitWords(line);
            std::size_t t = 0;
            for (const Property& p : e.properties) {
                long long count = 1;
                if (p.is_list) {
                    if (t >= tokens.size() || !AsciiValue(tokens[t], p.count_type, &count) ||
                        count < 0) {
                        bad("list '" + p.name + "' needs a count first");
                    }
                    ++t;
                }
                for (long long k = 0; k < count; ++k, ++t) {
                    if (t >= tokens.size()) bad("fewer values than the header declares");
                    if (!AsciiValue(tokens[t], p.type, nullptr)) {
                        bad("'" + tokens[t].substr(0, 20) + "' is not a " + p.type_name);
                    }
                }
            }
            if (t != tokens.size()) bad("more values than the header declares");
        }
    }
    while (std::getline(in, line)) {
        ++n;
        if (line.find_first_not_of(" \t") != std::string::npos) {
            throw InputError(path, n, "", "PLY data: more lines than the header declares");
        }
    }
}

// Walks the binary body: skips are arithmetic; a list count is read where it lies, moving the
// stream forward by reading through its buffer when the gap is small (a seek per count would
// discard the buffer: measured 1.06 s of system time for 2 M faces).
class BinaryCursor {
public:
    BinaryCursor(std::istream& in, std::streamoff base, unsigned long long size)
        : in_(in), base_(base), size_(size) {
        in_.seekg(base_);
    }
    unsigned long long position() const { return pos_; }
    bool Skip(unsigned long long bytes) {
        if (bytes > size_ - pos_) return false;
        pos_ += bytes;
        return true;
    }
    bool ReadCount(const PlyType& type, bool big_endian, long long& value) {
        unsigned char raw[8] = {};
        if (std::uint64_t(type.bytes) > size_ - pos_) return false;
        const unsigned long long gap = pos_ - stream_at_;
        if (gap > 65536) {
            in_.seekg(std::streamoff(base_ + pos_));
        } else if (gap > 0) {
            in_.ignore(std::streamsize(gap));
        }
        if (!in_.read(reinterpret_cast<char*>(raw), type.bytes)) return false;
        pos_ += type.bytes;
        stream_at_ = pos_;
        std::uint64_t u = 0;
        for (int k = 0; k < type.bytes; ++k) {
            const int shift = 8 * (big_endian ? type.bytes - 1 - k : k);
            u |= std::uint64_t(raw[k]) << shift;
        }
        const int bits = 8 * type.bytes;
        if (type.is_signed && (u >> (bits - 1)) & 1U) {
            value = static_cast<long long>(u) - (1LL << bits);
        } else {
            value = static_cast<long long>(u);
        }
        return true;
    }

private:
    std::istream& in_;
    std::streamoff base_;
    unsigned long long size_;
    unsigned long long pos_ = 0;        // where the walk is, from the body's start
    unsigned long long stream_at_ = 0;  // where the stream is, from the body's start
};

void CheckBinaryBody(const std::string& path, std::istream& in, const Header& header) {
    in.seekg(0, std::ios::end);
    const std::streamoff end = in.tellg();
    const unsigned long long size = end > header.body_start ? end - header.body_start : 0;
    BinaryCursor cursor(in, header.body_start, size);
    const bool big = header.format == PlyFormat::kBinaryBigEndian;
    for (const Element& e : header.elements) {
        auto short_body = [&](unsigned long long i) {
            throw InputError(path, 0, "",
                             "PLY data: the file ends in element '" + e.name + "' (instance " +
                                 std::to_string(i) + " of " + std::to_string(e.count) + ")");
        };
        if (!e.HasList()) {
            unsigned long long bytes = 0;
            for (const Property& p : e.properties) bytes += p.type.bytes;
            if (e.count > (size - cursor.position()) / std::max<unsigned long long>(bytes, 1)) {
                short_body((size - cursor.position()) / std::max<unsigned long long>(bytes, 1));
            }
            cursor.Skip(e.count * bytes);
            continue;
        }
        for (unsigned long long i = 0; i < e.count; ++i) {
            for (const Property& p : e.properties) {
                long long count = 1;
                if (p.is_list && !cursor.ReadCount(p.count_type, big, count)) short_body(i);
                if (count < 0) {
                    throw InputError(path, 0, "",
                                     "PLY data: negative count " + std::to_string(count) +
                                         " in list '" + p.name + "'");
                }
                if (!cursor.Skip(static_cast<unsigned long long>(count) * p.type.bytes))
                    short_body(i);
            }
        }
    }
    if (cursor.position() != size) {
        throw InputError(path, 0, "",
                         "PLY data: " + std::to_string(size - cursor.position()) +
                             " bytes after the last element the header declares");
    }
}

}  // namespace

PlyLayout PrecheckPly(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "", "cannot open the PLY file");
    const Header header = HeaderParser(path).Parse(in);
    CheckVertexElement(path, header);
    if (header.format == PlyFormat::kAscii) {
        CheckAsciiBody(path, in, header);
    } else {
        CheckBinaryBody(path, in, header);
    }
    PlyLayout layout;
    for (const Element& e : header.elements) {
        if (e.name == "vertex") layout.vertex_count = e.count;
    }
    return layout;
}

}  // namespace driftcorr::internal
