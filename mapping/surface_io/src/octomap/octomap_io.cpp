// OctoMap occupancy trees (PRIVATE to driftcorr_surface_io): floor voxels out, surface voxels in.
#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <streambuf>
#include <string>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/atomic_file.h"
#include "driftcorr/mapping/surface_io.h"

namespace driftcorr {
namespace {

// OctoMap reports progress and parse errors on std::cout / std::cerr; the caller reports errors
// itself (InputError naming the file), so the library's own lines are silenced while it runs.
class QuietStreams {
public:
    QuietStreams() : out_(std::cout.rdbuf(&null_)), err_(std::cerr.rdbuf(&null_)) {}
    ~QuietStreams() {
        std::cout.rdbuf(out_);
        std::cerr.rdbuf(err_);
    }
    QuietStreams(const QuietStreams&) = delete;
    QuietStreams& operator=(const QuietStreams&) = delete;

private:
    struct NullBuffer : std::streambuf {
        int overflow(int c) override { return c; }
    } null_;
    std::streambuf* out_;
    std::streambuf* err_;
};

constexpr double kMinResolutionM = 0.001;  ///< [m] finer than any floor map needs
constexpr double kMaxResolutionM = 100.0;  ///< [m]

// OctoMap's binary reader (OcTree::readBinaryNode) follows the child bits of the data
// recursively with no depth bound, so malformed data runs it off the stack (found by fuzzing).
// This walks the same encoding first: per node two bytes, two bits per child (01 occupied leaf,
// 10 free leaf, 11 inner node, 00 none), depth first; the tree must stay within OctoMap's 16
// levels and within the data, and hold at least one node.
bool ValidBinaryNode(const std::string& data, std::size_t& pos, int depth) {
    if (depth > 16 || pos + 2 > data.size()) return false;
    const unsigned char bytes[2] = {static_cast<unsigned char>(data[pos]),
                                    static_cast<unsigned char>(data[pos + 1])};
    pos += 2;
    for (const unsigned char b : bytes) {
        for (int i = 0; i < 4; ++i) {
            const bool low = (b >> (2 * i)) & 1, high = (b >> (2 * i + 1)) & 1;
            if (low && high && !ValidBinaryNode(data, pos, depth + 1)) return false;
        }
    }
    return true;
}

// A full (.ot) OcTree node as OcTreeBaseImpl::readNodesRecurs reads it: a float log-odds value,
// then one byte whose bits say which of the 8 children follow, depth first. OctoMap bounds neither
// the depth nor the data: past the file's end it reads an uninitialised child byte and recurses
// on it. So the data must stay within the file and OctoMap's 16 levels.
bool ValidFullNode(const std::string& data, std::size_t& pos, int depth) {
    if (depth > 16 || pos + sizeof(float) + 1 > data.size()) return false;
    pos += sizeof(float);
    const auto children = static_cast<unsigned char>(data[pos++]);
    for (int i = 0; i < 8; ++i) {
        if (((children >> i) & 1U) && !ValidFullNode(data, pos, depth + 1)) return false;
    }
    return true;
}

// What OctoMap's AbstractOcTree::readHeader takes from the lines after a file's first line
// (whitespace-separated tokens; "#" starts a comment to the end of the line; id, res and size take
// one value; any other token skips to the end of the line; "data" ends the header after the rest
// of its line). data_start is std::string::npos when there is no data token.
struct TreeHeader {
    std::size_t data_start = std::string::npos;
    std::string id;
    double res = 0.0;
    unsigned size = 0;  ///< the node count the header promises
};

TreeHeader ParseTreeHeader(const std::string& text, const std::string& first_line) {
    TreeHeader header;
    if (text.compare(0, first_line.size(), first_line) != 0) return header;
    const std::size_t pos = text.find('\n');
    if (pos == std::string::npos) return header;
    std::istringstream in(text.substr(pos + 1));
    auto skip_line = [&] { in.ignore(std::numeric_limits<std::streamsize>::max(), '\n'); };
    for (std::string token; in.good() && in >> token;) {
        if (token == "data") {
            // When no newline follows, OctoMap's stream ends up at the end of the file and its
            // reader then works on child bits it never read: the data is empty. (tellg() cannot
            // say so: at the end of the stream it returns -1.)
            skip_line();
            header.data_start =
                in && !in.eof() ? pos + 1 + static_cast<std::size_t>(in.tellg()) : text.size();
            return header;
        }
        // The values are read with the types OctoMap uses: "res 0.1data" is 0.1, then "data".
        if (token == "id") {
            in >> header.id;
        } else if (token == "res") {
            in >> header.res;
        } else if (token == "size") {
            in >> header.size;
        } else {
            skip_line();  // a comment ("#...") or a token OctoMap skips with a warning
        }
    }
    return header;
}

// Where OctoMap starts reading the tree data of a .bt file; std::string::npos when it reads none
// (no header it accepts, or a size of 0 nodes, for which it skips the data).
std::size_t BinaryDataStart(const std::string& text) {
    static const std::string kHeader = "# Octomap OcTree binary file";
    if (text.compare(0, kHeader.size(), kHeader) != 0) {
        // OctoMap then tries its legacy layout: int32 tree type 3, double resolution, uint32
        // size, and the tree data right after (byte 16).
        std::int32_t type = 0;
        std::uint32_t size = 0;
        if (text.size() >= 16) {
            std::memcpy(&type, text.data(), sizeof(type));
            std::memcpy(&size, text.data() + 12, sizeof(size));
        }
        return type == 3 && size > 0 ? 16 : std::string::npos;
    }
    const TreeHeader header = ParseTreeHeader(text, kHeader);
    return header.size > 0 ? header.data_start : std::string::npos;
}

std::string ReadWholeFile(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
}

void CheckBinaryTreeData(const std::string& path) {
    const std::string text = ReadWholeFile(path);
    std::size_t pos = BinaryDataStart(text);
    if (pos == std::string::npos) return;  // no data: OctoMap reads nothing (and reports it)
    if (!ValidBinaryNode(text, pos, 0)) {
        throw InputError(path, 0, "",
                         "binary OctoMap (.bt) data is malformed (the tree runs past the file's "
                         "end or deeper than 16 levels)");
    }
}

// A .ot file must be an OcTree ("id OcTree", or the deprecated "id 1") with a sane resolution
// and well-formed data before OctoMap creates and fills the tree (it sets the resolution and
// reads the data unchecked).
void CheckFullTreeFile(const std::string& path) {
    const std::string text = ReadWholeFile(path);
    const TreeHeader header = ParseTreeHeader(text, "# Octomap OcTree file");
    if (header.data_start == std::string::npos) {
        throw InputError(path, 1, "",
                         "not an OctoMap (.ot) file: the first line must start with '# Octomap "
                         "OcTree file' and the header end with a 'data' line");
    }
    if (header.id != "OcTree" && header.id != "1") {
        throw InputError(
            path, 0, "",
            "OctoMap file holds a tree of type '" + header.id.substr(0, 40) + "', not an OcTree");
    }
    if (!(header.res >= kMinResolutionM && header.res <= kMaxResolutionM)) {
        throw InputError(path, 0, "",
                         "OctoMap resolution " + std::to_string(header.res) + " m is outside [" +
                             std::to_string(kMinResolutionM) + ", " +
                             std::to_string(kMaxResolutionM) + "] m");
    }
    std::size_t pos = header.data_start;
    if (!ValidFullNode(text, pos, 0)) {
        throw InputError(path, 0, "",
                         "OctoMap (.ot) data is malformed (the tree runs past the file's end or "
                         "deeper than 16 levels)");
    }
}

// The one rule for which OctoMap format a path names, for reading and writing alike: ".ot" in any
// case (as ReadSurfacePoints dispatches it) is the full format (AbstractOcTree::read / write),
// anything else the binary one (.bt).
bool IsFullTreePath(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return ext == ".ot";
}

std::unique_ptr<octomap::OcTree> ReadTree(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        throw InputError(path, 0, "", "OctoMap file does not exist or is not a regular file");
    }
    if (IsFullTreePath(path)) {
        CheckFullTreeFile(path);
        const QuietStreams quiet;
        std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(path));
        auto* tree = dynamic_cast<octomap::OcTree*>(any.get());
        if (!tree) {
            throw InputError(path, 0, "",
                             any ? "OctoMap file holds a " + any->getTreeType() + ", not an OcTree"
                                 : "cannot be read or parsed as an OctoMap (.ot) file");
        }
        any.release();
        return std::unique_ptr<octomap::OcTree>(tree);
    }
    CheckBinaryTreeData(path);
    auto tree = std::make_unique<octomap::OcTree>(0.1);
    const bool ok = [&] {
        const QuietStreams quiet;
        return tree->readBinary(path);
    }();
    if (!ok) {
        throw InputError(path, 0, "", "cannot be read or parsed as a binary OctoMap (.bt) file");
    }
    return tree;
}

// Which of the n x n finest voxels in the layer centred at height z_m, over the leaf centred at
// c of size `size`, are occupied (index a * n + b along x, y). One pass over the occupied leaves
// that layer touches instead of a search per voxel: a pruned leaf stands for up to 4 M voxels.
std::vector<bool> OccupiedAbove(const octomap::OcTree& tree, const octomap::point3d& c, double size,
                                double res, int n, double z_m) {
    std::vector<bool> blocked(std::size_t(n) * n, false);
    const double x0 = c.x() - 0.5 * size, y0 = c.y() - 0.5 * size;
    const octomap::point3d lo(float(x0 + 0.5 * res), float(y0 + 0.5 * res), float(z_m));
    const octomap::point3d hi(float(x0 + size - 0.5 * res), float(y0 + size - 0.5 * res),
                              float(z_m));
    for (auto it = tree.begin_leafs_bbx(lo, hi), end = tree.end_leafs_bbx(); it != end; ++it) {
        const double s = it.getSize();
        const octomap::point3d lc = it.getCoordinate();
        // The bbx iterator also yields coarser leaves next to the box (measured: the pruned leaf
        // below it), so the layer must lie within the leaf's height.
        if (!tree.isNodeOccupied(*it) || std::abs(lc.z() - z_m) >= 0.5 * s) continue;
        auto cells = [&](double lo_m, double origin_m) {
            const long first = std::lround((lo_m - origin_m) / res);
            return std::make_pair(std::max(0L, first),
                                  std::min(long(n), first + std::lround(s / res)));
        };
        const auto [a0, a1] = cells(lc.x() - 0.5 * s, x0);
        const auto [b0, b1] = cells(lc.y() - 0.5 * s, y0);
        for (long a = a0; a < a1; ++a) {
            for (long b = b0; b < b1; ++b) blocked[std::size_t(a) * n + std::size_t(b)] = true;
        }
    }
    return blocked;
}

}  // namespace

// 4 M floor voxels: 100 m x 100 m of floor at 0.05 m, or 4 floors of it at 0.1 m.
constexpr std::size_t kMaxFloorVoxels = 4'000'000;
// The most occupied voxels a raw map may expand to (about 0.8 GB of points).
constexpr std::size_t kMaxOccupiedVoxels = 30'000'000;

namespace {

// The tree of `path` with a resolution within [kMinResolutionM, kMaxResolutionM]: a garbled header
// can carry any double as the resolution; OctoMap then converts infinite coordinates to keys
// (UBSan: inf to int, found by fuzzing).
std::unique_ptr<octomap::OcTree> ReadCheckedTree(const std::string& path) {
    std::unique_ptr<octomap::OcTree> tree = ReadTree(path);
    const double res = tree->getResolution();
    if (!(res >= kMinResolutionM && res <= kMaxResolutionM)) {
        throw InputError(path, 0, "",
                         "OctoMap resolution " + std::to_string(res) + " m is outside [" +
                             std::to_string(kMinResolutionM) + ", " +
                             std::to_string(kMaxResolutionM) + "] m");
    }
    return tree;
}

}  // namespace

std::vector<Eigen::Vector3d> ReadFloorVoxelsOctomap(const std::string& path) {
    const std::unique_ptr<octomap::OcTree> tree = ReadCheckedTree(path);
    const double res = tree->getResolution();
    std::vector<Eigen::Vector3d> floor;
    for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
        if (!tree->isNodeOccupied(*it)) continue;
        // A pruned leaf of size n * res: its top layer of n x n finest voxels.
        const double size = it.getSize();
        const int n = std::max(1, int(std::lround(size / res)));
        // A pruned leaf near the root stands for up to 2^15 x 2^15 finest voxels: refuse maps
        // whose floor would not fit in memory rather than expanding them (found by fuzzing).
        if (double(floor.size()) + double(n) * double(n) > double(kMaxFloorVoxels)) {
            throw InputError(path, 0, "",
                             "OctoMap floor would have more than " +
                                 std::to_string(kMaxFloorVoxels) +
                                 " voxels at its resolution (a pruned occupied leaf of " +
                                 std::to_string(size) + " m); coarsen or crop the map");
        }
        const octomap::point3d c = it.getCoordinate();
        const double z_top_centre = c.z() + 0.5 * size - 0.5 * res;
        // The same-size cell above: when it is one leaf (or nothing) and not occupied, the whole
        // top face is floor and needs no search per finest voxel.
        const octomap::OcTreeNode* above =
            tree->search(c.x(), c.y(), c.z() + size, static_cast<unsigned>(it.getDepth()));
        const bool open_above =
            !above || (!tree->nodeHasChildren(above) && !tree->isNodeOccupied(above));
        // Empty when open above: most leaves are single voxels, no allocation per leaf.
        const std::vector<bool> blocked =
            open_above ? std::vector<bool>()
                       : OccupiedAbove(*tree, c, size, res, n, z_top_centre + res);
        for (int a = 0; a < n; ++a) {
            for (int b = 0; b < n; ++b) {
                if (!blocked.empty() && blocked[std::size_t(a) * n + b]) continue;
                const double x = c.x() - 0.5 * size + res * (a + 0.5);
                const double y = c.y() - 0.5 * size + res * (b + 0.5);
                floor.emplace_back(x, y, z_top_centre + 0.5 * res);
            }
        }
    }
    if (floor.empty()) {
        throw InputError(path, 0, "",
                         "OctoMap has no floor voxel (no occupied voxel with free or unknown "
                         "space above it)");
    }
    return floor;
}

std::vector<Eigen::Vector3d> ReadOccupiedVoxelsOctomap(const std::string& path,
                                                       double* resolution_m) {
    const std::unique_ptr<octomap::OcTree> tree = ReadCheckedTree(path);
    const double res = tree->getResolution();
    if (resolution_m) *resolution_m = res;
    std::vector<Eigen::Vector3d> voxels;
    for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
        if (!tree->isNodeOccupied(*it)) continue;
        const double size = it.getSize();
        const int n = std::max(1, int(std::lround(size / res)));
        if (double(voxels.size()) + double(n) * n * n > double(kMaxOccupiedVoxels)) {
            throw InputError(path, 0, "",
                             "OctoMap has more than " + std::to_string(kMaxOccupiedVoxels) +
                                 " occupied voxels at its resolution; coarsen or crop the map");
        }
        const octomap::point3d c = it.getCoordinate();
        for (int a = 0; a < n; ++a) {
            for (int b = 0; b < n; ++b) {
                for (int d = 0; d < n; ++d) {
                    voxels.emplace_back(c.x() - 0.5 * size + res * (a + 0.5),
                                        c.y() - 0.5 * size + res * (b + 0.5),
                                        c.z() - 0.5 * size + res * (d + 0.5));
                }
            }
        }
    }
    if (voxels.empty()) throw InputError(path, 0, "", "OctoMap has no occupied voxel");
    return voxels;
}

void WriteOctomapFromPoints(const std::string& path, const std::vector<Eigen::Vector3d>& points,
                            double resolution_m) {
    if (!(resolution_m > 0.0)) throw std::logic_error("WriteOctomapFromPoints: resolution_m <= 0");
    octomap::OcTree tree(resolution_m);
    for (const Eigen::Vector3d& p : points) {
        tree.updateNode(
            octomap::point3d(float(p.x()), float(p.y()), float(p.z() - 0.5 * resolution_m)), true,
            /*lazy_eval=*/true);
    }
    tree.updateInnerOccupancy();
    WriteAtomically(path, [&](const std::string& tmp) {
        const bool written = [&] {
            const QuietStreams quiet;
            return IsFullTreePath(path) ? tree.write(tmp) : tree.writeBinary(tmp);
        }();
        if (!written) throw std::runtime_error(path + ": cannot write OctoMap");
    });
}

}  // namespace driftcorr
