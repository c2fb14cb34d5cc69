// `driftcorr map extract`: the walkable surface of a raw 3D map (mapping/walkable_surface.h),
// written as a point cloud an indoor scenario can name as its map, with a picture per floor.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "commands.h"
#include "driftcorr/core/errors.h"
#include "driftcorr/core/format.h"
#include "driftcorr/mapping/atomic_file.h"
#include "driftcorr/mapping/walkable_surface.h"
#include "driftcorr/pipeline/surface_io_loader.h"

namespace driftcorr::cli {
namespace {

const char* kMapUsage =
    "usage: driftcorr map extract <raw map: .pcd | .ply | .bt | .ot> -o walkable.pcd|.ply\n"
    "                             [--resolution M] [--headroom M] [--step M] [--min-area M2]\n"
    "                             [--fill-gap M]\n"
    "                             [--lifts x0,y0,x1,y1[;x0,y0,x1,y1...]]\n"
    "\n"
    "Finds where a person can stand in a raw 3D map of a building (a point cloud of a mapping\n"
    "run, or the occupied voxels of an OctoMap): occupied voxels with --headroom (1.8 m) of free\n"
    "space above, connected to their neighbours within --step (0.25 m; stairs are treads a riser\n"
    "apart), in regions of at least --min-area (4 m^2) connected to the largest one, in voxels\n"
    "of --resolution (0.1 m; an OctoMap's own voxel size by default). A lift does\n"
    "not show in a scan: --lifts declares each shaft's footprint [m, the map's frame], walkable\n"
    "at every 0.25 m between the floors it touches; the scenario's map layer declares them\n"
    "again (lifts: [[x0, y0, x1, y1]], printed below) so that a lift ride is corrected into its\n"
    "shaft. Gaps of the scan up to --fill-gap (2 m:\n"
    "holes, a doorway lost to a hole) are closed where nothing stands in the way. Writes the\n"
    "surface (-o, PCD or PLY; an\n"
    "indoor3d scenario names it as its map) and a picture of each floor next to it\n"
    "(<output>_floor_<z>.svg), and prints what was found and dropped.\n"
    "Exit codes: 0 written, 1 usage, 2 bad input (no walkable surface, not in metres).\n";

double ParseNumber(const std::string& text, const std::string& option) {
    const std::optional<double> value = ParseFiniteNumber(text);
    if (!value) throw InputError("", 0, option, "not a number: '" + text + "'");
    return *value;
}

std::vector<LiftShaft> ParseLifts(const std::string& text) {
    std::vector<LiftShaft> lifts;
    std::stringstream all(text);
    std::string one;
    while (std::getline(all, one, ';')) {
        std::vector<double> v;
        std::stringstream parts(one);
        std::string part;
        while (std::getline(parts, part, ',')) v.push_back(ParseNumber(part, "--lifts"));
        if (v.size() != 4 || !(v[2] > v[0] && v[3] > v[1])) {
            throw InputError("", 0, "--lifts",
                             "a shaft is x0,y0,x1,y1 with x1 > x0 and y1 > y0 (got '" + one + "')");
        }
        lifts.push_back({v[0], v[1], v[2], v[3]});
    }
    return lifts;
}

// The heights of the floors: the 0.25 m height bins holding at least 5 % of the surface points
// that are the fullest within 1.5 m.
std::vector<double> FloorLevels(const WalkableSurface& s) {
    constexpr double kBin = 0.25, kApart = 1.5, kShare = 0.05;
    std::map<long, std::size_t> bins;
    std::size_t total = 0;
    for (std::size_t n = 0; n < s.points.size(); ++n) {
        if (s.region[n] < 0) continue;
        ++bins[std::lround(s.points[n].z() / kBin)];
        ++total;
    }
    std::vector<std::pair<std::size_t, long>> full;
    for (const auto& [bin, count] : bins) {
        if (count >= kShare * total) full.emplace_back(count, bin);
    }
    std::sort(full.rbegin(), full.rend());
    std::vector<double> levels;
    for (const auto& [count, bin] : full) {
        const double z = bin * kBin;
        if (std::none_of(levels.begin(), levels.end(),
                         [&](double l) { return std::abs(l - z) < kApart; })) {
            levels.push_back(z);
        }
    }
    std::sort(levels.begin(), levels.end());
    return levels;
}

// A top view of the points nearest `level` (blue; lift points red) over the others (grey), one
// rectangle per run of cells along x.
std::string FloorPicture(const WalkableSurface& s, const std::vector<int>& level_of, int level,
                         double z, double resolution_m) {
    Eigen::Vector2d lo = s.points.front().head<2>(), hi = lo;
    for (const Eigen::Vector3d& p : s.points)
        lo = lo.cwiseMin(p.head<2>()), hi = hi.cwiseMax(p.head<2>());
    const double px = 4.0;  // pixels per cell
    const int nx = int(std::lround((hi.x() - lo.x()) / resolution_m)) + 1;
    const int ny = int(std::lround((hi.y() - lo.y()) / resolution_m)) + 1;
    // Per row, the cells of each kind: 0 other floors, 1 this floor, 2 lift.
    std::vector<std::vector<std::vector<bool>>> rows(3, std::vector<std::vector<bool>>(ny));
    double area = 0.0;
    for (std::size_t n = 0; n < s.points.size(); ++n) {
        const int i = int(std::lround((s.points[n].x() - lo.x()) / resolution_m));
        const int j = int(std::lround((s.points[n].y() - lo.y()) / resolution_m));
        const int kind = s.region[n] < 0 ? 2 : (level_of[n] == level ? 1 : 0);
        if (kind == 1) area += resolution_m * resolution_m;
        auto& row = rows[kind][ny - 1 - j];
        if (row.empty()) row.assign(nx, false);
        row[i] = true;
    }
    std::string svg = Format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\">\n"
        "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
        nx * px, ny * px + 24.0);
    const char* colours[3] = {"#d0d0d0", "#1f5fbf", "#c0392b"};
    for (int kind = 0; kind < 3; ++kind) {
        svg += std::string("<g fill=\"") + colours[kind] + "\">\n";
        for (int r = 0; r < ny; ++r) {
            const auto& row = rows[kind][r];
            for (int i = 0; i < int(row.size());) {
                if (!row[i]) {
                    ++i;
                    continue;
                }
                int end = i;
                while (end < int(row.size()) && row[end]) ++end;
                svg += Format("<rect x=\"%.0f\" y=\"%.0f\" width=\"%.0f\" height=\"%.0f\"/>\n",
                              i * px, 24.0 + r * px, (end - i) * px, px);
                i = end;
            }
        }
        svg += "</g>\n";
    }
    svg += Format(
        "<text x=\"4\" y=\"16\" font-family=\"sans-serif\" font-size=\"14\">floor at z %.2f m: "
        "%.1f m^2 walkable (blue), other floors grey, declared lifts red; %.2f m a cell, x east "
        "from %.1f m, y north from %.1f m</text>\n</svg>\n",
        z, area, resolution_m, lo.x(), lo.y());
    return svg;
}

int Extract(const std::string& input, const std::string& output, WalkableSurfaceConfig cfg,
            bool resolution_given) {
    CheckOutputPath(output, "-o");
    CheckOutputsAgainstInputs({{"-o", output}}, {{"the raw map", input}});
    const std::string ext = std::filesystem::path(output).extension().string();
    if (ext != ".pcd" && ext != ".ply") {
        throw InputError(output, 0, "-o", "the surface is written as .pcd or .ply");
    }
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    double voxel_m = 0.0;
    const std::vector<Eigen::Vector3d> cloud =
        pipeline::SurfaceIo().read_raw_points(input, &voxel_m);
    // An OctoMap is binned at its own voxel size unless --resolution says otherwise.
    if (voxel_m > 0.0 && !resolution_given) cfg.resolution_m = voxel_m;
    const auto t1 = Clock::now();
    if (auto problem = CheckCloudExtent(cloud)) throw InputError(input, 0, "", *problem);
    WalkableSurface s;
    try {
        s = ExtractWalkableSurface(cloud, cfg);
    } catch (const std::invalid_argument& e) {
        throw InputError(input, 0, "", e.what());
    }
    const auto t2 = Clock::now();
    if (s.area_m2 <= 0.0) {
        std::string found =
            "no occupied voxel has " + FormatFixed(cfg.headroom_m, 2) + " m of free space above it";
        if (!s.regions.empty()) {
            found = "the largest horizontal surface with " + FormatFixed(cfg.headroom_m, 2) +
                    " m free above it is " + FormatFixed(s.regions.front().area_m2, 2) +
                    " m^2 (at least " + FormatFixed(cfg.min_region_m2, 1) + " m^2 needed)";
        }
        throw InputError(input, 0, "", "no walkable surface: " + found);
    }
    if (ext == ".pcd") {
        pipeline::SurfaceIo().write_surface_points_pcd(output, s.points);
    } else {
        pipeline::SurfaceIo().write_surface_points_ply(output, s.points);
    }
    const std::vector<double> levels = FloorLevels(s);
    std::vector<int> level_of(s.points.size(), -1);
    for (std::size_t n = 0; n < s.points.size(); ++n) {
        if (s.region[n] < 0) continue;  // a lift's point belongs to no floor
        double best = 1e300;
        for (std::size_t l = 0; l < levels.size(); ++l) {
            const double d = std::abs(s.points[n].z() - levels[l]);
            if (d < best) best = d, level_of[n] = int(l);
        }
    }
    const std::string stem =
        (std::filesystem::path(output).parent_path() / std::filesystem::path(output).stem())
            .string();
    std::vector<std::string> pictures;
    for (std::size_t l = 0; l < levels.size(); ++l) {
        pictures.push_back(stem + "_floor_" + FormatFixed(levels[l], 2) + ".svg");
        WriteFileAtomically(pictures.back(),
                            FloorPicture(s, level_of, int(l), levels[l], cfg.resolution_m));
    }
    const auto t3 = Clock::now();
    auto seconds = [](Clock::time_point a, Clock::time_point b) {
        return std::chrono::duration<double>(b - a).count();
    };

    std::printf("map        %s: %zu points, %zu occupied voxels at %.2f m\n", input.c_str(),
                s.input_points, s.occupied_voxels, cfg.resolution_m);
    std::size_t kept = 0, small = 0;
    double small_max = 0.0;
    for (const WalkableRegion& r : s.regions) {
        if (r.kept) {
            ++kept;
        } else if (r.area_m2 < cfg.min_region_m2) {
            ++small;
            small_max = std::max(small_max, r.area_m2);
        }
    }
    std::printf(
        "walkable   %.1f m^2 in %zu region(s) from %zu standing places (%.1f m^2 of them closing "
        "gaps of the scan); %zu declared lift(s), %zu lift points\n",
        s.area_m2, kept, s.standing_places + s.filled_places,
        double(s.filled_places) * cfg.resolution_m * cfg.resolution_m, cfg.lifts.size(),
        s.lift_points);
    for (std::size_t l = 0; l < levels.size(); ++l) {
        const auto count = std::count(level_of.begin(), level_of.end(), int(l));
        std::printf("floor      z %.2f m: about %.1f m^2 (%s)\n", levels[l],
                    double(count) * cfg.resolution_m * cfg.resolution_m, pictures[l].c_str());
    }
    for (const WalkableRegion& r : s.regions) {
        if (r.kept || r.area_m2 < cfg.min_region_m2) continue;
        std::printf("dropped    %.1f m^2 at z %.2f..%.2f m: %s\n", r.area_m2, r.z_min_m, r.z_max_m,
                    r.why_dropped.c_str());
    }
    if (small > 0) {
        std::printf(
            "dropped    %zu region(s) smaller than %.1f m^2 (the largest %.2f m^2: "
            "furniture, shelves, noise)\n",
            small, cfg.min_region_m2, small_max);
    }
    std::printf("time       %.3f s (read %.3f, extract %.3f, write %.3f)\n", seconds(t0, t3),
                seconds(t0, t1), seconds(t1, t2), seconds(t2, t3));
    std::printf("wrote      %s (%zu points)\n", output.c_str(), s.points.size());
    if (!cfg.lifts.empty()) {
        std::string lifts;
        for (const LiftShaft& l : cfg.lifts) {
            lifts += Format("%s[%.15g, %.15g, %.15g, %.15g]", lifts.empty() ? "" : ", ", l.x0, l.y0,
                            l.x1, l.y1);
        }
        std::printf("scenario   map: [{path: %s, lifts: [%s]}]\n",
                    std::filesystem::path(output).filename().string().c_str(), lifts.c_str());
    }
    return kExitOk;
}

}  // namespace

int RunMapCommand(int argc, char** argv) {
    std::string output, resolution, headroom, step, min_area, lifts, fill_gap;
    std::vector<std::string> positional;
    OptionTable table;
    table.values = {
        {"-o", &output},           {"--output", &output},    {"--resolution", &resolution},
        {"--headroom", &headroom}, {"--step", &step},        {"--min-area", &min_area},
        {"--lifts", &lifts},       {"--fill-gap", &fill_gap}};
    std::string err;
    const bool ok = ParseOptions(
        argc, argv, 1, table,
        [&](const std::string& arg) {
            positional.push_back(arg);
            return positional.size() > 2 ? "unexpected argument '" + arg + "'" : std::string();
        },
        err);
    if (ok && (positional.size() != 2 || positional[0] != "extract")) {
        err = positional.empty() || positional[0] != "extract"
                  ? "expected 'extract' and a raw map"
                  : "expected a raw map after 'extract'";
    }
    if (ok && err.empty() && output.empty()) err = "-o walkable.pcd|.ply is required";
    if (!ok || !err.empty()) {
        if (err.empty()) {
            std::fputs(kMapUsage, stdout);
            return kExitOk;
        }
        std::fprintf(stderr, "driftcorr: %s\n\n%s", err.c_str(), kMapUsage);
        return kExitUsage;
    }
    return RunReportingErrors("driftcorr", [&] {
        WalkableSurfaceConfig cfg;
        if (!resolution.empty()) cfg.resolution_m = ParseNumber(resolution, "--resolution");
        if (!headroom.empty()) cfg.headroom_m = ParseNumber(headroom, "--headroom");
        if (!step.empty()) cfg.step_m = ParseNumber(step, "--step");
        if (!min_area.empty()) cfg.min_region_m2 = ParseNumber(min_area, "--min-area");
        if (!lifts.empty()) cfg.lifts = ParseLifts(lifts);
        if (!fill_gap.empty()) cfg.fill_gap_m = ParseNumber(fill_gap, "--fill-gap");
        if (std::string m = cfg.Validate(); !m.empty()) throw InputError("", 0, "", m);
        return Extract(positional[1], output, cfg, !resolution.empty());
    });
}

}  // namespace driftcorr::cli
