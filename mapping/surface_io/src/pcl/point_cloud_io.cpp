// PCD and PLY surface clouds through PCL (PRIVATE to driftcorr_surface_io).
#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <new>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "driftcorr/core/check.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/atomic_file.h"
#include "driftcorr/mapping/surface_io.h"
#include "header_text.h"
#include "ply_check.h"

namespace driftcorr {
namespace {

// PCL's readers print their own diagnostics ("[pcl::PCDReader::readHeader] No points to read")
// to stderr; the InputError thrown below, naming the file, is the one message a caller shows, so
// they are silenced while a reader runs (PCL's verbosity is process-wide; readers run on one
// thread at a time here).
class QuietPcl {
public:
    QuietPcl() : level_(pcl::console::getVerbosityLevel()) {
        pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    }
    ~QuietPcl() { pcl::console::setVerbosityLevel(level_); }
    QuietPcl(const QuietPcl&) = delete;
    QuietPcl& operator=(const QuietPcl&) = delete;

private:
    pcl::console::VERBOSITY_LEVEL level_;
};

// PCL's readers throw standard exceptions on some malformed headers (std::out_of_range from a
// number conversion, found by fuzzing) and allocate whatever a header declares: both become
// InputErrors naming the file.
template <typename F>
int CallPcl(const std::string& path, const std::string& kind, F&& read) {
    try {
        return read();
    } catch (const std::bad_alloc&) {
        throw InputError(path, 0, "", kind + " file declares more data than can be held in memory");
    } catch (const InvariantError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path, 0, "",
                         "cannot be parsed as a " + kind + " point cloud: " + e.what());
    }
}

// A point takes at least one byte in any encoding: a header that declares more points than the
// file has bytes is malformed (and would make PCL allocate for them first).
void RequireDeclaredPointsFit(const std::string& path, const std::string& kind, std::size_t count) {
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
    if (!ec && count > bytes) {
        throw InputError(path, 0, "",
                         kind + " header declares " + std::to_string(count) +
                             " points but the file has only " + std::to_string(bytes) + " bytes");
    }
}

// PCL allocates width * height * point_step bytes as the header says. Binary data holds exactly
// that; ASCII may be smaller than binary by at most about 8x (a field of up to 8 bytes written
// in as little as one digit and a separator). More than that is a malformed header.
void RequireDeclaredDataFits(const std::string& path, std::size_t count, std::size_t point_step) {
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
    if (ec) return;
    if (point_step == 0 || count > (8 * bytes + 1024) / point_step) {
        throw InputError(path, 0, "",
                         "PCD header declares " + std::to_string(count) + " points of " +
                             std::to_string(point_step) + " bytes, more than the file (" +
                             std::to_string(bytes) + " bytes) can hold");
    }
}

// PCL's ASCII body reader writes past its point buffer on some malformed bodies (valgrind:
// invalid write in PCDReader::readBodyASCII, found by fuzzing). So the body is checked first:
// exactly `points` lines (empty lines are skipped, as PCL does), each with `elems` numbers
// separated by single blanks; a number is what strtod reads whole (nan and inf included: the
// NaN check names them later).
void PrecheckPcdAsciiBody(const std::string& path, std::istream& in, long header_lines,
                          unsigned long long points, unsigned long long elems) {
    unsigned long long seen = 0;
    long n = header_lines;
    for (std::string line; std::getline(in, line);) {
        ++n;
        if (line.empty()) continue;
        auto bad = [&](const std::string& what) {
            throw InputError(path, n, "", "PCD data: " + what);
        };
        if (++seen > points) bad("more point lines than POINTS (" + std::to_string(points) + ")");
        unsigned long long count = 0;
        std::size_t pos = 0;
        for (;;) {
            const std::size_t end = std::min(line.find(' ', pos), line.size());
            const std::string word = line.substr(pos, end - pos);
            char* stop = nullptr;
            std::strtod(word.c_str(), &stop);
            if (word.empty() || stop != word.c_str() + word.size()) {
                bad("'" + word.substr(0, 20) +
                    "' is not a number (values are separated by single blanks)");
            }
            ++count;
            if (end == line.size()) break;
            pos = end + 1;
        }
        if (count != elems) {
            bad(std::to_string(count) + " values, the header declares " + std::to_string(elems) +
                " per point");
        }
    }
    if (seen != points) {
        throw InputError(path, n, "",
                         "PCD data: " + std::to_string(seen) +
                             " point lines, the header declares " + std::to_string(points));
    }
}

// PCL's compressed reader trusts the sizes at the start of the data: it resizes its buffer to
// the declared uncompressed size and then writes every point (a heap overflow when that is
// smaller). The declared sizes must match the header and the file.
void PrecheckPcdCompressedBody(const std::string& path, std::istream& in,
                               unsigned long long bytes) {
    std::uint32_t sizes[2] = {0, 0};
    const std::streampos start = in.tellg();
    if (start < 0 || !in.read(reinterpret_cast<char*>(sizes), sizeof(sizes))) {
        throw InputError(path, 0, "", "PCD data: binary_compressed data is missing its sizes");
    }
    std::error_code ec;
    const std::uintmax_t file = std::filesystem::file_size(path, ec);
    if (sizes[1] != bytes || (!ec && static_cast<std::uintmax_t>(start) + 8 + sizes[0] > file)) {
        throw InputError(path, 0, "",
                         "PCD data: binary_compressed sizes (" + std::to_string(sizes[0]) +
                             " compressed, " + std::to_string(sizes[1]) +
                             " uncompressed) do not match the header (" + std::to_string(bytes) +
                             " bytes) or the file");
    }
}

// PCL 1.13's PCDReader::readHeader does not stop at the DATA line: it goes on reading lines as
// header until one does not start with a header key, so data that begins with, say, "SIZE" or
// "POINTS" redefines the header after it was checked (an 8 GB allocation from a binary body that
// began "FIELDS x", found by fuzzing). The lines PCL would read after DATA are read here the way
// it reads them: empty lines, comments and VERSION lines are skipped, a line whose first word
// starts with another header key is rejected, anything else ends the header. `in` is left where
// it was.
void PrecheckPcdAfterData(const std::string& path, std::istream& in, long data_line) {
    static const char* kStateKeys[] = {"FIELDS", "COLUMNS", "SIZE",      "TYPE",   "COUNT",
                                       "WIDTH",  "HEIGHT",  "VIEWPOINT", "POINTS", "DATA"};
    const std::streampos start = in.tellg();
    long n = data_line;
    for (std::string line; std::getline(in, line);) {
        ++n;
        if (line.empty()) continue;
        const char* kBlanks = " \t\n\v\f\r";
        const std::size_t begin = line.find_first_not_of(kBlanks);
        if (begin == std::string::npos) break;
        const std::string word = line.substr(begin, line.find_first_of(kBlanks, begin) - begin);
        if (word[0] == '#' || word.rfind("VERSION", 0) == 0) continue;
        for (const char* key : kStateKeys) {
            if (word.rfind(key, 0) == 0) {
                throw InputError(path, n, "",
                                 std::string("PCD data: the line after DATA starts with '") + key +
                                     "', which PCL reads as another header line");
            }
        }
        break;
    }
    in.clear();
    in.seekg(start);
}

// PCL's PCDReader::readHeader misbehaves on malformed headers: it allocates what the header
// declares (8 GB for "SIZE 4 5555555555") and corrupts the heap on some garbled lines (found by
// fuzzing, ASan allocator check in readHeader). So PCL only sees headers validated here first:
// the keys of the PCD v0.7 header, each at most once, in a sane form (FIELDS, SIZE, TYPE and
// COUNT of one length; SIZE 1, 2, 4 or 8; TYPE F, I or U; COUNT 1..4096; WIDTH, HEIGHT, POINTS
// whole numbers with POINTS = WIDTH * HEIGHT; DATA ascii, binary or binary_compressed), the
// declared data must fit the file (RequireDeclaredDataFits) and PCL must stop reading the header
// at DATA (PrecheckPcdAfterData).
void PrecheckPcdHeader(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    auto bad = [&](long line, const std::string& what) {
        throw InputError(path, line, "", "PCD header: " + what);
    };
    std::map<std::string, std::vector<std::string>> keys;
    std::string line;
    long n = 0;
    while (std::getline(in, line) && n < 64) {
        ++n;
        // Only printable ASCII, blanks and tabs: PCL splits lines on "\t\r " only, so any other
        // byte (a NUL, a vertical tab) would make it see other fields than the checks below.
        for (const char c : line) {
            if (!(c == '\t' || c == '\r' || (c >= 0x20 && c <= 0x7e))) {  // tabs: below
                bad(n, "line " + std::to_string(n) + " has a control or non-ASCII byte");
            }
        }
        if (line.empty() || line[0] == '#') continue;
        // PCL counts the empty words around extra blanks, tabs and CRs as entries: "FIELDS x y z "
        // is four fields to it and three here, and it then indexes past its per-field arrays
        // (valgrind: invalid read in PCDReader::readHeader, found by fuzzing). Header lines must
        // be in the form PCL writes them: words separated by single blanks.
        if (line.find_first_of("\t\r") != std::string::npos || line.front() == ' ' ||
            line.back() == ' ' || line.find("  ") != std::string::npos) {
            bad(n, "line " + std::to_string(n) +
                       " is not single-blank separated (no tabs, CR, leading, trailing or double "
                       "blanks in a PCD header)");
        }
        const std::vector<std::string> words = internal::SplitWords(line);
        const std::string& key = words.front();  // the line is not empty and starts with a word
        static const std::set<std::string> kKeys = {"VERSION", "FIELDS", "SIZE",   "TYPE",
                                                    "COUNT",   "WIDTH",  "HEIGHT", "VIEWPOINT",
                                                    "POINTS",  "DATA"};
        if (!kKeys.count(key)) bad(n, "unknown line '" + line.substr(0, 40) + "'");
        if (keys.count(key)) bad(n, key + " given twice");
        keys[key] = std::vector<std::string>(words.begin() + 1, words.end());
        if (key == "DATA") break;
    }
    for (const char* k : {"FIELDS", "SIZE", "TYPE", "WIDTH", "POINTS", "DATA"}) {
        if (!keys.count(k)) bad(0, std::string("no ") + k + " line");
    }
    const std::size_t nf = keys["FIELDS"].size();
    if (nf == 0 || nf > 64 || keys["SIZE"].size() != nf || keys["TYPE"].size() != nf ||
        (keys.count("COUNT") && keys["COUNT"].size() != nf)) {
        bad(0, "FIELDS, SIZE, TYPE and COUNT must list one entry per field");
    }
    for (const std::string& name : keys["FIELDS"]) {
        static const char* kNameChars =
            "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_";
        if (name.find_first_not_of(kNameChars) != std::string::npos) {
            bad(0, "field name '" + name + "' is not made of letters, digits and '_'");
        }
    }
    if (keys.count("VIEWPOINT")) {
        const auto& vp = keys["VIEWPOINT"];
        bool ok = vp.size() == 7;
        for (std::size_t k = 0; ok && k < vp.size(); ++k) {
            char* end = nullptr;
            const double value = std::strtod(vp[k].c_str(), &end);
            ok = end != vp[k].c_str() && *end == '\0' && std::isfinite(value);
        }
        if (!ok) bad(0, "VIEWPOINT must be 7 finite numbers (tx ty tz qw qx qy qz)");
    }
    unsigned long long step = 0, elems = 0;  // bytes and values per point
    for (std::size_t k = 0; k < nf; ++k) {
        const std::string& s = keys["SIZE"][k];
        if (s != "1" && s != "2" && s != "4" && s != "8") bad(0, "SIZE must be 1, 2, 4 or 8");
        const std::string& type = keys["TYPE"][k];
        if (type != "F" && type != "I" && type != "U") bad(0, "TYPE must be F, I or U");
        unsigned long long count = 1;
        if (keys.count("COUNT") &&
            (!internal::ParseWholeNumber(keys["COUNT"][k], 4096, count) || count < 1)) {
            bad(0, "COUNT must be 1..4096");
        }
        step += std::stoull(s) * count;
        elems += count;
    }
    unsigned long long width = 0, height = 1, points = 0;
    auto whole = [&](const char* key, unsigned long long& value) {
        return keys[key].size() == 1 && internal::ParseWholeNumber(keys[key][0], 1ULL << 40, value);
    };
    if (!whole("WIDTH", width)) bad(0, "bad WIDTH");
    if (keys.count("HEIGHT") && !whole("HEIGHT", height)) bad(0, "bad HEIGHT");
    if (!whole("POINTS", points) || points != width * height) {
        bad(0, "POINTS must be a whole number equal to WIDTH * HEIGHT");
    }
    const auto& data = keys["DATA"];
    if (data.size() != 1 ||
        (data[0] != "ascii" && data[0] != "binary" && data[0] != "binary_compressed")) {
        bad(0, "DATA must be ascii, binary or binary_compressed");
    }
    RequireDeclaredDataFits(path, std::size_t(points), std::size_t(step));
    PrecheckPcdAfterData(path, in, n);
    if (data[0] == "ascii") PrecheckPcdAsciiBody(path, in, n, points, elems);
    if (data[0] == "binary_compressed") PrecheckPcdCompressedBody(path, in, points * step);
}

bool HasField(const pcl::PCLPointCloud2& cloud, const std::string& name) {
    return std::any_of(cloud.fields.begin(), cloud.fields.end(),
                       [&](const pcl::PCLPointField& f) { return f.name == name; });
}

// One value of a PCL field type at `at` (unaligned), as a double; nullopt for a type PCL 1.13
// does not define.
template <typename T>
double Load(const std::uint8_t* at) {
    T value;
    std::memcpy(&value, at, sizeof(T));
    return static_cast<double>(value);
}

std::optional<double> FieldValue(const std::uint8_t* at, std::uint8_t datatype) {
    switch (datatype) {
        case pcl::PCLPointField::INT8:
            return Load<std::int8_t>(at);
        case pcl::PCLPointField::UINT8:
            return Load<std::uint8_t>(at);
        case pcl::PCLPointField::INT16:
            return Load<std::int16_t>(at);
        case pcl::PCLPointField::UINT16:
            return Load<std::uint16_t>(at);
        case pcl::PCLPointField::INT32:
            return Load<std::int32_t>(at);
        case pcl::PCLPointField::UINT32:
            return Load<std::uint32_t>(at);
        case pcl::PCLPointField::FLOAT32:
            return Load<float>(at);
        case pcl::PCLPointField::FLOAT64:
            return Load<double>(at);
        default:
            return std::nullopt;
    }
}

// Checks and converts a cloud read from `path` (`kind` names the format in messages).
std::vector<Eigen::Vector3d> ToSurfacePoints(const pcl::PCLPointCloud2& blob,
                                             const std::string& path, const std::string& kind) {
    for (const char* axis : {"x", "y", "z"}) {
        if (!HasField(blob, axis)) {
            throw InputError(path, 0, "", kind + " file has no '" + axis + "' field");
        }
    }
    // PCL converts without checking that the data matches the header: an empty cloud makes it
    // index an empty vector (UBSan: reference binding to null), a short buffer or a field past the
    // point's end makes it read out of bounds. Check all three before converting.
    const std::size_t count = std::size_t(blob.width) * std::size_t(blob.height);
    if (count == 0) throw InputError(path, 0, "", kind + " file has no points");
    if (blob.point_step == 0 || blob.data.size() < count * std::size_t(blob.point_step)) {
        throw InputError(path, 0, "", kind + " file holds less point data than its header says");
    }
    for (const pcl::PCLPointField& f : blob.fields) {
        const std::size_t end = std::size_t(f.offset) + std::size_t(pcl::getFieldSize(f.datatype)) *
                                                            std::max<std::size_t>(1, f.count);
        if (end > blob.point_step) {
            throw InputError(path, 0, "",
                             kind + " file field '" + f.name + "' lies outside its point");
        }
    }
    // Converted here, not by pcl::fromPCLPointCloud2: that one matches fields by type as well as
    // name and leaves x, y, z at 0 when the file stores them as doubles (measured: a PLY or PCD
    // with double coordinates read as all zeros).
    std::array<const pcl::PCLPointField*, 3> xyz{};
    for (const pcl::PCLPointField& f : blob.fields) {
        if (f.name == "x") xyz[0] = &f;
        if (f.name == "y") xyz[1] = &f;
        if (f.name == "z") xyz[2] = &f;
    }
    std::vector<Eigen::Vector3d> points;
    points.reserve(count);
    std::size_t bad = 0, first_bad = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const std::uint8_t* point = blob.data.data() + i * std::size_t(blob.point_step);
        Eigen::Vector3d p;
        for (int k = 0; k < 3; ++k) {
            const std::optional<double> v = FieldValue(point + xyz[k]->offset, xyz[k]->datatype);
            if (!v) {
                throw InputError(path, 0, "",
                                 kind + " field '" + xyz[k]->name + "' has an unsupported type");
            }
            p[k] = *v;
        }
        if (!p.allFinite()) {
            if (bad++ == 0) first_bad = i;
            continue;
        }
        points.push_back(p);
    }
    if (bad > 0) {
        throw InputError(path, 0, "",
                         kind + " file has " + std::to_string(bad) + " of " +
                             std::to_string(count) +
                             " points with a NaN or infinite coordinate (first at index " +
                             std::to_string(first_bad) + "); a surface map must be dense");
    }
    return points;
}

void RequireReadable(const std::string& path, const std::string& kind) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        throw InputError(path, 0, "", kind + " file does not exist or is not a regular file");
    }
}

pcl::PointCloud<pcl::PointXYZ> ToCloud(const std::vector<Eigen::Vector3d>& points) {
    pcl::PointCloud<pcl::PointXYZ> cloud;
    cloud.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector3f p = points[i].cast<float>();
        cloud[i] = pcl::PointXYZ(p.x(), p.y(), p.z());
    }
    cloud.width = static_cast<std::uint32_t>(points.size());
    cloud.height = 1;
    cloud.is_dense = true;
    return cloud;
}

std::string LowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

}  // namespace

std::vector<Eigen::Vector3d> ReadSurfacePointsPcd(const std::string& path) {
    const QuietPcl quiet;
    RequireReadable(path, "PCD");
    pcl::PCLPointCloud2 blob;
    pcl::PCDReader reader;
    // The header first: PCL 1.13's read() crashes on some malformed files (no FIELDS line), so
    // the body is read only when the header has x, y, z fields and at least one point.
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0, data_type = 0;
    unsigned int data_idx = 0;
    PrecheckPcdHeader(path);
    if (CallPcl(path, "PCD", [&] {
            return reader.readHeader(path, blob, origin, orientation, version, data_type, data_idx);
        }) < 0) {
        throw InputError(path, 0, "", "cannot be read or parsed as a PCD point cloud (header)");
    }
    for (const char* axis : {"x", "y", "z"}) {
        if (!HasField(blob, axis)) {
            throw InputError(path, 0, "", std::string("PCD file has no '") + axis + "' field");
        }
    }
    if (std::size_t(blob.width) * blob.height == 0) {
        throw InputError(path, 0, "", "PCD file has no points");
    }
    RequireDeclaredPointsFit(path, "PCD", std::size_t(blob.width) * blob.height);
    RequireDeclaredDataFits(path, std::size_t(blob.width) * blob.height, blob.point_step);
    if (CallPcl(path, "PCD", [&] { return reader.read(path, blob); }) < 0) {
        throw InputError(path, 0, "", "cannot be read or parsed as a PCD point cloud");
    }
    return ToSurfacePoints(blob, path, "PCD");
}

std::vector<Eigen::Vector3d> ReadSurfacePointsPly(const std::string& path) {
    const QuietPcl quiet;
    RequireReadable(path, "PLY");
    const internal::PlyLayout layout = internal::PrecheckPly(path);
    pcl::PCLPointCloud2 blob;
    pcl::PLYReader reader;
    if (CallPcl(path, "PLY", [&] { return reader.read(path, blob); }) < 0) {
        throw InputError(path, 0, "", "cannot be read or parsed as a PLY point cloud");
    }
    // A camera element's viewport (or obj_info) makes PCL shape the cloud as width x height: a
    // shape that is not the vertex count would drop points or read past them.
    if (std::size_t(blob.width) * blob.height != layout.vertex_count) {
        throw InputError(path, 0, "",
                         "PLY camera viewport " + std::to_string(blob.width) + " x " +
                             std::to_string(blob.height) + " does not match the " +
                             std::to_string(layout.vertex_count) + " vertices");
    }
    return ToSurfacePoints(blob, path, "PLY");
}

std::vector<Eigen::Vector3d> ReadSurfacePoints(const std::string& path) {
    const std::string ext = LowerExtension(path);
    if (ext == ".pcd") return ReadSurfacePointsPcd(path);
    if (ext == ".ply") return ReadSurfacePointsPly(path);
    if (ext == ".bt" || ext == ".ot") return ReadFloorVoxelsOctomap(path);
    throw InputError(path, 0, "",
                     "unknown surface map extension '" + ext + "' (expected .pcd, .ply, .bt, .ot)");
}

std::vector<Eigen::Vector3d> ReadRawPoints(const std::string& path, double* voxel_m) {
    const std::string ext = LowerExtension(path);
    if (voxel_m) *voxel_m = 0.0;
    if (ext == ".pcd") return ReadSurfacePointsPcd(path);
    if (ext == ".ply") return ReadSurfacePointsPly(path);
    if (ext == ".bt" || ext == ".ot") return ReadOccupiedVoxelsOctomap(path, voxel_m);
    throw InputError(path, 0, "",
                     "unknown map extension '" + ext + "' (expected .pcd, .ply, .bt, .ot)");
}

void WriteSurfacePointsPcd(const std::string& path, const std::vector<Eigen::Vector3d>& points) {
    WriteAtomically(path, [&](const std::string& tmp) {
        if (pcl::io::savePCDFileBinary(tmp, ToCloud(points)) < 0) {
            throw std::runtime_error(path + ": cannot write PCD");
        }
    });
}

void WriteSurfacePointsPly(const std::string& path, const std::vector<Eigen::Vector3d>& points) {
    WriteAtomically(path, [&](const std::string& tmp) {
        if (pcl::io::savePLYFileBinary(tmp, ToCloud(points)) < 0) {
            throw std::runtime_error(path + ": cannot write PLY");
        }
    });
}

}  // namespace driftcorr
