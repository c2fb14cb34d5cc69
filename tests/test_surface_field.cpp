// Surface-map sources: the PCD/PLY/OctoMap readers (driftcorr_surface_io), BuildSurfaceField on
// hand-computable geometry, and the synthetic building generator (determinism; the three map
// formats give the same field).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "driftcorr/core/errors.h"
#include "driftcorr/mapping/surface_field.h"
#include "driftcorr/mapping/surface_io.h"

namespace driftcorr {
namespace {

namespace fs = std::filesystem;
using Points = std::vector<Eigen::Vector3d>;

const std::string kGenerator = DRIFTCORR_BINARY_DIR "/datasets/driftcorr_make_building_scenario";

fs::path TestDir(const std::string& name) {
    const fs::path dir =
        fs::path(DRIFTCORR_TEST_TMPDIR) / ("surface_" + name + "_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

std::string WriteText(const fs::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
    return path.string();
}

std::string AsciiPcd(const std::vector<std::string>& rows) {
    std::string s = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
    s += "WIDTH " + std::to_string(rows.size()) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n";
    s += "POINTS " + std::to_string(rows.size()) + "\nDATA ascii\n";
    for (const auto& r : rows) s += r + "\n";
    return s;
}

std::string AsciiPly(const std::vector<std::string>& rows) {
    std::string s = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(rows.size()) + "\n";
    s += "property float x\nproperty float y\nproperty float z\nend_header\n";
    for (const auto& r : rows) s += r + "\n";
    return s;
}

// Points on the lattice (spacing (i + 0.5)) of an axis-aligned rectangle at height z(x).
template <typename ZOfX>
void AddRect(double x0, double y0, double x1, double y1, ZOfX z, Points& out,
             double spacing = 0.1) {
    for (double y = y0 + 0.5 * spacing; y < y1; y += spacing)
        for (double x = x0 + 0.5 * spacing; x < x1; x += spacing) out.emplace_back(x, y, z(x));
}

// Expects `fn` to throw InputError whose message names `path` and contains `needle`.
template <typename Fn>
void ExpectInputError(Fn fn, const std::string& path, const std::string& needle) {
    try {
        fn();
        FAIL() << "no InputError for " << path;
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
}

// Writes each (file text, expected message part) case into `dir` as case<i><ext> and expects
// `read` to throw an InputError naming that file and containing the part.
using BadFiles = std::vector<std::pair<std::string, std::string>>;
template <typename Read>
void ExpectEachInputError(const fs::path& dir, const std::string& ext, const BadFiles& cases,
                          Read read) {
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const std::string path =
            WriteText(dir / ("case" + std::to_string(i) + ext), cases[i].first);
        ExpectInputError([&] { read(path); }, path, cases[i].second);
    }
}

// --- readers -------------------------------------------------------------------------------

TEST(SurfaceReaders, AsciiPcdAndPlyRoundTrip) {
    const fs::path dir = TestDir("readers");
    const std::vector<std::string> rows = {"1 2 3", "-1.5 0.25 4", "0 0 8"};
    const Points pcd = ReadSurfacePointsPcd(WriteText(dir / "a.pcd", AsciiPcd(rows)));
    const Points ply = ReadSurfacePointsPly(WriteText(dir / "a.ply", AsciiPly(rows)));
    ASSERT_EQ(pcd.size(), 3u);
    ASSERT_EQ(ply.size(), 3u);
    EXPECT_EQ(pcd[1], Eigen::Vector3d(-1.5, 0.25, 4.0));
    EXPECT_EQ(ply[1], Eigen::Vector3d(-1.5, 0.25, 4.0));
    // The writers (binary) round-trip exactly for float-representable points.
    WriteSurfacePointsPcd((dir / "b.pcd").string(), pcd);
    WriteSurfacePointsPly((dir / "b.ply").string(), pcd);
    EXPECT_EQ(ReadSurfacePoints((dir / "b.pcd").string()), pcd);
    EXPECT_EQ(ReadSurfacePoints((dir / "b.ply").string()), pcd);
    EXPECT_FALSE(fs::exists(dir / "b.pcd.tmp"));
}

TEST(SurfaceReaders, EmptyCloudIsAnInputErrorNamingTheFile) {
    const fs::path dir = TestDir("empty");
    const std::string pcd = WriteText(dir / "empty.pcd", AsciiPcd({}));
    const std::string ply = WriteText(dir / "empty.ply", AsciiPly({}));
    ExpectInputError([&] { ReadSurfacePointsPcd(pcd); }, pcd, "");
    ExpectInputError([&] { ReadSurfacePointsPly(ply); }, ply, "");
}

TEST(SurfaceReaders, NanPointIsAnInputErrorWithCountAndFirstIndex) {
    const fs::path dir = TestDir("nan");
    const std::vector<std::string> rows = {"0 0 0", "nan 1 0", "1 1 0", "2 nan 0"};
    const std::string pcd = WriteText(dir / "nan.pcd", AsciiPcd(rows));
    const std::string ply = WriteText(dir / "nan.ply", AsciiPly(rows));
    ExpectInputError([&] { ReadSurfacePointsPcd(pcd); }, pcd, "2 of 4 points");
    ExpectInputError([&] { ReadSurfacePointsPcd(pcd); }, pcd, "first at index 1");
    ExpectInputError([&] { ReadSurfacePointsPly(ply); }, ply, "2 of 4 points");
}

TEST(SurfaceReaders, UnreadableFilesAreInputErrors) {
    const fs::path dir = TestDir("garbage");
    const std::string garbage = "this is not a map\n\x01\x02\x03 at all\n";
    const std::string pcd = WriteText(dir / "g.pcd", garbage);
    const std::string ply = WriteText(dir / "g.ply", garbage);
    const std::string headless =
        WriteText(dir / "h.pcd", "VERSION 0.7\nPOINTS 2\nDATA ascii\n1 2\n");
    const std::string bt = WriteText(dir / "g.bt", garbage);
    const std::string ot = WriteText(dir / "g.ot", garbage);
    const std::string missing = (dir / "missing.pcd").string();
    ExpectInputError([&] { ReadSurfacePointsPcd(pcd); }, pcd, "");
    ExpectInputError([&] { ReadSurfacePointsPcd(headless); }, headless, "");
    ExpectInputError([&] { ReadSurfacePointsPly(ply); }, ply, "");
    ExpectInputError([&] { ReadFloorVoxelsOctomap(bt); }, bt, "OctoMap");
    ExpectInputError([&] { ReadFloorVoxelsOctomap(ot); }, ot, "OctoMap");
    ExpectInputError([&] { ReadSurfacePointsPcd(missing); }, missing, "does not exist");
    ExpectInputError([&] { ReadSurfacePoints((dir / "x.las").string()); }, "x.las", ".las");
}

// PCL splits header lines on blanks, tabs and CR only and corrupts its heap on some garbled
// headers (found by fuzzing), so headers with other bytes, odd field names or a malformed
// VIEWPOINT are refused before PCL reads them.
TEST(SurfaceReaders, PcdHeaderIsCheckedBeforePclSeesIt) {
    const fs::path dir = TestDir("pcd_header");
    auto pcd = [&](const std::string& name, const std::string& fields,
                   const std::string& viewpoint) {
        return WriteText(dir / name,
                         "VERSION 0.7\nFIELDS " + fields +
                             "\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
                             "VIEWPOINT " +
                             viewpoint + "\nPOINTS 1\nDATA ascii\n1 2 3\n");
    };
    EXPECT_EQ(ReadSurfacePointsPcd(pcd("ok.pcd", "x y z", "0 0 0 1 0 0 0")).size(), 1u);
    const std::string vtab = pcd("vtab.pcd", "x\vy z w", "0 0 0 1 0 0 0");
    ExpectInputError([&] { ReadSurfacePointsPcd(vtab); }, vtab, "control or non-ASCII byte");
    const std::string nul = pcd("nul.pcd", std::string("x y") + '\0' + "\x01 z", "0 0 0 1 0 0 0");
    ExpectInputError([&] { ReadSurfacePointsPcd(nul); }, nul, "control or non-ASCII byte");
    const std::string trailing = pcd("trailing.pcd", "x y z ", "0 0 0 1 0 0 0");
    ExpectInputError([&] { ReadSurfacePointsPcd(trailing); }, trailing, "single-blank separated");
    const std::string tab = pcd("tab.pcd", "x\ty z", "0 0 0 1 0 0 0");
    ExpectInputError([&] { ReadSurfacePointsPcd(tab); }, tab, "single-blank separated");
    const std::string name = pcd("name.pcd", "x y z-", "0 0 0 1 0 0 0");
    ExpectInputError([&] { ReadSurfacePointsPcd(name); }, name, "field name 'z-'");
    const std::string vp = pcd("vp.pcd", "x y z", "0 0 0 1 0 0");
    ExpectInputError([&] { ReadSurfacePointsPcd(vp); }, vp, "VIEWPOINT must be 7 finite numbers");
    const std::string vp_inf = pcd("vp_inf.pcd", "x y z", "0 0 inf 1 0 0 0");
    ExpectInputError([&] { ReadSurfacePointsPcd(vp_inf); }, vp_inf, "VIEWPOINT");
}

// The ASCII body is checked before PCL reads it (its reader wrote past its buffer on a garbled
// body, found by fuzzing): POINTS lines of the declared number of values, single-blank separated.
TEST(SurfaceReaders, PcdAsciiBodyIsCheckedBeforePclSeesIt) {
    const fs::path dir = TestDir("pcd_body");
    auto pcd = [&](const std::string& name, const std::string& body) {
        return WriteText(dir / name,
                         "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                         "COUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n" +
                             body);
    };
    EXPECT_EQ(ReadSurfacePointsPcd(pcd("ok.pcd", "1 2 3\n\n4 5 6\n")).size(), 2u);
    const std::string few = pcd("few.pcd", "1 2 3\n");
    ExpectInputError([&] { ReadSurfacePointsPcd(few); }, few,
                     "1 point lines, the header declares 2");
    const std::string many = pcd("many.pcd", "1 2 3\n4 5 6\n7 8 9\n");
    ExpectInputError([&] { ReadSurfacePointsPcd(many); }, many, "more point lines than POINTS");
    const std::string short_line = pcd("short.pcd", "1 2 3\n4 5\n");
    ExpectInputError([&] { ReadSurfacePointsPcd(short_line); }, short_line, "2 values");
    const std::string word = pcd("word.pcd", "1 2 3\n4 five 6\n");
    ExpectInputError([&] { ReadSurfacePointsPcd(word); }, word, "'five' is not a number");
    const std::string blanks = pcd("blanks.pcd", "1 2 3\n4  5 6\n");
    ExpectInputError([&] { ReadSurfacePointsPcd(blanks); }, blanks, "is not a number");
}

// binary_compressed data starts with its compressed and uncompressed sizes; PCL resizes its
// buffer to the latter and writes every point into it, so it must match the header.
TEST(SurfaceReaders, PcdCompressedSizesMustMatchTheHeader) {
    const fs::path dir = TestDir("pcd_lzf");
    auto pcd = [&](const std::string& name, std::uint32_t compressed, std::uint32_t uncompressed) {
        std::string bytes =
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary_compressed\n";
        bytes.append(reinterpret_cast<const char*>(&compressed), 4);
        bytes.append(reinterpret_cast<const char*>(&uncompressed), 4);
        bytes += std::string(32, '\0');
        return WriteText(dir / name, bytes);
    };
    const std::string small = pcd("small.pcd", 16, 4);  // 2 points of 12 bytes: 24 expected
    ExpectInputError([&] { ReadSurfacePointsPcd(small); }, small, "binary_compressed sizes");
    const std::string past_end = pcd("past_end.pcd", 4096, 24);
    ExpectInputError([&] { ReadSurfacePointsPcd(past_end); }, past_end, "binary_compressed sizes");
}

// PCL's header reader goes on past DATA while lines start with a header key, so a binary body
// that begins with one would redefine the checked header ("FIELDS x" then a huge SIZE made it
// allocate 8 GB, found by fuzzing); such a file is refused. Bytes PCL skips (an empty line, a
// '#') leave the data as declared.
TEST(SurfaceReaders, PcdDataThatPclWouldReadAsHeaderIsRefused) {
    const fs::path dir = TestDir("pcd_after_data");
    auto pcd = [&](const std::string& name, const std::string& first_bytes) {
        std::string body = first_bytes;
        body.resize(24, '\0');  // 2 points of 3 floats
        return WriteText(dir / name,
                         "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                         "COUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n" +
                             body);
    };
    const std::string fields = pcd("fields.pcd", "FIELDS x\n");
    ExpectInputError([&] { ReadSurfacePointsPcd(fields); }, fields, "starts with 'FIELDS'");
    const std::string points = pcd("points.pcd", "\n#\n POINTS 9\n");
    ExpectInputError([&] { ReadSurfacePointsPcd(points); }, points, "starts with 'POINTS'");
    EXPECT_EQ(ReadSurfacePointsPcd(pcd("zeros.pcd", "")).size(), 2u);
    EXPECT_EQ(ReadSurfacePointsPcd(pcd("hash.pcd", "#\n")).size(), 2u);
}

// A .bt file in OctoMap's legacy layout (int32 type 3, double resolution, uint32 size, tree):
// a resolution that is not a sane length is refused (an infinite one made OctoMap convert
// infinite coordinates to keys, found by fuzzing).
// A PLY header over `vertex_props` (lines "property ...") and `extra` element lines after it.
std::string PlyHeader(const std::string& format, std::size_t vertices,
                      const std::string& vertex_props, const std::string& extra = "") {
    return "ply\nformat " + format + " 1.0\ncomment test\nelement vertex " +
           std::to_string(vertices) + "\n" + vertex_props + extra + "end_header\n";
}

template <typename T>
void AppendBinary(std::string& out, T value, bool big_endian) {
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    if (big_endian) std::reverse(raw, raw + sizeof(T));
    out.append(raw, sizeof(T));
}

const char* const kXyzFloat = "property float x\nproperty float y\nproperty float z\n";
const char* const kXyzDouble = "property double x\nproperty double y\nproperty double z\n";
// What PCL's own writer puts after the vertices: an empty face element and a camera.
const char* const kPclCamera =
    "element face 0\nelement camera 1\nproperty float view_px\nproperty float view_py\n"
    "property float view_pz\nproperty int viewportx\nproperty int viewporty\n";

TEST(SurfaceReaders, PlyInTheFormsWritersUseLoads) {
    const fs::path dir = TestDir("ply_forms");
    const Points want = {{1.5, -2.25, 3.0}, {4.0, 5.0, -6.5}};
    // ASCII with colours + alpha, an empty face element and PCL's camera (viewport 2 x 1).
    const std::string rgba =
        "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        "property uchar alpha\n";
    const std::string a =
        WriteText(dir / "a.ply", PlyHeader("ascii", 2, kXyzFloat + rgba, kPclCamera) +
                                     "1.5 -2.25 3 255 0 0 255\n4 5 -6.5 0 255 0 128 \n0 0 0 2 1\n");
    EXPECT_EQ(ReadSurfacePointsPly(a), want);
    // Double coordinates, both byte orders, with a face list after the vertices.
    for (const bool big : {false, true}) {
        std::string body;
        for (const auto& p : want) {
            for (int k = 0; k < 3; ++k) AppendBinary<double>(body, p[k], big);
            AppendBinary<float>(body, 0.5f, big);  // intensity
        }
        AppendBinary<std::uint8_t>(body, 3, big);
        for (int k = 0; k < 3; ++k) AppendBinary<std::int32_t>(body, k % 2, big);
        const std::string name = big ? "be.ply" : "le.ply";
        const std::string path = WriteText(
            dir / name, PlyHeader(big ? "binary_big_endian" : "binary_little_endian", 2,
                                  std::string(kXyzDouble) + "property float intensity\n",
                                  "element face 1\nproperty list uchar int vertex_indices\n") +
                            body);
        EXPECT_EQ(ReadSurfacePointsPly(path), want) << name;
    }
}

// pcl::fromPCLPointCloud2 left double coordinates at 0 (measured before the reader converted
// them itself).
TEST(SurfaceReaders, PcdDoubleCoordinatesAreReadNotZeroed) {
    const fs::path dir = TestDir("pcd_double");
    std::string pcd = AsciiPcd({"1.5 -2.25 3", "4 5 -6.5"});
    pcd.replace(pcd.find("SIZE 4 4 4"), 10, "SIZE 8 8 8");
    const Points want = {{1.5, -2.25, 3.0}, {4.0, 5.0, -6.5}};
    EXPECT_EQ(ReadSurfacePointsPcd(WriteText(dir / "d.pcd", pcd)), want);
}

// PCL 1.13's PLY reader aborts (assertions are on in Debian's build) or writes out of bounds on
// these; each must be an InputError naming the file and the problem before PCL sees it.
TEST(SurfaceReaders, PlyHeaderIsCheckedBeforePclSeesIt) {
    const fs::path dir = TestDir("ply_header");
    const std::string body = "0 0 0\n1 0 0\n";
    const std::string rgb = "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    const BadFiles cases = {
        // found by fuzzing: the keyword after a blank reaches an assert in objInfoCallback
        {"ply\nformat ascii 1.0\n obj_info x\nelement vertex 2\n" + std::string(kXyzFloat) +
             "end_header\n" + body,
         "single blanks"},
        {PlyHeader("ascii", 2, kXyzFloat + std::string("property uchar blue\n")) +
             "0 0 0 1\n1 0 0 1\n",
         "colour"},
        {PlyHeader("ascii", 2, kXyzFloat + std::string("property uchar alpha\n")) +
             "0 0 0 1\n1 0 0 1\n",
         "colour"},
        {PlyHeader("ascii", 2, "property uchar green\n" + rgb + kXyzFloat) + body,
         "declared twice"},
        {PlyHeader("ascii", 2, kXyzFloat + std::string("property list uchar float n\n")) +
             "0 0 0 1 5\n1 0 0 1 5\n",
         "list property 'n' in the vertex"},
        {PlyHeader("ascii", 2, kXyzFloat,
                   "element range_grid 2\nproperty list uchar int vertex_indices\n") +
             body + "1 0\n1 1\n",
         "range_grid"},
        {"ply\nformat ascii 1.0\nobj_info num_cols 2\nobj_info num_rows 5\nelement vertex 2\n" +
             std::string(kXyzFloat) + "end_header\n" + body,
         "num_cols"},
        {"ply\r\nformat ascii 1.0\r\n", "CR"},
        {PlyHeader("ascii", 2, "property float3 x\n"), "unknown property type 'float3'"},
        {PlyHeader("ascii", 2, kXyzFloat, "element vertex 1\n"), "declared twice"},
        {"ply\nformat ascii 1.0\nproperty float x\n", "before the first element"},
        {"ply\nformat ascii 1.0\nelement vertex 2\n" + std::string(kXyzFloat), "no 'end_header'"},
        {PlyHeader("ascii", 2, "property float x\nproperty float y\n") + "0 0\n1 0\n", "no 'z'"},
        {PlyHeader("ascii", 2, kXyzFloat, "element junk 7\n") + body, "no properties"},
        {PlyHeader("binary_middle_endian", 2, kXyzFloat), "unknown format"},
        {PlyHeader("ascii", 0, kXyzFloat), "no points"},
        {"ply\nformat ascii 1.0\nelement vertex -2\n", "element <name> <count>"},
        {"", "the file is empty"},
    };
    ExpectEachInputError(dir, ".ply", cases, [](const std::string& f) { ReadSurfacePointsPly(f); });
}

TEST(SurfaceReaders, PlyBodyIsCheckedBeforePclSeesIt) {
    const fs::path dir = TestDir("ply_body");
    const std::string ascii = PlyHeader("ascii", 2, kXyzFloat);
    const std::string face = "element face 1\nproperty list uchar int vertex_indices\n";
    std::string le_points;
    for (int k = 0; k < 6; ++k) AppendBinary<float>(le_points, float(k), false);
    const std::string le = PlyHeader("binary_little_endian", 2, kXyzFloat);
    const std::string le_face = PlyHeader("binary_little_endian", 2, kXyzFloat, face);
    std::string negative_count = le_points;
    AppendBinary<std::int8_t>(negative_count, -3, false);
    const BadFiles cases = {
        {ascii + "0 0 0\n1 0\n", "fewer values"},
        {ascii + "0 0 0\n1 0 0 4\n", "more values"},
        {ascii + "0 0 0\n1 zero 0\n", "'zero' is not a float"},
        {ascii + "0 0 0\n", "1 of 2 lines"},
        {ascii + "0 0 0\n1 0 0\n2 0 0\n", "more lines"},
        {PlyHeader("ascii", 2, kXyzFloat, face) + "0 0 0\n1 0 0\n3 0 1\n", "fewer values"},
        {PlyHeader("ascii", 2, kXyzFloat, face) + "0 0 0\n1 0 0\n-1\n", "needs a count"},
        {le + le_points.substr(0, 20), "ends in element 'vertex'"},
        {le + le_points + "xy", "2 bytes after the last element"},
        {le_face + le_points + std::string("\x05\x00\x00\x00\x00", 5), "ends in element 'face'"},
        {PlyHeader("binary_little_endian", 2, kXyzFloat,
                   "element face 1\nproperty list char int vertex_indices\n") +
             negative_count,
         "negative count -3"},
        {PlyHeader("ascii", 2, kXyzFloat, kPclCamera) + "0 0 0\n1 0 0\n0 0 0 5 3\n",
         "viewport 5 x 3"},
        {"ply\nformat ascii 1.0\nelement vertex 1\n" + std::string(kXyzFloat) + "end_header",
         "right after"},
    };
    ExpectEachInputError(dir, ".ply", cases, [](const std::string& f) { ReadSurfacePointsPly(f); });
}

TEST(SurfaceReaders, OctomapResolutionOutsideSaneRangeIsAnInputError) {
    const fs::path dir = TestDir("octomap_res");
    auto legacy = [&](const std::string& name, double res) {
        std::string bytes(16, '\0');
        const std::int32_t type = 3;
        const std::uint32_t size = 17;  // nodes: 16 inner ones down to one finest leaf
        std::memcpy(&bytes[0], &type, 4);
        std::memcpy(&bytes[4], &res, 8);
        std::memcpy(&bytes[12], &size, 4);
        // Depth first, two bits per child: 11 inner node (levels 0-14), 10 occupied leaf.
        for (int level = 0; level < 15; ++level) bytes += std::string("\x03\x00", 2);
        bytes += std::string("\x02\x00", 2);
        return WriteText(dir / name, bytes);
    };
    const std::string ok = legacy("ok.bt", 0.1);
    EXPECT_EQ(ReadFloorVoxelsOctomap(ok).size(), 1u);
    for (double res : {1e-300, 1e6, std::numeric_limits<double>::infinity()}) {
        const std::string bt = legacy("bad.bt", res);
        ExpectInputError([&] { ReadFloorVoxelsOctomap(bt); }, bt, "resolution");
    }
}

// A full OcTree file (.ot) as AbstractOcTree::write lays it out: the header, then per node a
// float log-odds value and one byte of child bits, depth first. `levels` nested first children
// below the root, the last one occupied.
std::string FullTreeFile(const std::string& id, const std::string& res, int levels) {
    std::string s = "# Octomap OcTree file\n# (comment)\n#\nid " + id + "\nsize " +
                    std::to_string(levels + 1) + "\nres " + res + "\ndata\n";
    const float occupied = 2.0f;
    for (int level = 0; level <= levels; ++level) {
        s.append(reinterpret_cast<const char*>(&occupied), sizeof(float));
        s.push_back(level < levels ? '\x01' : '\x00');
    }
    return s;
}

TEST(SurfaceReaders, OctomapFullTreeFileIsCheckedBeforeOctomapReadsIt) {
    const fs::path dir = TestDir("octomap_ot");
    const std::string ok = WriteText(dir / "ok.ot", FullTreeFile("OcTree", "0.1", 16));
    const Points floor = ReadFloorVoxelsOctomap(ok);
    ASSERT_EQ(floor.size(), 1u);
    // The finest voxel with key 0 in every axis: centre (0 - 32768 + 0.5) * 0.1 m; its top face
    // 0.05 m higher.
    EXPECT_NEAR(floor[0].x(), -3276.75, 1e-3);
    EXPECT_NEAR(floor[0].z(), -3276.70, 1e-3);
    const std::string full = FullTreeFile("OcTree", "0.1", 16);
    const BadFiles cases = {
        {full.substr(0, full.size() - 3), "runs past the file's end"},  // truncated
        {FullTreeFile("OcTree", "0.1", 17), "deeper than 16 levels"},
        {FullTreeFile("ColorOcTree", "0.1", 16), "type 'ColorOcTree'"},
        {FullTreeFile("OcTree", "1e6", 16), "resolution"},
        {FullTreeFile("OcTree", "0", 16), "resolution"},
        {"# Octomap OcTree file\nid OcTree\nres 0.1\n", "'data' line"},
        {"# Octomap OcTree binary file\nid OcTree\nres 0.1\ndata\n", "first line"},
    };
    ExpectEachInputError(dir, ".ot", cases,
                         [](const std::string& f) { ReadFloorVoxelsOctomap(f); });
}

// OctoMap's header reader skips from the "data" token to the next newline. With none after it (a
// vertical tab ends the token too) it reaches the file's end, and its tree reader then followed
// child bits it had not read, off the stack (found by fuzzing). Same tree, three separators.
TEST(SurfaceReaders, OctomapBinaryDataWithoutNewlineAfterTheDataTokenIsAnInputError) {
    const fs::path dir = TestDir("octomap_data_line");
    std::string tree;  // 16 inner nodes down to one finest leaf, as in the legacy test above
    for (int level = 0; level < 15; ++level) tree += std::string("\x03\x00", 2);
    tree += std::string("\x02\x00", 2);
    auto file = [&](const std::string& name, const std::string& size, const std::string& sep) {
        return WriteText(dir / name,
                         "# Octomap OcTree binary file\n# (comment)\n#\nid OcTree\n"
                         "size " +
                             size + "\nres 0.1\ndata" + sep + tree);
    };
    EXPECT_EQ(ReadFloorVoxelsOctomap(file("newline.bt", "17", "\n")).size(), 1u);
    const std::string tab = file("vtab.bt", "17", "\v");
    ExpectInputError([&] { ReadFloorVoxelsOctomap(tab); }, tab, "runs past the file's end");
    const std::string ot = WriteText(dir / "vtab.ot", [] {
        std::string s = FullTreeFile("OcTree", "0.1", 16);
        s[s.find("data\n") + 4] = '\v';
        return s;
    }());
    ExpectInputError([&] { ReadFloorVoxelsOctomap(ot); }, ot, "runs past the file's end");
    // "size 0": OctoMap reads no data at all, so what follows "data" does not matter; the tree is
    // empty and has no floor.
    const std::string empty = file("empty.bt", "0", "\v");
    ExpectInputError([&] { ReadFloorVoxelsOctomap(empty); }, empty, "");
}

// Floor voxels in the corner x, y < corner_m must lie at z_high, all others at z_low (checked
// per voxel); returns how many are at {z_low, z_high}.
std::pair<int, int> CountFloorLevels(const Points& floor, double corner_m, double z_low,
                                     double z_high) {
    int low = 0, high = 0;
    for (const auto& p : floor) {
        const bool corner = p.x() < corner_m && p.y() < corner_m;
        EXPECT_NEAR(p.z(), corner ? z_high : z_low, 1e-6) << p.transpose();
        (corner ? high : low)++;
    }
    return {low, high};
}

// Floor rule: an occupied voxel with a non-occupied voxel above is floor; its top face is
// returned. A 1 m x 1 m floor at z = 0 (100 voxels of 0.1 m) with a second occupied voxel on top
// in one 0.3 m x 0.3 m corner (9 columns): 91 floor voxels at z = 0, 9 at z = 0.1.
TEST(SurfaceReaders, OctomapFloorVoxelsAreOccupiedWithFreeOrUnknownAbove) {
    const fs::path dir = TestDir("octomap");
    Points pts;
    AddRect(
        0.0, 0.0, 1.0, 1.0, [](double) { return 0.0; }, pts);
    AddRect(
        0.0, 0.0, 0.3, 0.3, [](double) { return 0.1; }, pts);
    // The same tree in either format; the extension picks it, in any case, for writer and reader.
    for (const char* name : {"floor.bt", "floor.ot", "floor.Ot"}) {
        SCOPED_TRACE(name);
        const std::string path = (dir / name).string();
        WriteOctomapFromPoints(path, pts, 0.1);
        std::string first_line;
        std::getline(std::ifstream(path), first_line);
        EXPECT_EQ(first_line, std::string(name) == "floor.bt" ? "# Octomap OcTree binary file"
                                                              : "# Octomap OcTree file");
        const Points floor = ReadSurfacePoints(path);
        ASSERT_EQ(floor.size(), 100u);
        const auto [low, high] = CountFloorLevels(floor, 0.3, 0.0, 0.1);
        EXPECT_EQ(low, 91);
        EXPECT_EQ(high, 9);
        for (const auto& p : floor) {
            EXPECT_NEAR(std::fmod(p.x() + 1.0, 0.1), 0.05, 1e-6);  // voxel centres, 0.05 + 0.1 i
        }
    }
}

// OctoMap prunes a uniform block into one leaf: its whole top face is floor except where an
// occupied voxel sits on it. An 8 x 8 x 8 block of 0.1 m voxels (one 0.8 m leaf) with one voxel
// on top of its corner: 63 floor voxels at z = 0.8, 1 at z = 0.9.
TEST(SurfaceReaders, OctomapPrunedLeafFloorExcludesWhatStandsOnIt) {
    const fs::path dir = TestDir("octomap_pruned");
    Points pts;
    for (int layer = 1; layer <= 8; ++layer) {
        AddRect(
            0.0, 0.0, 0.8, 0.8, [&](double) { return 0.1 * layer; }, pts);
    }
    const std::string block = (dir / "block.bt").string();
    WriteOctomapFromPoints(block, pts, 0.1);
    EXPECT_EQ(ReadFloorVoxelsOctomap(block).size(), 64u);
    pts.emplace_back(0.05, 0.05, 0.9);
    const std::string box = (dir / "block_box.bt").string();
    WriteOctomapFromPoints(box, pts, 0.1);
    const Points floor = ReadFloorVoxelsOctomap(box);
    ASSERT_EQ(floor.size(), 64u);
    const auto [low, high] = CountFloorLevels(floor, 0.1, 0.8, 0.9);
    EXPECT_EQ(low, 63);
    EXPECT_EQ(high, 1);
}

// --- BuildSurfaceField ---------------------------------------------------------------------

double Corridor(const TraversableField& f, const Eigen::Vector3d& p) {
    const auto s = f.Query(p);
    EXPECT_TRUE(s.has_value()) << p.transpose();
    return s ? s->corridor.value : 1e9;
}

// The default config with room above the surfaces for the queries 2 m up.
SurfaceFieldConfig TallConfig() {
    SurfaceFieldConfig c;
    c.vertical_margin_m = 3.0;
    return c;
}

// The wall clearance: centre is 0 in open space, 0.8 m + corridor within 0.8 m of the edge.
TEST(SurfaceField, CentreKeepsClearOfWalls) {
    Points pts;
    AddRect(
        0.0, 0.0, 10.0, 10.0, [](double) { return 0.0; }, pts);
    SurfaceFieldConfig clear = TallConfig();
    const TraversableField f = BuildSurfaceField(pts, clear);
    // On the surface the B-spline rounds the vertical V of the distance: (0.25 + 0.25) / 6 m.
    EXPECT_NEAR(f.Query({5.0, 5.0, 0.0})->centre.value, 0.083, 0.01);  // open floor
    // 0.25 m in from the south edge: corridor = -(0.25 + 0.05), centre = 0.8 - 0.3 = 0.5.
    EXPECT_NEAR(f.Query({5.05, 0.25, 0.0})->centre.value, 0.5, 0.03);
    // 1 m outside the floor: corridor 0.95, centre 1.75.
    EXPECT_GT(f.Query({5.05, -1.0, 0.0})->centre.value, 1.5);
    clear.wall_clearance_m = 0.0;  // surface only: the distance to the nearest surface voxel
    const TraversableField g = BuildSurfaceField(pts, clear);
    EXPECT_NEAR(g.Query({5.05, 0.25, 0.0})->centre.value, 0.083, 0.01);
    EXPECT_NEAR(g.Query({5.0, 5.0, 2.0})->centre.value, 2.0, 0.02);
}

// A 10 m x 10 m floor at z = 0, points every 0.1 m (x, y = 0.05 ... 9.95), default grid
// (0.2 m cells from -1.95, 0.25 m layers, vertical tolerance 0.5 m).
TEST(SurfaceField, FlatFloorMatchesHandComputedDistances) {
    Points pts;
    AddRect(
        0.0, 0.0, 10.0, 10.0, [](double) { return 0.0; }, pts);
    SurfaceFieldStats stats;
    const TraversableField f = BuildSurfaceField(pts, TallConfig(), &stats);
    EXPECT_EQ(stats.points, pts.size());
    EXPECT_EQ(stats.surface_voxels * 5, stats.traversable_voxels);  // 5 layers: -0.5 ... 0.5
    // Inside, near the south edge: the zero level lies half-way between the last inside cell
    // centre (y = 0.05) and the first outside one (y = -0.15): corridor = -(y + 0.05). Exact for
    // the B-spline (linear in y, constant over the 5 layers around z = 0).
    for (double y : {0.65, 1.05, 1.45}) EXPECT_NEAR(Corridor(f, {5.05, y, 0.0}), -(y + 0.05), 0.01);
    EXPECT_LT(Corridor(f, {5.0, 5.0, 0.0}), -4.0);  // middle of the floor: about -5 (truncated)
    // 2 m above the floor: 1.5 m above the traversable layer's top, minus half a cell.
    EXPECT_NEAR(Corridor(f, {5.0, 5.0, 2.0}), 1.4, 0.02);
    // centre = max(distance to the surface, wall_clearance_m + corridor) = max(2.0, 0.8 + 1.4).
    EXPECT_NEAR(f.Query({5.0, 5.0, 2.0})->centre.value, 2.2, 0.02);
    // Gradient against central differences at random interior points (fixed seed).
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u_xy(-1.0, 11.0), u_z(-1.0, 2.5);
    const double h = 1e-4;
    for (int n = 0; n < 200; ++n) {
        const Eigen::Vector3d p(u_xy(rng), u_xy(rng), u_z(rng));
        const auto s = f.Query(p);
        ASSERT_TRUE(s.has_value());
        for (int a = 0; a < 3; ++a) {
            const Eigen::Vector3d e = Eigen::Vector3d::Unit(a) * h;
            const double g_corr =
                (f.Query(p + e)->corridor.value - f.Query(p - e)->corridor.value) / (2 * h);
            const double g_centre =
                (f.Query(p + e)->centre.value - f.Query(p - e)->centre.value) / (2 * h);
            EXPECT_NEAR(s->corridor.gradient[a], g_corr, 1e-4 + 1e-4 * std::abs(g_corr));
            EXPECT_NEAR(s->centre.gradient[a], g_centre, 1e-4 + 1e-4 * std::abs(g_centre));
        }
    }
}

// A ramp (stairs): z = 0.5 x over x in [0, 8], 2 m wide. Traversable along the slope (more than
// 0.3 m inside, away from the ends, where the edge is near), not 1.5 m above it.
TEST(SurfaceField, RampIsTraversableAlongTheSlope) {
    Points pts;
    AddRect(
        0.0, 0.0, 8.0, 2.0, [](double x) { return 0.5 * x; }, pts);
    const TraversableField f = BuildSurfaceField(pts, TallConfig());
    for (double x = 0.6; x <= 7.4; x += 0.1) {
        EXPECT_LT(Corridor(f, {x, 1.0, 0.5 * x}), -0.3) << "x = " << x;
        EXPECT_GT(Corridor(f, {x, 1.0, 0.5 * x + 1.5}), 0.5) << "x = " << x;
    }
}

// Two stacked floors (z = 0 and 4) joined only by a ramp: the path over the ramp stays inside,
// the vertical path between the floors does not.
TEST(SurfaceField, TwoFloorsJoinedOnlyByARamp) {
    Points pts;
    AddRect(
        0.0, 0.0, 10.0, 10.0, [](double) { return 0.0; }, pts);  // floor A
    AddRect(
        10.0, 0.0, 18.0, 2.0, [](double x) { return 0.5 * (x - 10.0); }, pts);  // ramp
    AddRect(
        0.0, 3.0, 28.0, 10.0, [](double) { return 4.0; }, pts);  // floor B
    AddRect(
        18.0, 0.0, 28.0, 3.0, [](double) { return 4.0; }, pts);  // its landing
    const TraversableField f = BuildSurfaceField(pts, TallConfig());
    const std::vector<Eigen::Vector3d> path = {{5, 1, 0},  {10, 1, 0}, {18, 1, 4},
                                               {22, 1, 4}, {22, 6, 4}, {5, 6, 4}};
    for (std::size_t k = 1; k < path.size(); ++k) {
        for (double t = 0.0; t <= 1.0; t += 0.01) {
            const Eigen::Vector3d p = path[k - 1] + t * (path[k] - path[k - 1]);
            EXPECT_LT(Corridor(f, p), -0.3) << p.transpose();
        }
    }
    // Between A and B: 1 m above A's traversable layer (top at 0.5 m), minus half a cell. (At
    // z = 2, mid-way, the distance has a kink that the B-spline rounds: about 1.32 for 1.4.)
    EXPECT_NEAR(Corridor(f, {5.0, 6.0, 1.5}), 0.9, 0.01);
    EXPECT_GT(Corridor(f, {5.0, 6.0, 2.0}), 1.2);
    EXPECT_GT(Corridor(f, {14.0, 1.0, 4.5}), 1.0);  // 2.5 m above the ramp's middle
}

TEST(SurfaceField, BadInputAndMemoryCap) {
    EXPECT_THROW(BuildSurfaceField({}, SurfaceFieldConfig{}), std::invalid_argument);
    Points nan_pts = {{0, 0, 0}, {std::nan(""), 0, 0}};
    EXPECT_THROW(BuildSurfaceField(nan_pts, SurfaceFieldConfig{}), std::invalid_argument);
    SurfaceFieldConfig bad;
    bad.vertical_tolerance_m = 0.1;  // < resolution_z_m
    EXPECT_NE(bad.Validate().find("vertical_tolerance_m"), std::string::npos);
    SurfaceFieldConfig small;
    small.max_memory_mb = 1.0;
    Points pts;
    AddRect(
        0.0, 0.0, 60.0, 30.0, [](double) { return 0.0; }, pts, 0.5);
    try {
        BuildSurfaceField(pts, small);
        FAIL() << "no memory-cap error";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("would fit"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("max_memory_mb"), std::string::npos) << e.what();
    }
}

// --- the synthetic building ----------------------------------------------------------------

std::string ReadBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

void RunGenerator(const fs::path& out, const std::string& args = "") {
    const std::string cmd = kGenerator + " " + out.string() + " " + args + " > /dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

std::vector<Eigen::Vector3d> ReadTumPositions(const fs::path& path) {
    std::ifstream in(path);
    std::vector<Eigen::Vector3d> out;
    double t, x, y, z, qx, qy, qz, qw;
    while (in >> t >> x >> y >> z >> qx >> qy >> qz >> qw) out.emplace_back(x, y, z);
    return out;
}

const char* const kScenarioFiles[] = {
    "building.pcd",     "building.ply",     "building.bt",   "building.ot",
    "ground_truth.tum", "estimate.tum",     "scenario.yaml", "scenario_octomap.yaml",
    "scenario_ot.yaml", "scenario_ply.yaml"};

TEST(SynthBuilding, SameSeedSameBytes) {
    const fs::path a = TestDir("gen_a"), b = TestDir("gen_b"), c = TestDir("gen_c");
    RunGenerator(a);
    RunGenerator(b);
    RunGenerator(c, "--seed 8");
    for (const char* name : kScenarioFiles) {
        ASSERT_TRUE(fs::exists(a / name)) << name;
        EXPECT_EQ(ReadBytes(a / name), ReadBytes(b / name)) << name;
        EXPECT_FALSE(fs::exists(a / (std::string(name) + ".tmp"))) << name;
    }
    EXPECT_EQ(ReadBytes(a / "building.pcd"), ReadBytes(c / "building.pcd"));  // map: no noise
    EXPECT_EQ(ReadBytes(a / "ground_truth.tum"), ReadBytes(c / "ground_truth.tum"));
    EXPECT_NE(ReadBytes(a / "estimate.tum"), ReadBytes(c / "estimate.tum"));
    EXPECT_NE(
        std::system(
            (kGenerator + " " + (a / "x").string() + " --scale-error 3 2> /dev/null").c_str()),
        0);
}

// The three map files give the same field: every ground-truth pose (floors, stairs, the lift
// ride) lies inside the traversable set, and the corridor values at the poses agree. PCD and PLY
// hold the same float points, so their fields are identical; the OctoMap quantises heights to its
// 0.1 m voxels (stairs, lift levels), so its corridor values may differ by up to 0.15 m. The .bt
// and .ot files hold the same tree (occupancy bits, log-odds), so their fields are identical.
TEST(SynthBuilding, PcdPlyAndOctomapGiveTheSameField) {
    const fs::path dir = TestDir("formats");
    RunGenerator(dir);
    const auto gt = ReadTumPositions(dir / "ground_truth.tum");
    ASSERT_GT(gt.size(), 500u);
    // Timings are printed for the record (speed is measured, never asserted, in unit tests).
    const auto t0 = std::chrono::steady_clock::now();
    const Points pcd_points = ReadSurfacePoints((dir / "building.pcd").string());
    const auto t1 = std::chrono::steady_clock::now();
    SurfaceFieldStats stats;
    const TraversableField pcd = BuildSurfaceField(pcd_points, {}, &stats);
    const auto t2 = std::chrono::steady_clock::now();
    const double read_s = std::chrono::duration<double>(t1 - t0).count();
    const double build_s = std::chrono::duration<double>(t2 - t1).count();
    std::printf(
        "building.pcd: %zu points read in %.3f s; field of %zu voxels (%zu traversable) "
        "built in %.3f s (%.1f Mvoxel/s)\n",
        pcd_points.size(), read_s, stats.voxels, stats.traversable_voxels, build_s,
        1e-6 * double(stats.voxels) / build_s);
    const TraversableField ply =
        BuildSurfaceField(ReadSurfacePoints((dir / "building.ply").string()), {});
    const TraversableField bt =
        BuildSurfaceField(ReadSurfacePoints((dir / "building.bt").string()), {});
    const TraversableField ot =
        BuildSurfaceField(ReadSurfacePoints((dir / "building.ot").string()), {});
    double max_ply = 0.0, max_bt = 0.0, max_ot = 0.0, worst_inside = -1e9;
    for (const auto& p : gt) {
        const double c = Corridor(pcd, p);
        worst_inside = std::max(worst_inside, c);
        max_ply = std::max(max_ply, std::abs(Corridor(ply, p) - c));
        const double c_bt = Corridor(bt, p);
        max_bt = std::max(max_bt, std::abs(c_bt - c));
        max_ot = std::max(max_ot, std::abs(Corridor(ot, p) - c_bt));
    }
    EXPECT_LT(worst_inside, -0.1);  // every pose inside, >= 0.1 m from the edge
    EXPECT_EQ(max_ply, 0.0);
    EXPECT_LT(max_bt, 0.15);
    EXPECT_EQ(max_ot, 0.0);
    RecordProperty("max_corridor_difference_octomap_m", std::to_string(max_bt));
    std::printf(
        "max |corridor difference| at the %zu GT poses: PLY %.4f m, OctoMap %.4f m; "
        "least-inside pose corridor %.3f m\n",
        gt.size(), max_ply, max_bt, worst_inside);
}

}  // namespace
}  // namespace driftcorr
