// PCD and PLY surface clouds through PCL (PRIVATE to driftcorr_mapping_pcl).
#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <new>
#include <sstream>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/surface_io.h"

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
    } catch (const std::exception& e) {
        throw InputError(path, 0, "", "cannot be parsed as a " + kind + " point cloud: " + e.what());
    }
}

// A point takes at least one byte in any encoding: a header that declares more points than the
// file has bytes is malformed (and would make PCL allocate for them first).
void RequireDeclaredPointsFit(const std::string& path, const std::string& kind, std::size_t count) {
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
    if (!ec && count > bytes) {
        throw InputError(path, 0, "", kind + " header declares " + std::to_string(count) +
                                          " points but the file has only " +
                                          std::to_string(bytes) + " bytes");
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

// PCL's PCDReader::readHeader already allocates width * height * point_step bytes as the header
// declares (found by fuzzing: 8 GB for "SIZE 4 5555555555"), so the header is bounded here first:
// SIZE values 1, 2, 4 or 8, COUNT values 1..4096, and the declared data must fit the file (see
// RequireDeclaredDataFits). Malformed numbers are left to PCL's own parser, which rejects them.
void PrecheckPcdHeader(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<long long> sizes, counts;
    long long width = 1, height = 1, points = -1;
    std::string line;
    for (int n = 0; n < 64 && std::getline(in, line); ++n) {
        std::istringstream words(line);
        std::string key;
        if (!(words >> key)) continue;
        std::vector<long long> values;
        for (long long v; words >> v;) values.push_back(v);
        if (key == "SIZE") sizes = values;
        else if (key == "COUNT") counts = values;
        else if (key == "WIDTH" && !values.empty()) width = values[0];
        else if (key == "HEIGHT" && !values.empty()) height = values[0];
        else if (key == "POINTS" && !values.empty()) points = values[0];
        else if (key == "DATA") break;
    }
    long long step = 0;
    for (std::size_t k = 0; k < sizes.size(); ++k) {
        const long long count = k < counts.size() ? counts[k] : 1;
        const long long s = sizes[k];
        if ((s != 1 && s != 2 && s != 4 && s != 8) || count < 1 || count > 4096) {
            throw InputError(path, 0, "", "PCD header: field " + std::to_string(k) + " has SIZE " +
                                              std::to_string(s) + ", COUNT " + std::to_string(count));
        }
        step += s * count;
    }
    const long long declared = points >= 0 ? points : width * height;
    if (width < 0 || height < 0 || declared < 0) {
        throw InputError(path, 0, "", "PCD header: negative WIDTH, HEIGHT or POINTS");
    }
    if (step > 0) RequireDeclaredDataFits(path, std::size_t(declared), std::size_t(step));
}

// The vertex count of a PLY header ("element vertex N"), 0 when absent; a negative or
// unparseable count is an InputError.
std::size_t PlyVertexCount(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    for (int n = 0; n < 200 && std::getline(in, line); ++n) {
        if (line.rfind("end_header", 0) == 0) break;
        std::istringstream words(line);
        std::string element, name;
        long long count = -1;
        if (!(words >> element >> name) || element != "element" || name != "vertex") continue;
        if (!(words >> count) || count < 0) {
            throw InputError(path, n + 1, "", "PLY header: bad vertex count in '" + line + "'");
        }
        return static_cast<std::size_t>(count);
    }
    return 0;
}

bool HasField(const pcl::PCLPointCloud2& cloud, const std::string& name) {
    return std::any_of(cloud.fields.begin(), cloud.fields.end(),
                       [&](const pcl::PCLPointField& f) { return f.name == name; });
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
        const std::size_t end = std::size_t(f.offset) +
                                std::size_t(pcl::getFieldSize(f.datatype)) * std::max<std::size_t>(1, f.count);
        if (end > blob.point_step) {
            throw InputError(path, 0, "", kind + " file field '" + f.name + "' lies outside its point");
        }
    }
    pcl::PointCloud<pcl::PointXYZ> cloud;
    pcl::fromPCLPointCloud2(blob, cloud);
    if (cloud.empty()) throw InputError(path, 0, "", kind + " file has no points");
    std::vector<Eigen::Vector3d> points;
    points.reserve(cloud.size());
    std::size_t bad = 0, first_bad = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud[i].getVector3fMap().cast<double>();
        if (!p.allFinite()) {
            if (bad++ == 0) first_bad = i;
            continue;
        }
        points.push_back(p);
    }
    if (bad > 0) {
        throw InputError(path, 0, "",
                         kind + " file has " + std::to_string(bad) + " of " +
                             std::to_string(cloud.size()) +
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

void RenameInto(const std::string& tmp, const std::string& path) {
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw std::runtime_error(path + ": cannot rename from " + tmp + ": " + ec.message());
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
    RequireDeclaredPointsFit(path, "PLY", PlyVertexCount(path));
    pcl::PCLPointCloud2 blob;
    pcl::PLYReader reader;
    if (CallPcl(path, "PLY", [&] { return reader.read(path, blob); }) < 0) {
        throw InputError(path, 0, "", "cannot be read or parsed as a PLY point cloud");
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

void WriteSurfacePointsPcd(const std::string& path, const std::vector<Eigen::Vector3d>& points) {
    const std::string tmp = path + ".tmp";
    if (pcl::io::savePCDFileBinary(tmp, ToCloud(points)) < 0) {
        throw std::runtime_error(tmp + ": cannot write PCD");
    }
    RenameInto(tmp, path);
}

void WriteSurfacePointsPly(const std::string& path, const std::vector<Eigen::Vector3d>& points) {
    const std::string tmp = path + ".tmp";
    if (pcl::io::savePLYFileBinary(tmp, ToCloud(points)) < 0) {
        throw std::runtime_error(tmp + ": cannot write PLY");
    }
    RenameInto(tmp, path);
}

}  // namespace driftcorr
