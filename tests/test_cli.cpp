// End-to-end tests of the `driftcorr` command-line tool on bad and unusual input.
//
// One valid synthetic scenario (a 60 s drive, 601 poses) is generated per test process in a
// folder named after the process id, so parallel ctest runs do not collide. Every case copies it,
// changes one thing, runs the CLI and checks
//   1. the exit code (0 ok, 1 usage, 2 bad input, 3 no usable correction, 4 internal);
//   2. that stderr holds exactly one message line, "driftcorr: ...", naming the offending file and
//      line or key (progress lines "[driftcorr] ..." and, after a usage error, the usage text
//      are allowed besides it);
//   3. that no output file (nor a temporary of it) was created, or, for the cases marked
//      `sentinel`, that a pre-existing output file is left byte-identical.
// Valid but unusual inputs must succeed with one output pose per estimate pose.
// The other formats are reached from the same copy: the KITTI cases convert its estimate to
// estimate.kitti + times.txt, the indoor3d cases replace it with a small corridor walk written by
// the test (GeoJSON floor plan + walkways, or an ASCII PCD floor); each has a valid case too.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <ostream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "driftcorr/io/trajectory_io.h"
#include "driftcorr/mapping/surface_io.h"
#include "driftcorr/mapping/walkable_surface.h"
#include "test_support.h"

namespace {

namespace fs = std::filesystem;

const std::string kCli = DRIFTCORR_BINARY_DIR "/examples/driftcorr";
const std::string kGenerator = DRIFTCORR_BINARY_DIR "/datasets/driftcorr_make_road_scenario";
constexpr int kExitOk = 0, kExitUsage = 1, kExitBadInput = 2, kExitSolver = 3;

// ---- files ------------------------------------------------------------------------------------

std::string ReadFile(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("test setup: cannot read " + path.string());
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteFile(const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out) throw std::runtime_error("test setup: cannot write " + path.string());
}

// The edit helpers throw when their pattern is absent, so that a change of the generator's output
// makes a case fail loudly instead of silently testing a valid file.

/// Replaces the one occurrence of `from` in `file`.
void Replace(const fs::path& file, const std::string& from, const std::string& to) {
    std::string text = ReadFile(file);
    const std::size_t at = text.find(from);
    if (at == std::string::npos || text.find(from, at + 1) != std::string::npos) {
        throw std::runtime_error("test setup: '" + from + "' is not in " + file.string() + " once");
    }
    WriteFile(file, text.replace(at, from.size(), to));
}

/// Replaces the matches of `pattern` (all, or only the first) in `file`; at least one must exist.
void RegexReplace(const fs::path& file, const std::string& pattern, const std::string& to,
                  bool first_only = false) {
    const std::string text = ReadFile(file);
    const std::regex re(pattern);
    if (!std::regex_search(text, re)) {
        throw std::runtime_error("test setup: /" + pattern + "/ matches nothing in " +
                                 file.string());
    }
    WriteFile(file, std::regex_replace(text, re, to,
                                       first_only ? std::regex_constants::format_first_only
                                                  : std::regex_constants::format_default));
}

using Fields = std::vector<std::string>;

/// Rewrites the data lines of a TUM file (blank and '#' lines are kept as they are).
void TransformTum(const fs::path& file, const std::function<void(std::vector<Fields>&)>& edit) {
    std::istringstream in(ReadFile(file));
    std::vector<std::string> lines;
    std::vector<std::size_t> data_at;
    std::vector<Fields> poses;
    for (std::string line; std::getline(in, line);) {
        if (!line.empty() && line[0] != '#') {
            std::istringstream fields(line);
            poses.emplace_back(std::istream_iterator<std::string>(fields),
                               std::istream_iterator<std::string>());
            data_at.push_back(lines.size());
        }
        lines.push_back(line);
    }
    edit(poses);
    if (poses.size() != data_at.size()) throw std::logic_error("TransformTum keeps the pose count");
    std::string out;
    for (std::size_t i = 0, p = 0; i < lines.size(); ++i) {
        if (p < data_at.size() && data_at[p] == i) {
            std::string joined;
            for (const std::string& f : poses[p++]) joined += (joined.empty() ? "" : " ") + f;
            out += joined + "\n";
        } else {
            out += lines[i] + "\n";
        }
    }
    WriteFile(file, out);
}

/// Applies `edit` to the fields of line `line_no` (1-based) of a TUM file; it must be a data line.
void EditTumLine(const fs::path& file, std::size_t line_no,
                 const std::function<void(Fields&)>& edit) {
    std::istringstream in(ReadFile(file));
    std::string out, line;
    for (std::size_t n = 1; std::getline(in, line); ++n) {
        if (n == line_no) {
            if (line.empty() || line[0] == '#')
                throw std::runtime_error("test setup: not a data line");
            std::istringstream fields(line);
            Fields f{std::istream_iterator<std::string>(fields),
                     std::istream_iterator<std::string>()};
            edit(f);
            line.clear();
            for (const std::string& s : f) line += (line.empty() ? "" : " ") + s;
        }
        out += line + "\n";
    }
    WriteFile(file, out);
}

/// Throws unless `text` occurs in `file`.
void Require(const fs::path& file, const std::string& text) {
    if (ReadFile(file).find(text) == std::string::npos) {
        throw std::runtime_error("test setup: '" + text + "' is not in " + file.string());
    }
}

/// Keeps the first `n` lines of a file.
void KeepLines(const fs::path& file, std::size_t n) {
    std::istringstream in(ReadFile(file));
    std::string out, line;
    for (std::size_t i = 0; i < n && std::getline(in, line); ++i) out += line + "\n";
    WriteFile(file, out);
}

// ---- running the CLI --------------------------------------------------------------------------

std::string ShellQuote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

struct RunResult {
    int exit_code = -1;  ///< WEXITSTATUS; 128 + signal when the program crashed; 124 on timeout
    std::string out, err;
    std::string command;
};

/// Runs `program args...` with stdout and stderr captured into files in `capture_dir`.
RunResult RunProgram(const std::string& program, const std::vector<std::string>& args,
                     const fs::path& capture_dir) {
    RunResult r;
    r.command = ShellQuote(program);
    for (const std::string& a : args) r.command += " " + ShellQuote(a);
    const fs::path out = capture_dir / "stdout.txt", err = capture_dir / "stderr.txt";
    const std::string shell = "timeout 120 " + r.command + " </dev/null >" +
                              ShellQuote(out.string()) + " 2>" + ShellQuote(err.string());
    const int status = std::system(shell.c_str());
    if (status != -1 && WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
    r.out = ReadFile(out);
    r.err = ReadFile(err);
    return r;
}

/// The message lines of a stderr text: progress lines ("[driftcorr] ...") dropped, and after a
/// usage error the usage text (a blank line, then "usage: ..." to the end).
std::vector<std::string> MessageLines(const std::string& err) {
    std::vector<std::string> lines, messages;
    std::istringstream in(err);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    for (std::size_t i = 0; i < lines.size(); ++i) {
        if (lines[i].rfind("[driftcorr]", 0) == 0) continue;
        if (lines[i].empty() && i + 1 < lines.size() && lines[i + 1].rfind("usage:", 0) == 0) break;
        messages.push_back(lines[i]);
    }
    return messages;
}

std::vector<std::string> FolderEntries(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    return names;
}

// ---- other estimate and map formats -----------------------------------------------------------

std::string Fmt(const char* format, double a, double b = 0.0, double c = 0.0) {
    char buf[128];
    std::snprintf(buf, sizeof(buf), format, a, b, c);
    return buf;
}

/// Writes estimate.kitti (12 numbers a line: row-major 3x4 [R|t], R from the TUM quaternion) and
/// times.txt (the TUM timestamps) from the scenario's estimate.tum, and points scenario.yaml's
/// estimate at them with both `rate_hz: 10` and `times: times.txt` (the times file wins).
/// estimate.tum is kept: the valid cases compare the output's timestamps with it.
void TumToKitti(const fs::path& s) {
    std::istringstream in(ReadFile(s / "estimate.tum"));
    std::string kitti, times;
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream fields(line);
        double t, x, y, z, qx, qy, qz, qw;
        if (!(fields >> t >> x >> y >> z >> qx >> qy >> qz >> qw))
            throw std::runtime_error("test setup: bad TUM line " + line);
        const double n = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
        qx /= n, qy /= n, qz /= n, qw /= n;
        const double r[3][3] = {
            {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)},
            {2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)},
            {2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)}};
        const double p[3] = {x, y, z};
        std::string row;
        for (int i = 0; i < 3; ++i) {
            row += Fmt("%.9g %.9g %.9g", r[i][0], r[i][1], r[i][2]) + Fmt(" %.6f", p[i]);
            row += i < 2 ? " " : "\n";
        }
        kitti += row;
        times += Fmt("%.6f\n", t);
    }
    WriteFile(s / "estimate.kitti", kitti);
    WriteFile(s / "times.txt", times);
    Replace(s / "scenario.yaml", "  path: estimate.tum\n  format: tum\n",
            "  path: estimate.kitti\n  format: kitti\n  rate_hz: 10\n  times: times.txt\n");
}

/// Applies `edit` to the numbers of line `line_no` (1-based) of a KITTI (or times) file.
void EditKittiLine(const fs::path& file, std::size_t line_no,
                   const std::function<void(Fields&)>& edit) {
    EditTumLine(file, line_no, edit);  // the same: whitespace-separated fields, no comments
}

// A small indoor scenario (mode indoor3d, frame enu, anchor in UTM 32N): a person walks 30 steps
// east along a 20 m x 3 m corridor whose floor is at height 0. Map coordinates are local
// East-North metres from the anchor (x east, y north), written as UTM for the GeoJSON layers.
constexpr double kIndoorEasting = 566578.7, kIndoorNorthing = 5932830.4;

std::string Utm(double x, double y) {
    return Fmt("[%.3f, %.3f]", kIndoorEasting + x, kIndoorNorthing + y);
}

std::string Ring(const std::vector<std::pair<double, double>>& xy) {
    std::string s = "[[";
    for (std::size_t i = 0; i <= xy.size(); ++i) {  // closed: the first point repeated
        const auto& p = xy[i % xy.size()];
        s += (i ? ", " : "") + Utm(p.first, p.second);
    }
    return s + "]]";
}

std::string Box(double x0, double y0, double x1, double y1) {
    return Ring({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
}

std::string PolygonFeature(const std::string& type, const std::string& ring) {
    return R"({"type": "Feature", "properties": {"Type": ")" + type +
           R"("}, "geometry": {"type": "Polygon", "coordinates": )" + ring + "}}";
}

const std::string kCrs32632 =
    R"("crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}},)";

std::string FeatureCollection(const std::vector<std::string>& features) {
    std::string s = "{\n\"type\": \"FeatureCollection\",\n" + kCrs32632 + "\n\"features\": [\n";
    for (std::size_t i = 0; i < features.size(); ++i) s += (i ? ",\n" : "") + features[i];
    return s + "\n]\n}\n";
}

/// Ground truth: 30 poses 0.6 m apart along y = 0, every 0.5 s, facing east. The estimate drifts:
/// 4 % too long steps and a heading error growing to about 3 degrees, still inside the corridor.
void WriteIndoorWalk(const fs::path& s) {
    std::string est, gt;
    double ex = 1.0, ey = 0.0;
    for (int i = 0; i < 30; ++i) {
        const double t = 100.0 + 0.5 * i;
        gt += Fmt("%.3f", t) + Fmt(" %.4f %.4f %.4f", 1.0 + 0.6 * i, 0.0, 0.0) + " 0 0 0 1\n";
        const double yaw = 0.002 * i;
        est += Fmt("%.3f", t) + Fmt(" %.4f %.4f %.4f", ex, ey, 0.0) +
               Fmt(" 0 0 %.9f %.9f\n", std::sin(yaw / 2), std::cos(yaw / 2));
        ex += 0.624 * std::cos(yaw);
        ey += 0.624 * std::sin(yaw);
    }
    WriteFile(s / "estimate.tum", est);
    WriteFile(s / "ground_truth.tum", gt);
}

std::string IndoorScenarioYaml(const std::string& map_layers) {
    return "name: synthetic-corridor\nmode: indoor3d\n"
           "estimate:\n  path: estimate.tum\n  format: tum\n"
           "ground_truth:\n  path: ground_truth.tum\n  format: tum\n"
           "frame: enu\n"
           "anchor:\n  crs: EPSG:32632\n" +
           Fmt("  easting_m: %.3f\n  northing_m: %.3f\n", kIndoorEasting, kIndoorNorthing) +
           "  yaw_deg: 0.0\n  z_m: 0.0\n"
           "map:\n" +
           map_layers;
}

/// Replaces the folder `s` with the indoor scenario mapped by two GeoJSON layers: plan.geojson
/// (a Corridor, a Room north of it and the Walls between) and walkways.geojson (a LineString
/// along the corridor), both with role and floor_z_m 0.
void WriteIndoorGeoJsonScenario(const fs::path& s) {
    fs::remove_all(s);
    fs::create_directories(s);
    WriteIndoorWalk(s);
    WriteFile(s / "plan.geojson",
              FeatureCollection({PolygonFeature("Corridor", Box(0, -1.5, 20, 1.5)),
                                 PolygonFeature("Room", Box(5, 1.5, 10, 6)),
                                 PolygonFeature("Wall", Box(0, 1.5, 5, 1.7)),
                                 PolygonFeature("Wall", Box(10, 1.5, 20, 1.7))}));
    WriteFile(s / "walkways.geojson",
              FeatureCollection({R"({"type": "Feature", "properties": {"name": "corridor"}, )"
                                 R"("geometry": {"type": "LineString", "coordinates": [)" +
                                 Utm(0.5, 0) + ", " + Utm(19.5, 0) + "]}}"}));
    WriteFile(s / "scenario.yaml",
              IndoorScenarioYaml(
                  "  - {path: walkways.geojson, format: geojson, role: walkways, floor_z_m: 0.0}\n"
                  "  - {path: plan.geojson, format: geojson, role: floorplan, floor_z_m: 0.0}\n"));
}

/// Replaces the folder `s` with the indoor scenario mapped by floor.pcd: an ASCII PCD of the
/// corridor floor, 20 m x 3 m sampled every 0.1 m at z = 0 (local East-North-Up).
void WriteIndoorPcdScenario(const fs::path& s) {
    fs::remove_all(s);
    fs::create_directories(s);
    WriteIndoorWalk(s);
    std::string points;
    std::size_t n = 0;
    for (int i = 0; i <= 200; ++i) {
        for (int j = 0; j <= 30; ++j, ++n) points += Fmt("%.2f %.2f 0\n", 0.1 * i, -1.5 + 0.1 * j);
    }
    WriteFile(s / "floor.pcd",
              "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
              "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
              "WIDTH " +
                  std::to_string(n) +
                  "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
                  "POINTS " +
                  std::to_string(n) + "\nDATA ascii\n" + points);
    WriteFile(s / "scenario.yaml", IndoorScenarioYaml("  - {path: floor.pcd, format: pcd}\n"));
}

// ---- cases ------------------------------------------------------------------------------------

/// Where one case works: a fresh copy of the valid scenario, and an empty output folder.
struct CaseDirs {
    fs::path scenario;  ///< copy of the valid scenario folder, to be broken
    fs::path out_dir;   ///< empty; only the output may appear here
    fs::path output;    ///< out_dir / "corrected.tum", the -o path
    fs::path params;    ///< where a case may write a parameter file (outside both folders)
};

/// Changes one thing in the copy and returns the CLI arguments.
using Mutation = std::function<std::vector<std::string>(const CaseDirs&)>;

std::vector<std::string> Correct(const CaseDirs& c, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args = {"correct", c.scenario.string(), "-o", c.output.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
}

/// Edits the scenario copy and runs `driftcorr correct <copy> -o <output>`.
Mutation Edit(std::function<void(const fs::path& scenario)> edit) {
    return [edit](const CaseDirs& c) {
        edit(c.scenario);
        return Correct(c);
    };
}

/// Runs the valid scenario with a parameter file holding `yaml`.
Mutation WithParams(std::string yaml) {
    return [yaml](const CaseDirs& c) {
        WriteFile(c.params, yaml);
        return Correct(c, {"--config", c.params.string()});
    };
}

Mutation EditEstimateLine(std::size_t line_no, std::function<void(Fields&)> edit) {
    return Edit([=](const fs::path& s) { EditTumLine(s / "estimate.tum", line_no, edit); });
}

/// Converts the estimate to KITTI (estimate.kitti + times.txt), then applies `edit`.
Mutation Kitti(std::function<void(const fs::path& scenario)> edit = nullptr) {
    return Edit([edit](const fs::path& s) {
        TumToKitti(s);
        if (edit) edit(s);
    });
}

/// Replaces the copy with the small indoor GeoJSON scenario, then applies `edit`.
Mutation IndoorGeoJson(std::function<void(const fs::path& scenario)> edit = nullptr) {
    return Edit([edit](const fs::path& s) {
        WriteIndoorGeoJsonScenario(s);
        if (edit) edit(s);
    });
}

/// Replaces the copy with the small indoor point-cloud scenario, then applies `edit`.
Mutation IndoorPcd(std::function<void(const fs::path& scenario)> edit = nullptr) {
    return Edit([edit](const fs::path& s) {
        WriteIndoorPcdScenario(s);
        if (edit) edit(s);
    });
}

/// Scales the rotation part (R) of the fields of one KITTI line by `factor`.
void ScaleKittiRotation(Fields& f, double factor) {
    for (int i : {0, 1, 2, 4, 5, 6, 8, 9, 10}) f[i] = Fmt("%.9g", std::stod(f[i]) * factor);
}

struct BadInputCase {
    const char* name;
    Mutation mutate;
    int exit_code;
    /// ECMAScript regexes that the one message line must each contain (std::regex_search).
    std::vector<std::string> message;
    /// Write "sentinel\n" to the output first; it must be left byte-identical.
    bool sentinel = false;
};

void PrintTo(const BadInputCase& c, std::ostream* os) { *os << c.name; }

std::vector<BadInputCase> BadInputCases() {
    const std::string kNothingWritten = "nothing written";
    constexpr bool kSentinelKept = true;  // BadInputCase::sentinel
    return {
        // ---- estimate.tum (data lines start at line 1; line 5 is the fifth pose) ----
        {"EstimateSevenNumbers",
         EditEstimateLine(5, [](Fields& f) { f.pop_back(); }),
         kExitBadInput,
         {R"(estimate\.tum:5: expected 8 numbers, found 7 fields)"},
         kSentinelKept},
        {"EstimateShortLine",
         EditEstimateLine(5, [](Fields& f) { f.resize(3); }),
         kExitBadInput,
         {R"(estimate\.tum:5: expected 8 numbers, found 3 fields)"}},
        {"EstimateNonNumber",
         EditEstimateLine(5, [](Fields& f) { f[2] = "12.x"; }),
         kExitBadInput,
         {R"(estimate\.tum:5: field 3 '12\.x' is not a number)"}},
        {"EstimateNaN",
         EditEstimateLine(5, [](Fields& f) { f[1] = "nan"; }),
         kExitBadInput,
         {R"(estimate\.tum:5: field 2 'nan' is not finite)"}},
        {"EstimateInf",
         EditEstimateLine(5, [](Fields& f) { f[3] = "-inf"; }),
         kExitBadInput,
         {R"(estimate\.tum:5: field 4 '-inf' is not finite)"}},
        {"EstimateTimestampBackwards",
         EditEstimateLine(5, [](Fields& f) { f[0] = "999.0"; }),
         kExitBadInput,
         {R"(estimate\.tum:5: timestamp 999 does not increase)"}},
        {"EstimateTimestampRepeated",
         EditEstimateLine(5, [](Fields& f) { f[0] = "1000.3"; }),
         kExitBadInput,
         {R"(estimate\.tum:5: timestamp 1000\.3 does not increase)"}},
        {"EstimateZeroQuaternion",
         EditEstimateLine(5, [](Fields& f) { f[4] = f[5] = f[6] = f[7] = "0"; }),
         kExitBadInput,
         {R"(estimate\.tum:5: quaternion has zero norm)"}},
        {"EstimateTwoPoses",
         Edit([](const fs::path& s) { KeepLines(s / "estimate.tum", 2); }),
         kExitBadInput,
         {R"(estimate\.tum: has 2 poses, need at least 3)"}},
        {"EstimateEmpty",
         Edit([](const fs::path& s) { WriteFile(s / "estimate.tum", ""); }),
         kExitBadInput,
         {R"(estimate\.tum: has 0 poses, need at least 3)"},
         kSentinelKept},
        {"EstimateMissing",
         Edit([](const fs::path& s) { fs::remove(s / "estimate.tum"); }),
         kExitBadInput,
         {R"(estimate\.tum: cannot open file)"}},
        {"GroundTruthPoseCount",
         Edit([](const fs::path& s) { KeepLines(s / "ground_truth.tum", 501); }),
         kExitBadInput,
         {R"(ground_truth\.tum: ground truth has 501 poses, the estimate 601)"},
         kSentinelKept},

        // ---- scenario.yaml ----
        {"ScenarioUnknownFormat",
         Edit([](const fs::path& s) {
             Replace(s / "scenario.yaml", "path: estimate.tum\n  format: tum",
                     "path: estimate.tum\n  format: gpx");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: estimate\.format: unknown value 'gpx')"},
         kSentinelKept},
        {"ScenarioUnknownFrame",
         Edit([](const fs::path& s) {
             Replace(s / "scenario.yaml", "\nframe: enu\n", "\nframe: ned\n");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: frame: unknown value 'ned')"}},
        {"ScenarioUnknownMode",
         Edit([](const fs::path& s) {
             Replace(s / "scenario.yaml", "\nmode: road2d\n", "\nmode: road3d\n");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: mode: unknown value 'road3d')"}},
        {"ScenarioAnchorLatWithoutLon",
         Edit([](const fs::path& s) {
             RegexReplace(s / "scenario.yaml", "\n  lon_deg: [^\n]*", "");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: anchor\.lon_deg: missing required key)"}},
        {"ScenarioAnchorWithoutYaw",
         Edit([](const fs::path& s) {
             RegexReplace(s / "scenario.yaml", "\n  yaw_deg: [^\n]*", "");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: anchor\.yaw_deg: missing required key)"}},
        {"ScenarioFileIsAFolder",
         Edit([](const fs::path& s) {
             fs::remove(s / "scenario.yaml");
             fs::create_directory(s / "scenario.yaml");
         }),
         kExitBadInput,
         {R"(scenario\.yaml: is a folder, not a file)"}},
        {"ScenarioNoAnchor",
         Edit([](const fs::path& s) {
             RegexReplace(s / "scenario.yaml", "\nanchor:\n(  [^\n]*\n)+", "\n");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: anchor: missing required key)"}},
        {"ScenarioAnchorLat95",
         Edit([](const fs::path& s) {
             RegexReplace(s / "scenario.yaml", "\n  lat_deg: [^\n]*", "\n  lat_deg: 95");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: anchor\.lat_deg: must be within \[-90, 90\])"}},
        {"ScenarioMapListEmpty",
         Edit([](const fs::path& s) {
             RegexReplace(s / "scenario.yaml", "\nmap:\n(  [^\n]*\n)+", "\nmap: []\n");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: map: must list at least one layer)"}},
        {"ScenarioMissingEstimate",
         Edit([](const fs::path& s) {
             RegexReplace(s / "scenario.yaml", "\nestimate:\n(  [^\n]*\n)+", "\n");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: estimate: missing required key)"}},
        {"ScenarioYamlSyntaxError",
         Edit([](const fs::path& s) {
             Replace(s / "scenario.yaml", "\nframe: enu\n", "\nframe: [enu\n");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: YAML error)"},
         kSentinelKept},
        {"ScenarioGeoJsonLayerInRoadMode",
         Edit([](const fs::path& s) {
             Replace(s / "scenario.yaml", "  - path: map.osm\n    format: osm",
                     "  - path: map.osm\n    format: geojson");
         }),
         kExitBadInput,
         {R"(scenario\.yaml: map: road2d mode reads OpenStreetMap layers only)"}},
        {"ScenarioFolderWithoutYaml",
         Edit([](const fs::path& s) { fs::remove(s / "scenario.yaml"); }),
         kExitBadInput,
         {R"(scenario\.yaml: scenario folder has no scenario\.yaml)"}},
        {"ScenarioFileNotYaml",
         [](const CaseDirs& c) {
             fs::rename(c.scenario / "scenario.yaml", c.scenario / "scenario.txt");
             return std::vector<std::string>{"correct", (c.scenario / "scenario.txt").string(),
                                             "-o", c.output.string()};
         },
         kExitBadInput,
         {R"(scenario\.txt: expected a scenario folder or a \.yaml/\.yml file)"}},

        // ---- map.osm ----
        {"OsmOnlyFootways",
         Edit([](const fs::path& s) {
             RegexReplace(s / "map.osm", R"(<tag k="highway" v="[^"]*"/>)",
                          R"(<tag k="highway" v="footway"/>)");
         }),
         kExitBadInput,
         {R"(map\.osm: no usable roads)", "'vehicle' profile"},
         kSentinelKept},
        {"OsmNoHighwayWays",
         Edit([](const fs::path& s) {
             RegexReplace(s / "map.osm", R"(<tag k="highway")", R"(<tag k="landuse")");
         }),
         kExitBadInput,
         {R"(map\.osm: no usable roads: 0 highway way)"}},
        {"OsmTruncated",
         Edit([](const fs::path& s) {
             const std::string xml = ReadFile(s / "map.osm");
             WriteFile(s / "map.osm", xml.substr(0, xml.size() / 2));
         }),
         kExitBadInput,
         {R"(map\.osm:\d+: malformed XML)"},
         kSentinelKept},
        {"OsmNodeLat95",
         Edit([](const fs::path& s) {
             RegexReplace(s / "map.osm", R"re((<node id="\d+" lat=)"[^"]*")re", R"re($1"95")re",
                          true);
         }),
         kExitBadInput,
         {R"(map\.osm:\d+: lat: node \d+: '95' is outside \[-90, 90\])"}},
        {"OsmMissing",
         Edit([](const fs::path& s) { fs::remove(s / "map.osm"); }),
         kExitBadInput,
         {R"(map\.osm: cannot open)"}},

        // ---- estimate.kitti (+ times.txt; the estimate of the road scenario as KITTI) ----
        {"KittiElevenNumbers",
         Kitti([](const fs::path& s) {
             EditKittiLine(s / "estimate.kitti", 5, [](Fields& f) { f.pop_back(); });
         }),
         kExitBadInput,
         {R"(estimate\.kitti:5: expected 12 numbers, found 11 fields)"},
         kSentinelKept},
        {"KittiRotationScaledByTwo",
         Kitti([](const fs::path& s) {
             EditKittiLine(s / "estimate.kitti", 5, [](Fields& f) { ScaleKittiRotation(f, 2.0); });
         }),
         kExitBadInput,
         {R"(estimate\.kitti:5: rotation part is not a rotation matrix \(det 8\b)"}},
        {"KittiNaN",
         Kitti([](const fs::path& s) {
             EditKittiLine(s / "estimate.kitti", 5, [](Fields& f) { f[7] = "nan"; });
         }),
         kExitBadInput,
         {R"(estimate\.kitti:5: field 8 'nan' is not finite)"}},
        {"KittiTimesLineCount",
         Kitti([](const fs::path& s) { KeepLines(s / "times.txt", 600); }),
         kExitBadInput,
         {R"(times\.txt: has 600 timestamps but .*estimate\.kitti has 601 poses)"},
         kSentinelKept},
        {"KittiTimesBackwards",
         Kitti([](const fs::path& s) {
             EditKittiLine(s / "times.txt", 5, [](Fields& f) { f[0] = "1000.1"; });
         }),
         kExitBadInput,
         {R"(times\.txt:5: timestamp 1000\.1 does not increase)"}},
        {"KittiTimesMissing",
         Kitti([](const fs::path& s) { fs::remove(s / "times.txt"); }),
         kExitBadInput,
         {R"(times\.txt: cannot open file)"}},
        {"KittiRateZero",
         Kitti([](const fs::path& s) {
             Replace(s / "scenario.yaml", "  rate_hz: 10\n  times: times.txt\n", "  rate_hz: 0\n");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d+: estimate\.rate_hz: must be positive)"}},

        // ---- indoor3d GeoJSON layers (plan.geojson, walkways.geojson) ----
        {"GeoJsonNoCrs",
         IndoorGeoJson([](const fs::path& s) { Replace(s / "plan.geojson", kCrs32632, ""); }),
         kExitBadInput,
         {R"(plan\.geojson: crs: no `crs` member)"},
         kSentinelKept},
        {"GeoJsonUnknownCrs",
         IndoorGeoJson([](const fs::path& s) {
             Replace(s / "walkways.geojson", "EPSG::32632", "EPSG::99999");
         }),
         kExitBadInput,
         {R"(walkways\.geojson: crs: .*99999)"}},
        {"GeoJsonSyntaxError",
         IndoorGeoJson([](const fs::path& s) {
             Replace(s / "plan.geojson", "\"features\": [\n", "\"features\": [\n,");
         }),
         kExitBadInput,
         {R"(plan\.geojson:5: )"}},
        {"GeoJsonPlanOnlyWalls",
         IndoorGeoJson([](const fs::path& s) {
             RegexReplace(s / "plan.geojson", R"re("Type": "(Corridor|Room)")re",
                          R"("Type": "Wall")");
         }),
         kExitBadInput,
         {R"(plan\.geojson: the floor plan has no walkable polygon)"}},
        {"GeoJsonLayerWithoutFloorZ",
         IndoorGeoJson([](const fs::path& s) {
             Replace(s / "scenario.yaml", "role: floorplan, floor_z_m: 0.0}", "role: floorplan}");
         }),
         kExitBadInput,
         {R"(scenario\.yaml:\d*:? ?map\[1\]: .*needs role .* and floor_z_m)"}},
        {"GeoJsonLayerWithoutRole",
         IndoorGeoJson(
             [](const fs::path& s) { Replace(s / "scenario.yaml", "role: walkways, ", ""); }),
         kExitBadInput,
         {R"(scenario\.yaml:\d*:? ?map\[0\]: .*needs role .* and floor_z_m)"}},

        // ---- indoor3d point-cloud / OctoMap layers (floor.pcd) ----
        {"PcdNoPoints",
         IndoorPcd([](const fs::path& s) {
             WriteFile(s / "floor.pcd",
                       "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                       "COUNT 1 1 1\nWIDTH 0\nHEIGHT 1\n"
                       "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA ascii\n");
         }),
         kExitBadInput,
         {R"(floor\.pcd: PCD file has no points)"},
         kSentinelKept},
        {"PcdNaNPoint",
         IndoorPcd([](const fs::path& s) {
             Replace(s / "floor.pcd", "\n0.10 -1.40 0\n", "\n0.10 nan 0\n");
         }),
         kExitBadInput,
         {R"(floor\.pcd: PCD file has 1 of 6231 points with a NaN or infinite coordinate)"}},
        {"PcdGarbage",
         IndoorPcd([](const fs::path& s) {
             WriteFile(s / "floor.pcd", "this is not a point cloud\n\x01\x02\x03 garbage\n");
         }),
         kExitBadInput,
         {R"(floor\.pcd:1: PCD header: unknown line 'this is not a point cloud')"}},
        {"PlyEmpty",
         IndoorPcd([](const fs::path& s) {
             WriteFile(s / "floor.ply", "");
             Replace(s / "scenario.yaml", "{path: floor.pcd, format: pcd}",
                     "{path: floor.ply, format: ply}");
         }),
         kExitBadInput,
         {R"(floor\.ply: PLY header: the file is empty)"}},
        {"OctomapGarbage",
         IndoorPcd([](const fs::path& s) {
             WriteFile(s / "floor.bt", "# Octomap OcTree binary file\ngarbage\n");
             Replace(s / "scenario.yaml", "{path: floor.pcd, format: pcd}",
                     "{path: floor.bt, format: octomap}");
         }),
         kExitBadInput,
         {R"(floor\.bt: cannot be read or parsed as a binary OctoMap \(\.bt\) file)"}},
        {"SurfaceFieldOverMemoryCap",
         [](const CaseDirs& c) {
             WriteIndoorPcdScenario(c.scenario);
             WriteFile(c.params, "surface_field: {max_memory_mb: 0.01}\n");
             return Correct(c, {"--config", c.params.string()});
         },
         kExitBadInput,
         {R"(scenario\.yaml: map: )", "max_memory_mb = 0\\.01",
          R"(a horizontal resolution of [0-9.]+ m or coarser would fit)"},
         kSentinelKept},

        // ---- params.yaml via --config ----
        {"ParamsUnknownKey",
         WithParams("model: {step_sigmaa_m: 1}\n"),
         kExitBadInput,
         {R"(params\.yaml:1: model\.step_sigmaa_m: unknown parameter)"},
         kSentinelKept},
        {"ParamsNegativeSigma",
         WithParams("model: {step_sigma_m: -1}\n"),
         kExitBadInput,
         {R"(params\.yaml:1: model\.step_sigma_m: must be > 0)"}},
        {"ParamsWeightTwo",
         WithParams("model:\n  map_weight: 2\n"),
         kExitBadInput,
         {R"(params\.yaml:2: model\.map_weight: must be in \(0, 1\])"}},
        {"ParamsOnlineUpdateFraction",
         WithParams("online:\n  update_fraction: 2\n"),
         kExitBadInput,
         {R"(params\.yaml:2: online\.update_fraction: must be in \[0, 1\])"}},
        {"ParamsNonNumber",
         WithParams("model: {step_sigma_m: abc}\n"),
         kExitBadInput,
         {R"(params\.yaml:1: model\.step_sigma_m: must be a number)"}},
        {"ParamsUnknownSection",
         WithParams("modle: {step_sigma_m: 1}\n"),
         kExitBadInput,
         {R"(params\.yaml:1: modle: unknown section)"}},
        {"ParamsKeyGivenTwice",
         WithParams("model:\n  map_weight: 0.5\n  map_weight: 0.7\n"),
         kExitBadInput,
         {R"(params\.yaml:3: model\.map_weight: key given twice)"}},
        {"ParamsListAsKey",
         WithParams("model: {[step_sigma_m]: 1}\n"),
         kExitBadInput,
         {R"(params\.yaml:1: model: keys must be plain names)"}},
        {"ParamsProfileList",
         WithParams("roads: {profile: [vehicle]}\n"),
         kExitBadInput,
         {R"(params\.yaml:1: roads\.profile: must be vehicle, pedestrian or all)"}},
        {"ParamsUnknownProfile",
         WithParams("roads:\n  profile: tank\n"),
         kExitBadInput,
         {R"(params\.yaml:2: roads\.profile: must be .*'tank')"}},
        {"ParamsYamlSyntaxError",
         WithParams("model: {step_sigma_m: 1\n"),
         kExitBadInput,
         {R"(params\.yaml:\d+: YAML syntax error)"}},
        {"ParamsMissingFile",
         [](const CaseDirs& c) {
             return Correct(c, {"--config", c.params.string()});
         },
         kExitBadInput,
         {R"(params\.yaml: cannot open the parameter file)"}},

        // ---- command line ----
        {"NoArguments",
         [](const CaseDirs&) { return std::vector<std::string>{}; },
         kExitUsage,
         {"^driftcorr: missing command$"}},
        {"UnknownCommand",
         [](const CaseDirs& c) {
             return std::vector<std::string>{"fix", c.scenario.string(), "-o", c.output.string()};
         },
         kExitUsage,
         {"^driftcorr: unknown command 'fix'$"}},
        {"MissingOutput",
         [](const CaseDirs& c) {
             return std::vector<std::string>{"correct", c.scenario.string()};
         },
         kExitUsage,
         {"^driftcorr: missing -o"}},
        {"UnknownOption",
         [](const CaseDirs& c) { return Correct(c, {"--fast"}); },
         kExitUsage,
         {"^driftcorr: unknown option --fast$"},
         kSentinelKept},
        {"OptionWithoutValue",
         [](const CaseDirs& c) { return Correct(c, {"--config"}); },
         kExitUsage,
         {"^driftcorr: --config needs a value$"}},
        {"NonexistentScenario",
         [](const CaseDirs& c) {
             return std::vector<std::string>{"correct", (c.scenario / "no_such_scenario").string(),
                                             "-o", c.output.string()};
         },
         kExitBadInput,
         {R"(no_such_scenario: no such file or folder)"},
         kSentinelKept},
        {"OutputFolderMissing",
         [](const CaseDirs& c) {
             return std::vector<std::string>{"correct", c.scenario.string(), "-o",
                                             (c.out_dir / "missing" / "corrected.tum").string()};
         },
         kExitBadInput,
         {R"(missing/corrected\.tum: -o: folder '.*missing' does not exist)"}},
        // (-o naming a folder with one scenario writes <name>.tum into it, as with several.)
        {"CovarianceIsAFolder",
         [](const CaseDirs& c) {
             return std::vector<std::string>{"correct",      c.scenario.string(),
                                             "-o",           c.output.string(),
                                             "--covariance", c.out_dir.string()};
         },
         kExitBadInput,
         {R"(: --covariance: is a folder)"}},
        // The GeoJSON path is bad: the corrected trajectory must not be written either.
        {"GeoJsonFolderMissing",
         [](const CaseDirs& c) {
             return Correct(c, {"--geojson", (c.out_dir / "missing" / "tracks.geojson").string()});
         },
         kExitBadInput,
         {R"(tracks\.geojson: --geojson: folder '.*missing' does not exist)"},
         kSentinelKept},

        // ---- the solver does not produce a usable correction ----
        // One Ipopt iteration for the final refinement: it stops at the iteration limit (also
        // when re-solved without the hard corridor), so there is no usable correction.
        {"RefineStopsAtMaxIterations",
         WithParams("corrector: {refine_max_iterations: 1}\n"),
         kExitSolver,
         {"^driftcorr: ", "max_iterations", kNothingWritten},
         kSentinelKept},
        // Every window stops after one iteration and there is no refinement to rescue them.
        {"WindowsStopAtMaxIterations",
         WithParams("corrector: {refine: false, window_max_iterations: 1}\n"),
         kExitSolver,
         {"^driftcorr: ", "window\\(s\\) failed", kNothingWritten}},
    };
}

struct ValidCase {
    const char* name;
    Mutation mutate;
};

void PrintTo(const ValidCase& c, std::ostream* os) { *os << c.name; }

/// The vehicle stops at pose `first` for `count` poses: poses first..first+count-1 repeat pose
/// `first`, later poses are the original ones shifted by count-1 (the drive resumes where it
/// stopped), timestamps unchanged, the last count-1 poses dropped.
void InsertStop(std::vector<Fields>& poses, std::size_t first, std::size_t count) {
    std::vector<Fields> out = poses;
    for (std::size_t i = first; i < poses.size(); ++i) {
        const std::size_t src = i < first + count ? first : i - (count - 1);
        for (std::size_t k = 1; k < 8; ++k) out[i][k] = poses[src][k];
    }
    poses = out;
}

/// Moves the last `count` poses `dx_m` along the frame's x axis (east for an enu frame, yaw 0).
void ShiftTail(std::vector<Fields>& poses, std::size_t count, double dx_m) {
    for (std::size_t i = poses.size() - count; i < poses.size(); ++i) {
        char buf[64];
        std::snprintf(buf, sizeof(buf), "%.6f", std::stod(poses[i][1]) + dx_m);
        poses[i][1] = buf;
    }
}

std::vector<ValidCase> ValidCases() {
    return {
        {"LongStop", Edit([](const fs::path& s) {
             for (const char* f : {"estimate.tum", "ground_truth.tum"}) {
                 TransformTum(s / f, [](std::vector<Fields>& p) { InsertStop(p, 200, 30); });
             }
         })},
        {"LeavesMapExtent", Edit([](const fs::path& s) {
             // +x is east because the trajectory frame is enu with yaw 0.
             Require(s / "scenario.yaml", "\nframe: enu\n");
             Require(s / "scenario.yaml", "\n  yaw_deg: 0.0\n");
             for (const char* f : {"estimate.tum", "ground_truth.tum"}) {
                 TransformTum(s / f, [](std::vector<Fields>& p) { ShiftTail(p, 50, 3000.0); });
             }
         })},
        {"KittiWithTimes", Kitti()},
        // rate_hz only: timestamps i / 10, so the reference estimate.tum is shifted to start at 0.
        {"KittiRateHz", Kitti([](const fs::path& s) {
             Replace(s / "scenario.yaml", "  rate_hz: 10\n  times: times.txt\n", "  rate_hz: 10\n");
             TransformTum(s / "estimate.tum", [](std::vector<Fields>& p) {
                 for (std::size_t i = 0; i < p.size(); ++i) p[i][0] = Fmt("%.6f", 0.1 * i);
             });
         })},
        {"IndoorGeoJson", IndoorGeoJson()},
        {"IndoorPcd", IndoorPcd()},
        {"ScenarioYamlPath",
         [](const CaseDirs& c) {
             return std::vector<std::string>{"correct", (c.scenario / "scenario.yaml").string(),
                                             "-o", c.output.string()};
         }},
        {"WithGeoJsonAndConfig",
         [](const CaseDirs& c) {
             WriteFile(c.params, "model:\n  map_weight: 0.8\nroads: {profile: vehicle}\n");
             return Correct(c, {"--config", c.params.string(), "--geojson",
                                (c.out_dir / "tracks.geojson").string()});
         }},
    };
}

// ---- fixture ----------------------------------------------------------------------------------

class CliTest : public ::testing::Test {
protected:
    /// Generates the valid scenario once per suite, in a folder of this process.
    static void SetUpTestSuite() {
        root_ = driftcorr::test::FreshProcessDir("test_cli");
        base_ = root_ / "valid_scenario";
        const RunResult gen = RunProgram(kGenerator, {base_.string(), "--duration-s", "60"}, root_);
        base_error_.clear();
        if (gen.exit_code != 0 || !fs::exists(base_ / "scenario.yaml")) {
            base_error_ = "generating the scenario failed (exit " + std::to_string(gen.exit_code) +
                          "): " + gen.command + "\n" + gen.err;
        }
    }
    /// Keeps the folder for inspection when a test failed.
    static void TearDownTestSuite() {
        const auto* suite = ::testing::UnitTest::GetInstance()->current_test_suite();
        if (suite == nullptr || suite->Passed()) fs::remove_all(root_);
    }

    void SetUp() override { ASSERT_TRUE(base_error_.empty()) << base_error_; }

    /// A fresh copy of the valid scenario and an empty output folder for the case `name`.
    static CaseDirs MakeCase(const std::string& name) {
        CaseDirs c;
        const fs::path dir = root_ / name;
        fs::remove_all(dir);
        c.scenario = dir / "scenario";
        c.out_dir = dir / "out";
        c.output = c.out_dir / "corrected.tum";
        c.params = dir / "params.yaml";
        fs::create_directories(c.out_dir);
        fs::copy(base_, c.scenario, fs::copy_options::recursive);
        return c;
    }

    static inline fs::path root_, base_;
    static inline std::string base_error_;
};

class CliBadInput : public CliTest, public ::testing::WithParamInterface<BadInputCase> {};
class CliValidInput : public CliTest, public ::testing::WithParamInterface<ValidCase> {};

TEST_P(CliBadInput, OneMessageRightExitCodeNothingWritten) {
    const BadInputCase& tc = GetParam();
    const CaseDirs c = MakeCase(tc.name);
    const std::vector<std::string> args = tc.mutate(c);
    const std::string kSentinel = "sentinel\n";
    if (tc.sentinel) WriteFile(c.output, kSentinel);

    const RunResult r = RunProgram(kCli, args, c.out_dir.parent_path());
    SCOPED_TRACE("command: " + r.command + "\nstderr:\n" + r.err);

    EXPECT_EQ(r.exit_code, tc.exit_code);
    const std::vector<std::string> messages = MessageLines(r.err);
    ASSERT_EQ(messages.size(), 1u) << "expected exactly one message line on stderr";
    const std::string& message = messages.front();
    std::cout << "  [" << tc.name << "] exit " << r.exit_code << ": " << message << "\n";
    EXPECT_EQ(message.rfind("driftcorr: ", 0), 0u) << message;
    EXPECT_EQ(message.find('\r'), std::string::npos);
    for (const std::string& pattern : tc.message) {
        EXPECT_TRUE(std::regex_search(message, std::regex(pattern)))
            << "message '" << message << "' does not contain /" << pattern << "/";
    }
    EXPECT_EQ(message.find("internal error"), std::string::npos) << message;
    if (tc.exit_code == kExitUsage) {
        EXPECT_NE(r.err.find("usage: driftcorr correct"), std::string::npos);
    }

    // Nothing written: the output folder holds nothing new (no output, no temporary).
    const std::vector<std::string> entries = FolderEntries(c.out_dir);
    if (tc.sentinel) {
        EXPECT_EQ(entries, std::vector<std::string>{"corrected.tum"});
        const std::string now = ReadFile(c.output);
        EXPECT_TRUE(now == kSentinel) << "the pre-existing output was clobbered: now " << now.size()
                                      << " bytes, starting '" << now.substr(0, 60) << "'";
    } else {
        EXPECT_TRUE(entries.empty())
            << "output folder holds " << entries.size() << " file(s), e.g. "
            << (entries.empty() ? "" : entries.front());
    }
}

INSTANTIATE_TEST_SUITE_P(Cases, CliBadInput, ::testing::ValuesIn(BadInputCases()),
                         [](const ::testing::TestParamInfo<BadInputCase>& p) {
                             return std::string(p.param.name);
                         });

TEST_P(CliValidInput, SucceedsWithOnePosePerEstimatePose) {
    const ValidCase& tc = GetParam();
    const CaseDirs c = MakeCase(tc.name);
    const std::vector<std::string> args = tc.mutate(c);
    WriteFile(c.output, "sentinel\n");  // an existing output is replaced

    const RunResult r = RunProgram(kCli, args, c.out_dir.parent_path());
    SCOPED_TRACE("command: " + r.command + "\nstderr:\n" + r.err);
    ASSERT_EQ(r.exit_code, kExitOk);
    // Progress lines and warnings (degenerate but valid input) only; no error message.
    for (const std::string& line : MessageLines(r.err)) {
        EXPECT_EQ(line.rfind("driftcorr: warning: ", 0), 0u) << "unexpected stderr line: " << line;
    }
    if (tc.name == std::string("LeavesMapExtent")) {  // the 3 km step is reported, not scaled
        EXPECT_NE(r.err.find("treated as discontinuities"), std::string::npos);
    }
    EXPECT_NE(r.out.find("wrote"), std::string::npos) << r.out;

    const driftcorr::Trajectory estimate =
        driftcorr::io::ReadTum((c.scenario / "estimate.tum").string());
    const driftcorr::Trajectory corrected = driftcorr::io::ReadTum(c.output.string());
    ASSERT_EQ(corrected.size(), estimate.size());
    for (std::size_t i = 0; i < estimate.size(); ++i) {
        ASSERT_NEAR(corrected.t_s[i], estimate.t_s[i], 1e-3) << "pose " << i;
    }
    for (std::size_t i = 0; i + 1 < args.size(); ++i) {
        if (args[i] == "--geojson") {
            EXPECT_GT(fs::file_size(args[i + 1]), 0u) << args[i + 1];
        }
    }
    for (const std::string& name : FolderEntries(c.out_dir)) {
        EXPECT_EQ(name.find(".tmp."), std::string::npos) << "temporary left behind: " << name;
    }
}

INSTANTIATE_TEST_SUITE_P(Cases, CliValidInput, ::testing::ValuesIn(ValidCases()),
                         [](const ::testing::TestParamInfo<ValidCase>& p) {
                             return std::string(p.param.name);
                         });

TEST(CliHelp, ListsTheCommandsAndExitsZero) {
    for (const char* flag : {"--help", "-h", "help"}) {
        const RunResult r = RunProgram(kCli, {flag}, fs::path(DRIFTCORR_TEST_TMPDIR));
        EXPECT_EQ(r.exit_code, kExitOk) << flag;
        for (const char* cmd : {"correct", "stream", "eval", "--on-failure", "--covariance"}) {
            EXPECT_NE(r.out.find(cmd), std::string::npos) << flag << " does not mention " << cmd;
        }
    }
}

// `params --preset NAME` prints the sections model and corrector at a preset's values, in the
// lines `params` prints; `road` gives the defaults' (the start of `params`), a bad name is a usage
// error naming the valid ones.
TEST(CliParams, PresetPrintsTheModelAndCorrectorAtItsValues) {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "cli_params";  // its own capture files
    fs::create_directories(dir);
    const RunResult all = RunProgram(kCli, {"params"}, dir);
    const RunResult road = RunProgram(kCli, {"params", "--preset", "road"}, dir);
    const RunResult walk = RunProgram(kCli, {"params", "--preset", "pedestrian"}, dir);
    for (const RunResult* r : {&all, &road, &walk}) {
        ASSERT_EQ(r->exit_code, kExitOk) << r->command << "\n" << r->err;
        EXPECT_EQ(r->err, "") << r->command;
    }
    const std::string header = "# driftcorr params --preset ";
    ASSERT_EQ(road.out.rfind(header + "road\n", 0), 0u) << road.out;
    ASSERT_EQ(walk.out.rfind(header + "pedestrian\n", 0), 0u) << walk.out;
    const std::string road_sections = road.out.substr(road.out.find('\n') + 1);
    EXPECT_EQ(all.out.rfind(road_sections, 0), 0u) << road_sections;
    EXPECT_NE(road.out.find("\n  max_speed_mps: 70 "), std::string::npos) << road.out;
    EXPECT_NE(walk.out.find("\n  max_speed_mps: 10 "), std::string::npos) << walk.out;
    EXPECT_NE(walk.out.find("\n  chunk_m: 15 "), std::string::npos) << walk.out;
    EXPECT_NE(walk.out.find("\nmodel:  # "), std::string::npos) << walk.out;
    EXPECT_NE(walk.out.find("\ncorrector:  # "), std::string::npos) << walk.out;
    EXPECT_EQ(walk.out.find("indoor_"), std::string::npos) << walk.out;

    for (const std::string bad : {"car", "Pedestrian", ""}) {
        const RunResult r = RunProgram(kCli, {"params", "--preset", bad}, dir);
        EXPECT_EQ(r.exit_code, kExitUsage) << bad;
        EXPECT_EQ(r.out, "") << bad;
        const std::vector<std::string> lines = MessageLines(r.err);
        ASSERT_EQ(lines.size(), 1u) << r.err;
        EXPECT_EQ(lines[0], "driftcorr: --preset must be road or pedestrian, not '" + bad + "'");
    }
    const RunResult missing = RunProgram(kCli, {"params", "--preset"}, dir);
    EXPECT_EQ(missing.exit_code, kExitUsage);
    EXPECT_NE(missing.err.find("--preset needs a value"), std::string::npos) << missing.err;
}

// The valid scenario with its anchor turned by 30 deg: the start does not fit the map, the verdict
// is failed, and what is written depends on --on-failure; the exit code is 3 in every case.
class CliOnFailure : public CliTest {
protected:
    CaseDirs WrongAnchor(const std::string& name) {
        const CaseDirs c = MakeCase(name);
        RegexReplace(c.scenario / "scenario.yaml", "\n  yaw_deg: [^\n]*", "\n  yaw_deg: 30.0");
        return c;
    }
};

TEST_F(CliOnFailure, EvalExitsThreeWhenTheVerdictFailed) {
    const CaseDirs c = WrongAnchor("EvalVerdictFailed");
    const RunResult r = RunProgram(
        kCli, {"eval", c.scenario.string(), "--methods", "estimate,driftcorr", "--quiet"},
        c.out_dir.parent_path());
    EXPECT_EQ(r.exit_code, kExitSolver) << r.err;
    EXPECT_NE(r.err.find("verdict is failed on 1 of 1"), std::string::npos) << r.err;
}

TEST_F(CliOnFailure, RefuseWritesNothing) {
    const CaseDirs c = WrongAnchor("OnFailureRefuse");
    const RunResult r = RunProgram(kCli, Correct(c), c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    EXPECT_EQ(r.exit_code, kExitSolver);
    EXPECT_NE(r.out.find("verdict    failed"), std::string::npos);
    EXPECT_NE(r.out.find("the anchor does not fit the map"), std::string::npos);
    EXPECT_TRUE(FolderEntries(c.out_dir).empty());
}

TEST_F(CliOnFailure, EstimateWritesTheInputUnchanged) {
    const CaseDirs c = WrongAnchor("OnFailureEstimate");
    const RunResult r =
        RunProgram(kCli, Correct(c, {"--on-failure", "estimate"}), c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    EXPECT_EQ(r.exit_code, kExitSolver);
    const driftcorr::Trajectory est =
        driftcorr::io::ReadTum((c.scenario / "estimate.tum").string());
    const driftcorr::Trajectory out = driftcorr::io::ReadTum(c.output.string());
    ASSERT_EQ(out.size(), est.size());
    for (std::size_t i = 0; i < est.size(); ++i) {
        ASSERT_LT((out.p_frame[i] - est.p_frame[i]).norm(), 1e-5) << "pose " << i;
    }
}

TEST_F(CliOnFailure, WriteWritesTheResultAndPerPoseCovariance) {
    const CaseDirs c = WrongAnchor("OnFailureWrite");
    const fs::path cov = c.out_dir / "poses.txt";
    const RunResult r =
        RunProgram(kCli, Correct(c, {"--on-failure", "write", "--covariance", cov.string()}),
                   c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    EXPECT_EQ(r.exit_code, kExitSolver);
    const driftcorr::Trajectory est =
        driftcorr::io::ReadTum((c.scenario / "estimate.tum").string());
    const driftcorr::Trajectory out = driftcorr::io::ReadTum(c.output.string());
    ASSERT_EQ(out.size(), est.size());
    double moved_m = 0.0;
    for (std::size_t i = 0; i < est.size(); ++i) {
        moved_m = std::max(moved_m, (out.p_frame[i] - est.p_frame[i]).norm());
    }
    EXPECT_GT(moved_m, 1.0) << "the corrected result, not the estimate";
    // One row per pose after the header: t and five (co)variances, the flags.
    std::istringstream rows(ReadFile(cov));
    std::size_t n = 0;
    for (std::string line; std::getline(rows, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream fields(line);
        double t, ve, cen, vn, vu, vyaw;
        unsigned flags;
        ASSERT_TRUE(fields >> t >> ve >> cen >> vn >> vu >> vyaw >> flags) << line;
        if (n > 0) {
            EXPECT_GT(ve, 0.0) << line;
        }
        EXPECT_LE(cen * cen, ve * vn * (1 + 1e-9)) << line;
        ++n;
    }
    EXPECT_EQ(n, est.size());
}

}  // namespace

namespace {

// ---- a trajectory file with --osm and --anchor; many scenarios with -j and --manifest --------

class CliFormats : public CliTest {
protected:
    /// `driftcorr correct <scenario>/estimate.tum --osm <scenario>/map.osm --anchor ...`.
    static std::vector<std::string> CorrectFile(const CaseDirs& c, const std::string& trajectory,
                                                const std::vector<std::string>& extra) {
        std::vector<std::string> args = {"correct", trajectory,
                                         "--osm",   (c.scenario / "map.osm").string(),
                                         "-o",      c.output.string()};
        args.insert(args.end(), extra.begin(), extra.end());
        return args;
    }
};

// The numbers of two texts of the same shape, each pair within `tolerance`.
void ExpectSameNumbers(const std::string& a, const std::string& b, double tolerance) {
    std::istringstream sa(a), sb(b);
    std::size_t n = 0;
    for (double x, y; sa >> x;) {
        ASSERT_TRUE(sb >> y) << "the second text ends after " << n << " numbers";
        ASSERT_NEAR(x, y, tolerance) << "number " << n;
        ++n;
    }
    double extra;
    EXPECT_FALSE(sb >> extra) << "the second text has more than " << n << " numbers";
    EXPECT_GT(n, 0u);
}

// The scenario's own anchor (48.98, 8.39, yaw 0, enu) given on the command line gives the same
// corrected trajectory as the scenario file. Not to the last digit: the command line has no
// altitude (the scenario's is 115 m), so the map's projection differs in its rounding, and the
// final solve stops at a tolerance, not where every such difference has been washed out.
TEST_F(CliFormats, TrajectoryWithOsmAndAnchorMatchesTheScenario) {
    const CaseDirs c = MakeCase("FileAndAnchor");
    const fs::path via_scenario = c.out_dir.parent_path() / "via_scenario.tum";
    ASSERT_EQ(RunProgram(kCli, {"correct", c.scenario.string(), "-o", via_scenario.string()},
                         c.out_dir.parent_path())
                  .exit_code,
              kExitOk);
    const RunResult r = RunProgram(kCli,
                                   CorrectFile(c, (c.scenario / "estimate.tum").string(),
                                               {"--anchor", "48.98,8.39,0", "--frame", "enu"}),
                                   c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    ASSERT_EQ(r.exit_code, kExitOk);
    ExpectSameNumbers(ReadFile(c.output), ReadFile(via_scenario), 1e-6);
}

// An anchor with latitude and longitude swapped puts the drive thousands of kilometres from the
// map: bad input before any solve, naming the likely cause; an anchor 50 km off is bad input too,
// without that hint.
TEST_F(CliFormats, AnAnchorFarFromTheMapIsBadInputBeforeTheSolve) {
    const CaseDirs c = MakeCase("SwappedAnchor");
    const std::string estimate = (c.scenario / "estimate.tum").string();
    const RunResult swapped =
        RunProgram(kCli, CorrectFile(c, estimate, {"--anchor", "8.39,48.98,0", "--frame", "enu"}),
                   c.out_dir.parent_path());
    SCOPED_TRACE(swapped.out + swapped.err);
    EXPECT_EQ(swapped.exit_code, kExitBadInput);
    EXPECT_NE(swapped.err.find("from the nearest road of the map"), std::string::npos);
    EXPECT_NE(swapped.err.find("lat and lon look swapped"), std::string::npos);
    EXPECT_EQ(swapped.out.find("solver"), std::string::npos) << "refused before the solve";
    EXPECT_FALSE(fs::exists(c.output));

    const RunResult far =
        RunProgram(kCli, CorrectFile(c, estimate, {"--anchor", "48.5,8.39,0", "--frame", "enu"}),
                   c.out_dir.parent_path());
    SCOPED_TRACE(far.out + far.err);
    EXPECT_EQ(far.exit_code, kExitBadInput);
    EXPECT_NE(far.err.find("check the anchor and the map file"), std::string::npos);
}

// --scale S multiplies the trajectory's positions: a file written at a tenth of its size and
// given --scale 10 is corrected as the metric file is; --scale 0 is bad input naming the flag.
TEST_F(CliFormats, ScaleOnTheCommandLine) {
    const CaseDirs c = MakeCase("ScaleFlag");
    const fs::path metric = c.out_dir.parent_path() / "metric.tum";
    const std::string estimate = (c.scenario / "estimate.tum").string();
    ASSERT_EQ(
        RunProgram(kCli, CorrectFile(c, estimate, {"--anchor", "48.98,8.39,0", "--frame", "enu"}),
                   c.out_dir.parent_path())
            .exit_code,
        kExitOk);
    fs::rename(c.output, metric);
    std::istringstream in(ReadFile(estimate));
    std::ostringstream small;
    for (std::string line; std::getline(in, line);) {
        std::istringstream f(line);
        double v[8];
        for (double& x : v) f >> x;
        if (!f) continue;
        small << std::setprecision(17) << v[0] << ' ' << 0.1 * v[1] << ' ' << 0.1 * v[2] << ' '
              << 0.1 * v[3] << ' ' << v[4] << ' ' << v[5] << ' ' << v[6] << ' ' << v[7] << '\n';
    }
    const fs::path small_path = c.out_dir.parent_path() / "small.tum";
    std::ofstream(small_path) << small.str();
    const RunResult r =
        RunProgram(kCli,
                   CorrectFile(c, small_path.string(),
                               {"--anchor", "48.98,8.39,0", "--frame", "enu", "--scale", "10"}),
                   c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    ASSERT_EQ(r.exit_code, kExitOk);
    ExpectSameNumbers(ReadFile(c.output), ReadFile(metric.string()), 1e-3);

    const RunResult zero =
        RunProgram(kCli,
                   CorrectFile(c, small_path.string(),
                               {"--anchor", "48.98,8.39,0", "--frame", "enu", "--scale", "0"}),
                   c.out_dir.parent_path());
    EXPECT_EQ(zero.exit_code, kExitBadInput);
    EXPECT_NE(zero.err.find("--scale: must be auto or a number"), std::string::npos) << zero.err;
}

// A user's own ground truth beside a trajectory file: the summary gives the same errors as the
// scenario file that names it; an output naming it is refused as an input.
TEST_F(CliFormats, GroundTruthOnTheCommandLineGivesTheErrors) {
    const CaseDirs c = MakeCase("GroundTruthFlag");
    const std::string gt = (c.scenario / "ground_truth.tum").string();
    const RunResult via_scenario = RunProgram(
        kCli, {"correct", c.scenario.string(), "-o", c.output.string()}, c.out_dir.parent_path());
    ASSERT_EQ(via_scenario.exit_code, kExitOk) << via_scenario.err;
    const RunResult r = RunProgram(
        kCli,
        CorrectFile(c, (c.scenario / "estimate.tum").string(),
                    {"--anchor", "48.98,8.39,0", "--frame", "enu", "--ground-truth", gt}),
        c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    ASSERT_EQ(r.exit_code, kExitOk);
    auto ate_line = [](const std::string& out, const std::string& row) {
        std::size_t at = out.find("\n  " + row + " ");
        if (at == std::string::npos) return std::string();
        ++at;
        return out.substr(at, out.find('\n', at) - at);
    };
    ASSERT_FALSE(ate_line(r.out, "estimate").empty());
    EXPECT_EQ(ate_line(r.out, "estimate"), ate_line(via_scenario.out, "estimate"));
    EXPECT_EQ(ate_line(r.out, "corrected"), ate_line(via_scenario.out, "corrected"));

    const RunResult overwrite =
        RunProgram(kCli,
                   {"correct", (c.scenario / "estimate.tum").string(), "--osm",
                    (c.scenario / "map.osm").string(), "-o", gt, "--anchor", "48.98,8.39,0",
                    "--frame", "enu", "--ground-truth", gt},
                   c.out_dir.parent_path());
    EXPECT_EQ(overwrite.exit_code, kExitBadInput);
    EXPECT_NE(overwrite.err.find("destroy an input"), std::string::npos) << overwrite.err;
    EXPECT_EQ(RunProgram(kCli,
                         CorrectFile(c, (c.scenario / "estimate.tum").string(),
                                     {"--anchor", "48.98,8.39,0", "--frame", "enu",
                                      "--ground-truth-times", gt}),
                         c.out_dir.parent_path())
                  .exit_code,
              kExitBadInput);
}

// A start that does not fit the map (the yaw 40 deg off), given on the command line: the advice
// names the flag, not the scenario key.
TEST_F(CliFormats, FailureAdviceNamesTheFlagsTheUserGave) {
    const CaseDirs c = MakeCase("AdviceInFlags");
    const RunResult r = RunProgram(kCli,
                                   CorrectFile(c, (c.scenario / "estimate.tum").string(),
                                               {"--anchor", "48.98,8.39,40", "--frame", "enu"}),
                                   c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    EXPECT_EQ(r.exit_code, kExitSolver);
    EXPECT_NE((r.out + r.err)
                  .find("check the yaw and the position of --anchor, or give --anchor "
                        "LAT,LON,auto"),
              std::string::npos);
    EXPECT_EQ((r.out + r.err).find("yaw_deg"), std::string::npos);
}

// An enu drive read as kitti_camera climbs by its northward travel: bad input before the solve,
// asking whether the axes are those of the frame.
TEST_F(CliFormats, AWrongFrameIsBadInputBeforeTheSolve) {
    const CaseDirs c = MakeCase("WrongFrame");
    const RunResult r =
        RunProgram(kCli,
                   CorrectFile(c, (c.scenario / "estimate.tum").string(),
                               {"--anchor", "48.98,8.39,0", "--frame", "kitti_camera"}),
                   c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    EXPECT_EQ(r.exit_code, kExitBadInput);
    EXPECT_NE(r.err.find("frame: with frame kitti_camera the estimate's height spans"),
              std::string::npos);
    EXPECT_FALSE(fs::exists(c.output));
}

/// The TUM lines `t x y z qx qy qz qw` of `tum` as positions only, `t x y z`.
std::string PositionsOnly(const std::string& tum) {
    std::istringstream full(tum);
    std::string positions;
    for (std::string line; std::getline(full, line);) {
        std::istringstream f(line);
        std::string t, x, y, z;
        f >> t >> x >> y >> z;
        positions += t + " " + x + " " + y + " " + z + "\n";
    }
    return positions;
}

// stream reads poses with orientation: a replayed positions-only estimate is bad input naming
// the file (it crashed before the check).
TEST_F(CliFormats, StreamRefusesAPositionsOnlyEstimate) {
    const CaseDirs c = MakeCase("StreamPositionsOnly");
    const std::string positions = PositionsOnly(ReadFile(c.scenario / "estimate.tum"));
    WriteFile(c.scenario / "estimate.tum", positions);
    const RunResult r =
        RunProgram(kCli, {"stream", c.scenario.string(), "--replay"}, c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    EXPECT_EQ(r.exit_code, kExitBadInput);
    EXPECT_NE(r.err.find("estimate.tum: the estimate has positions only"), std::string::npos);
}

TEST_F(CliFormats, PositionsOnlyTumSaysTheHeadingCameFromTheMotion) {
    const CaseDirs c = MakeCase("PositionsOnly");
    const std::string positions = PositionsOnly(ReadFile(c.scenario / "estimate.tum"));
    const fs::path traj = c.out_dir.parent_path() / "positions.tum";
    WriteFile(traj, positions);
    const fs::path geojson = c.out_dir / "tracks.geojson";
    const RunResult r = RunProgram(
        kCli,
        CorrectFile(c, traj.string(),
                    {"--anchor", "48.98,8.39,0", "--frame", "enu", "--geojson", geojson.string()}),
        c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    ASSERT_EQ(r.exit_code, kExitOk);
    EXPECT_NE(r.out.find("heading    from the direction of motion (the estimate has no "
                         "orientation"),
              std::string::npos);
    // evo's TUM reader: 8 space-separated numbers a line, no header, no trailing space.
    const std::string tum = ReadFile(c.output);
    const std::regex line_re(R"(-?\d+\.\d+( -?\d+\.\d+){7})");
    std::istringstream lines(tum);
    std::size_t n = 0;
    for (std::string line; std::getline(lines, line); ++n) {
        ASSERT_TRUE(std::regex_match(line, line_re)) << "line " << n + 1 << ": '" << line << "'";
    }
    EXPECT_EQ(n, driftcorr::io::ReadTum(traj.string()).size());
    // Per-vertex timestamps in the GeoJSON, as many as coordinates.
    const std::string json = ReadFile(geojson);
    EXPECT_NE(json.find("\"coordinateProperties\":{\"times\":[1000.000000,1000.100000,"),
              std::string::npos);
}

TEST_F(CliFormats, EurocCsvNeedsNoFrameAndAnchorMayBeAuto) {
    const CaseDirs c = MakeCase("Euroc");
    const driftcorr::Trajectory est =
        driftcorr::io::ReadTum((c.scenario / "estimate.tum").string());
    std::string csv = "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m]\n";
    for (std::size_t i = 0; i < est.size(); ++i) {
        char line[128];
        std::snprintf(line, sizeof(line), "%lld,%.6f,%.6f,%.6f\n",
                      static_cast<long long>(std::llround(est.t_s[i] * 1e9)), est.p_frame[i].x(),
                      est.p_frame[i].y(), est.p_frame[i].z());
        csv += line;
    }
    const fs::path traj = c.out_dir.parent_path() / "leica0.csv";
    WriteFile(traj, csv);
    const RunResult r =
        RunProgram(kCli, CorrectFile(c, traj.string(), {"--anchor", "48.98,8.39,auto"}),
                   c.out_dir.parent_path());
    SCOPED_TRACE(r.out + r.err);
    ASSERT_EQ(r.exit_code, kExitOk);
    EXPECT_NE(r.out.find("anchor     estimated yaw"), std::string::npos);
    EXPECT_EQ(driftcorr::io::ReadTum(c.output.string()).size(), est.size());
}

TEST_F(CliFormats, MissingOrBadOptionsAreNamed) {
    const CaseDirs c = MakeCase("BadOptions");
    const std::string traj = (c.scenario / "estimate.tum").string();
    struct Bad {
        std::vector<std::string> extra;
        int code;
        std::string message;
    };
    const std::vector<Bad> cases = {
        {{"--anchor", "48.98,8.39,0"}, kExitBadInput, "estimate.tum: --frame: missing"},
        {{"--anchor", "48.98,8.39", "--frame", "enu"},
         kExitBadInput,
         "--anchor: expected LAT,LON,YAW"},
        {{"--anchor", "48.98,east,0", "--frame", "enu"},
         kExitBadInput,
         "--anchor: longitude 'east' is not a number"},
        {{"--frame", "enu"}, kExitUsage, "missing --anchor"},
        {{"--anchor", "1,2,0", "--crs", "EPSG:banana", "--frame", "enu"},
         kExitBadInput,
         "--crs: unknown CRS spelling"},
        {{"--anchor", "91,8.39,0", "--frame", "enu"},
         kExitBadInput,
         "--anchor: the latitude must be within [-90, 90]"},
        {{"--anchor", "48.98,-180.5,0", "--frame", "enu"},
         kExitBadInput,
         "--anchor: the longitude must be within [-180, 180]"},
        {{"--anchor", "48.98,8.39,0", "--frame", "enu", "--format", "gpx"},
         kExitBadInput,
         "--format: unknown format 'gpx'"},
    };
    for (const Bad& b : cases) {
        const RunResult r =
            RunProgram(kCli, CorrectFile(c, traj, b.extra), c.out_dir.parent_path());
        EXPECT_EQ(r.exit_code, b.code) << r.err;
        EXPECT_NE(r.err.find(b.message), std::string::npos) << r.err;
        EXPECT_TRUE(FolderEntries(c.out_dir).empty());
    }
}

TEST_F(CliFormats, PbfThatIsTruncatedOrNotPbfIsBadInputNamingTheFile) {
    const CaseDirs c = MakeCase("BadPbf");
    const fs::path pbf = c.out_dir.parent_path() / "map.osm.pbf";
    // A PBF's first blob header, cut off: the length prefix and the start of "OSMHeader".
    WriteFile(pbf, std::string("\x00\x00\x00\x0d\x0a\x09OSMHe", 11));
    const std::string traj = (c.scenario / "estimate.tum").string();
    for (const std::string& content :
         {std::string("\x00\x00\x00\x0d\x0a\x09OSMHe", 11), std::string("PK\x03\x04 a zip file")}) {
        WriteFile(pbf, content);
        const RunResult r = RunProgram(kCli,
                                       {"correct", traj, "--osm", pbf.string(), "--anchor",
                                        "48.98,8.39,0", "--frame", "enu", "-o", c.output.string()},
                                       c.out_dir.parent_path());
        EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
        EXPECT_NE(r.err.find(pbf.string() + ": is neither OSM XML"), std::string::npos) << r.err;
        EXPECT_TRUE(FolderEntries(c.out_dir).empty());
    }
}

// Three scenarios and a manifest line that names no scenario: the bad line is reported with its
// line, the others are written, the exit code is 2 (bad input before failed).
TEST_F(CliFormats, ManyScenariosOnThreadsOneBadLineDoesNotStopTheOthers) {
    const CaseDirs c = MakeCase("Batch");
    const fs::path root = c.out_dir.parent_path();
    fs::copy(c.scenario, root / "second", fs::copy_options::recursive);
    const fs::path manifest = root / "manifest.txt";
    WriteFile(manifest, "# drives\nsecond\n\nno_such_scenario\n");
    const fs::path out = root / "batch_out";
    const RunResult r = RunProgram(kCli,
                                   {"correct", c.scenario.string(), "--manifest", manifest.string(),
                                    "-o", out.string(), "-j", "2", "--geojson", out.string()},
                                   root);
    SCOPED_TRACE(r.out + r.err);
    EXPECT_EQ(r.exit_code, kExitBadInput);
    EXPECT_NE(
        r.out.find("no_such_scenario                 bad input (" + manifest.string() + ":4)"),
        std::string::npos);
    EXPECT_NE(r.out.find("2 of 3 scenarios corrected and written"), std::string::npos);
    const std::vector<std::string> expected = {"scenario.geojson", "scenario.tum", "second.geojson",
                                               "second.tum"};
    std::vector<std::string> entries = FolderEntries(out);
    std::sort(entries.begin(), entries.end());
    EXPECT_EQ(entries, expected);
    EXPECT_EQ(ReadFile(out / "scenario.tum"), ReadFile(out / "second.tum"));

    // The same two good scenarios one at a time give the same files.
    const fs::path out1 = root / "batch_out_j1";
    const RunResult r1 = RunProgram(kCli,
                                    {"correct", c.scenario.string(), (root / "second").string(),
                                     "-o", out1.string(), "-j", "1"},
                                    root);
    EXPECT_EQ(r1.exit_code, kExitOk) << r1.out << r1.err;
    EXPECT_EQ(ReadFile(out1 / "second.tum"), ReadFile(out / "second.tum"));
}

TEST_F(CliFormats, BatchUsageErrors) {
    const CaseDirs c = MakeCase("BatchUsage");
    const std::string s = c.scenario.string();
    const fs::path root = c.out_dir.parent_path();
    EXPECT_EQ(
        RunProgram(kCli, {"correct", s, s, "-o", (root / "o").string(), "-j", "0"}, root).exit_code,
        kExitUsage);
    EXPECT_EQ(
        RunProgram(kCli, {"correct", s, s, "-o", (root / "o").string(), "--osm", "m.osm"}, root)
            .exit_code,
        kExitUsage);
    // Two scenarios whose outputs would collide: bad input before any work.
    const RunResult r = RunProgram(kCli, {"correct", s, s, "-o", (root / "o").string()}, root);
    EXPECT_EQ(r.exit_code, kExitBadInput);
    EXPECT_NE(r.err.find("its output would be scenario.tum, as for argument 1"), std::string::npos)
        << r.err;
    const RunResult m = RunProgram(
        kCli, {"correct", "--manifest", (root / "none.txt").string(), "-o", (root / "o").string()},
        root);
    EXPECT_EQ(m.exit_code, kExitBadInput);
    EXPECT_NE(m.err.find("none.txt: --manifest: cannot open file"), std::string::npos) << m.err;
}

// `eval --methods` runs the methods listed, in that order, and names a bad list.
TEST_F(CliFormats, EvalRunsTheListedMethodsOnly) {
    const CaseDirs c = MakeCase("EvalMethods");
    const std::string s = c.scenario.string();
    const fs::path root = c.out_dir.parent_path();
    const RunResult r = RunProgram(kCli, {"eval", s, "--methods", "online,estimate", "-q"}, root);
    SCOPED_TRACE(r.out + r.err);
    ASSERT_EQ(r.exit_code, kExitOk);
    const std::size_t online = r.out.find("| online"), estimate = r.out.find("| estimate");
    ASSERT_NE(online, std::string::npos);
    ASSERT_NE(estimate, std::string::npos);
    EXPECT_LT(online, estimate);
    EXPECT_EQ(r.out.find("paper"), std::string::npos);
    EXPECT_EQ(r.out.find("driftcorr "), std::string::npos);
    for (const char* bad : {"online,bogus", "online,online", ""}) {
        const RunResult u = RunProgram(kCli, {"eval", s, "--methods", bad}, root);
        EXPECT_EQ(u.exit_code, kExitUsage) << bad;
        EXPECT_NE(u.err.find("--methods"), std::string::npos) << bad << ": " << u.err;
    }
}

// ---- map extract ------------------------------------------------------------------------------

// An ASCII PCD of `points`.
void WritePcd(const fs::path& path, const std::vector<std::array<double, 3>>& points) {
    std::ostringstream o;
    o << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH "
      << points.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << points.size()
      << "\nDATA ascii\n";
    for (const auto& p : points) o << p[0] << " " << p[1] << " " << p[2] << "\n";
    WriteFile(path, o.str());
}

// A 6 m x 5 m room scanned at 0.1 m: floor, four walls and a ceiling 2.7 m up, times `scale`.
std::vector<std::array<double, 3>> Room(double scale) {
    std::vector<std::array<double, 3>> p;
    for (double y = 0.05; y < 5.0; y += 0.1) {
        for (double x = 0.05; x < 6.0; x += 0.1) p.push_back({x, y, 0.0}), p.push_back({x, y, 2.7});
    }
    for (double z = 0.0; z < 2.7; z += 0.1) {
        for (double x = 0.0; x < 6.0; x += 0.1)
            p.push_back({x, -0.05, z}), p.push_back({x, 5.05, z});
        for (double y = 0.0; y < 5.0; y += 0.1)
            p.push_back({-0.05, y, z}), p.push_back({6.05, y, z});
    }
    for (auto& q : p) q = {q[0] * scale, q[1] * scale, q[2] * scale};
    return p;
}

TEST(CliMap, ExtractWritesTheSurfaceAndAPicturePerFloor) {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "map_extract";
    fs::remove_all(dir);
    fs::create_directories(dir);
    WritePcd(dir / "room.pcd", Room(1.0));
    const RunResult r = RunProgram(
        kCli, {"map", "extract", (dir / "room.pcd").string(), "-o", (dir / "walk.ply").string()},
        dir);
    ASSERT_EQ(r.exit_code, kExitOk) << r.err;
    EXPECT_NE(r.out.find("walkable   30.0 m^2 in 1 region(s)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ceiling or roof seen from below"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(dir / "walk.ply"));
    ASSERT_TRUE(fs::exists(dir / "walk_floor_0.00.svg")) << r.out;
    EXPECT_NE(ReadFile(dir / "walk_floor_0.00.svg").find("30.0 m^2 walkable"), std::string::npos);
}

TEST(CliMap, BadRawMapsAreNamedWithWhatWasFound) {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "map_extract_bad";
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::vector<std::array<double, 3>> wall;
    for (double z = 0.0; z < 3.0; z += 0.1) {
        for (double x = 0.0; x < 8.0; x += 0.1)
            wall.push_back({x, 0.0, z}), wall.push_back({x, 0.1, z});
    }
    WritePcd(dir / "wall.pcd", wall);
    WritePcd(dir / "room_mm.pcd", Room(1000.0));
    const std::string out = (dir / "walk.pcd").string();
    struct Case {
        std::vector<std::string> args;
        int code;
        std::string message;
    };
    const std::vector<Case> cases = {
        {{"map", "extract", (dir / "wall.pcd").string(), "-o", out},
         kExitBadInput,
         "wall.pcd: no walkable surface: the largest horizontal surface with 1.80 m free above "
         "it is "},
        {{"map", "extract", (dir / "room_mm.pcd").string(), "-o", out},
         kExitBadInput,
         "room_mm.pcd: the cloud spans 6"},
        {{"map", "extract", (dir / "room_mm.pcd").string(), "-o", out},
         kExitBadInput,
         "not a building in metres (millimetres or centimetres?"},
        {{"map", "extract", (dir / "none.pcd").string(), "-o", out}, kExitBadInput, "none.pcd"},
        {{"map", "extract", (dir / "wall.pcd").string(), "-o", (dir / "walk.txt").string()},
         kExitBadInput,
         "written as .pcd or .ply"},
        {{"map", "extract", (dir / "wall.pcd").string(), "-o", out, "--lifts", "1,2,3"},
         kExitBadInput,
         "--lifts: a shaft is x0,y0,x1,y1"},
        {{"map", "extract", (dir / "wall.pcd").string()},
         kExitUsage,
         "-o walkable.pcd|.ply is required"},
        {{"map", "carve", (dir / "wall.pcd").string(), "-o", out},
         kExitUsage,
         "expected 'extract'"},
    };
    for (const Case& c : cases) {
        const RunResult r = RunProgram(kCli, c.args, dir);
        EXPECT_EQ(r.exit_code, c.code) << c.args[2] << ": " << r.err;
        EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(out)) << c.args[2];
    }
}

// A fresh synthetic building scenario (datasets/synth_building) in `dir`.
void MakeBuildingScenario(const fs::path& dir) {
    fs::remove_all(dir);
    const RunResult g =
        RunProgram(DRIFTCORR_BINARY_DIR "/datasets/driftcorr_make_building_scenario",
                   {dir.string()}, fs::path(DRIFTCORR_TEST_TMPDIR));
    ASSERT_EQ(g.exit_code, 0) << g.err;
}

TEST(CliMap, AWalkThatStartsOffTheWalkableSurfaceIsBadInput) {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "walk_off_surface";
    ASSERT_NO_FATAL_FAILURE(MakeBuildingScenario(dir));
    // The anchor 2.5 m lower: the walk's heights no longer meet the map's floors.
    Replace(dir / "scenario.yaml", "  z_m: 0.0", "  z_m: -2.5");
    const fs::path out = dir / "corrected.tum";
    const RunResult r = RunProgram(kCli, {"correct", dir.string(), "-o", out.string()}, dir);
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("scenario.yaml: estimate: the walk starts"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("map and walk are not in one frame"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

// The synthetic building's raw scan (walls, ceilings, furniture, noise, holes): the extracted
// surface against the true walkable surface the generator knows (without the floor under the
// furniture), and the correction on it against the correction on the clean surface.
TEST(CliMap, RawBuildingScanGivesTheWalkableSurfaceAndTheSameCorrection) {
    const fs::path dir = fs::path(DRIFTCORR_TEST_TMPDIR) / "raw_building";
    ASSERT_NO_FATAL_FAILURE(MakeBuildingScenario(dir));
    const RunResult x = RunProgram(kCli,
                                   {"map", "extract", (dir / "building_raw.pcd").string(), "-o",
                                    (dir / "walkable.pcd").string(), "--lifts", "50,17.5,52,19.5"},
                                   dir);
    ASSERT_EQ(x.exit_code, kExitOk) << x.err;
    std::printf("%s", x.out.c_str());
    // The layer line for the scenario, with the shaft the generator declares in its own scenarios.
    EXPECT_NE(x.out.find("scenario   map: [{path: walkable.pcd, lifts: [[50, 17.5, 52, 19.5]]}]"),
              std::string::npos)
        << x.out;
    EXPECT_NE(ReadFile(dir / "scenario.yaml").find("lifts: [[50, 17.5, 52, 19.5]]"),
              std::string::npos);
    const driftcorr::SurfaceAgreement a = driftcorr::CompareSurfaces(
        driftcorr::ReadSurfacePointsPcd((dir / "walkable.pcd").string()),
        driftcorr::ReadSurfacePointsPcd((dir / "building_raw_walkable.pcd").string()), 0.1, 0.3);
    std::printf("extracted surface: precision %.4f, recall %.4f (%zu points, %zu true)\n",
                a.precision, a.recall, a.extracted, a.truth);
    EXPECT_GE(a.precision, 0.95);
    EXPECT_GE(a.recall, 0.95);
    for (const std::string floor : {"0.00", "4.00", "8.00"}) {
        EXPECT_TRUE(fs::exists(dir / ("walkable_floor_" + floor + ".svg"))) << x.out;
    }
    Replace(dir / "scenario.yaml", "name: synthetic-building-pcd", "name: synthetic-building-raw");
    std::string yaml = ReadFile(dir / "scenario.yaml");
    WriteFile(dir / "scenario_extracted.yaml",
              std::regex_replace(yaml, std::regex("path: building\\.pcd"), "path: walkable.pcd"));
    auto ate = [&](const std::string& scenario) {
        const RunResult r = RunProgram(
            kCli, {"correct", (dir / scenario).string(), "-o", (dir / "c.tum").string()}, dir);
        EXPECT_EQ(r.exit_code, kExitOk) << scenario << ": " << r.err;
        std::smatch m;
        const bool found = std::regex_search(r.out, m, std::regex("corrected  ATE +([0-9.]+) m"));
        EXPECT_TRUE(found) << r.out;
        EXPECT_NE(r.out.find("right floor 100.0 %"), std::string::npos) << r.out;
        return found ? std::stod(m[1]) : 1e9;
    };
    const double clean = ate("scenario.yaml"), extracted = ate("scenario_extracted.yaml");
    std::printf("corrected ATE: clean surface %.2f m, extracted %.2f m\n", clean, extracted);
    EXPECT_LE(std::abs(extracted - clean), 0.1);
}

}  // namespace
